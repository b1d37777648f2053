"""The hand-written TD3 and DDPG update (`cyberdog.rl.td3.TD3.update`) against TorchRL's `TD3Loss` and `DDPGLoss`,
the oracles: losses and gradients on fixed batches (to 1e-5), whole updates with Adam and soft target updates, and
the soft update bit for bit. The oracles are built here, over copies of the agent's networks."""
import dataclasses

import pytest
import torch
from tensordict import TensorDict
from torchrl.data import Bounded
from torchrl.modules import ValueOperator
from torchrl.objectives import DDPGLoss, SoftUpdate, TD3Loss

from cyberdog import config as C
from cyberdog.rl.networks import QCritic, make_actor
from cyberdog.rl.td3 import TD3, UpdateSettings, soft_update

OBS, ACT, B = 62, 12, 64


def fixed_batch(seed: int = 0) -> TensorDict:
    g = torch.Generator().manual_seed(seed)
    terminated = torch.zeros(B, 1, dtype=torch.bool)
    terminated[::7] = True  # some transitions end the episode: no bootstrap there
    return TensorDict({
        "observation": torch.randn(B, OBS, generator=g), "action": torch.rand(B, ACT, generator=g) * 2 - 1,
        "next": {"observation": torch.randn(B, OBS, generator=g), "reward": torch.randn(B, 1, generator=g),
                 "terminated": terminated, "done": terminated.clone()}}, batch_size=[B])


def make_agent(algorithm: str = "td3", **changes) -> TD3:
    torch.manual_seed(0)
    cfg = dataclasses.replace(C.AgentConfig(hidden_sizes=(32, 32, 32), algorithm=algorithm), **changes)
    agent = TD3(cfg, OBS, ACT, observation_scale=torch.linspace(0.5, 3.0, OBS))
    with torch.no_grad():  # move the targets away from the online networks, as after some training
        for net in (agent.target_actor, agent.target_critic):
            for p in net.parameters():
                p.add_(0.05 * torch.randn_like(p))
        agent.actor.module.net[-1].weight.mul_(100)  # an actor that acts, not the near-zero initial one
    return agent


def oracle(agent: TD3) -> tuple:
    """TorchRL's loss for the agent's algorithm, holding copies of the agent's networks and targets, and its
    `SoftUpdate` (made first: it starts by copying each network onto its target)."""
    cfg = agent.cfg
    actor = make_actor(OBS, ACT, cfg.hidden_sizes)
    critic = ValueOperator(QCritic(OBS, ACT, cfg.hidden_sizes), in_keys=["observation", "action"])
    if agent.twin:
        loss = TD3Loss(actor, critic, action_spec=Bounded(-1.0, 1.0, shape=(ACT,)), num_qvalue_nets=2,
                       policy_noise=cfg.policy_noise, noise_clip=cfg.noise_clip, loss_function="l2",
                       delay_actor=True, delay_qvalue=True)
    else:
        loss = DDPGLoss(actor, critic, loss_function="l2", delay_actor=True, delay_value=True)
    loss.make_value_estimator(gamma=cfg.gamma)
    soft = SoftUpdate(loss, tau=cfg.tau)
    state = loss.state_dict()
    assert set(agent.network_state()) <= set(state)  # the agent's names are the loss's
    state.update({k: v.clone() for k, v in agent.network_state().items()})
    loss.load_state_dict(state)
    return loss, soft


def grads(tensors) -> list[torch.Tensor]:
    trainable = [t for t in tensors if t.requires_grad]
    assert trainable and all(t.grad is not None for t in trainable)
    return [t.grad.clone() for t in trainable]


def critic_tensors(loss) -> list[torch.Tensor]:
    params = loss.qvalue_network_params if isinstance(loss, TD3Loss) else loss.value_network_params
    return [params.flatten_keys()[k] for k in sorted(params.flatten_keys().keys()) if "scale" not in k]


def actor_tensors(loss) -> list[torch.Tensor]:
    params = loss.actor_network_params.flatten_keys()
    return [params[k] for k in sorted(params.keys()) if "scale" not in k]


def ours(net_named: dict) -> list[torch.Tensor]:
    return [net_named[k] for k in sorted(net_named) if "scale" not in k]  # the oracle's order


@pytest.mark.parametrize("algorithm", ["td3", "ddpg"])
def test_critic_loss_and_gradients_equal_torchrl(algorithm):
    """One update whose actor waits (a critic warm-up of one update): its critic loss, Q-values and the critics'
    gradients (left on the tensors by its step) are the oracle's."""
    agent = make_agent(algorithm)
    (ref_loss, _), batch = oracle(agent), fixed_batch()
    torch.manual_seed(1)  # the target-policy noise is drawn first in both
    ref, meta = (ref_loss.value_loss if agent.twin else ref_loss.loss_value)(batch.clone())
    ref.backward()
    torch.manual_seed(1)
    critics_only = UpdateSettings.of(agent.cfg, C.StageConfig(critic_warmup_updates=1))
    metrics = agent.update(batch.clone(), critics_only)
    assert agent.actor_updates == 0
    assert metrics["critic_loss"].item() == pytest.approx(ref.item(), rel=1e-5)
    for name in ("mean", "max"):
        assert metrics[f"q_{name}"].item() == pytest.approx(getattr(meta["pred_value"], name)().item(), rel=1e-5)
    mine, theirs = grads(ours(agent.critic.named())), grads(critic_tensors(ref_loss))
    assert len(mine) == len(theirs) > 0  # every trainable tensor compared, none left out by zip
    for g, g_ref in zip(mine, theirs):
        assert torch.allclose(g, g_ref, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("algorithm", ["td3", "ddpg"])
def test_actor_loss_and_gradients_equal_torchrl(algorithm):
    agent = make_agent(algorithm, action_l2=0.0)
    (ref_loss, _), batch = oracle(agent), fixed_batch(3)
    ref, _ = (ref_loss.actor_loss if agent.twin else ref_loss.loss_actor)(batch.clone())
    ref.backward()
    got = agent.actor_loss(batch.clone(), UpdateSettings.of(agent.cfg))
    got.backward()
    assert got.item() == pytest.approx(ref.item(), rel=1e-5)
    mine, theirs = grads(ours(agent.actor_net.named())), grads(actor_tensors(ref_loss))
    assert len(mine) == len(theirs) > 0  # every trainable tensor compared, none left out by zip
    for g, g_ref in zip(mine, theirs):
        assert torch.allclose(g, g_ref, rtol=1e-5, atol=1e-6)
    assert all(t.grad is None or not t.grad.any() for t in agent.critic.parameters())  # the critics stay put


def test_whole_updates_track_torchrl():
    """Ten TD3 updates with an action penalty (two actor updates every second one, soft target updates) from the
    same start on the same batches and noise, ours against TorchRL's loss, Adam and SoftUpdate: the networks
    stay equal up to float rounding."""
    agent = make_agent(action_l2=0.3)
    settings = UpdateSettings.of(agent.cfg)
    ref_loss, soft = oracle(agent)
    critic_opt = torch.optim.Adam(list(ref_loss.qvalue_network_params.flatten_keys().values()), agent.cfg.critic_lr)
    actor_opt = torch.optim.Adam(list(ref_loss.actor_network_params.flatten_keys().values()), agent.cfg.actor_lr)
    for k in range(10):
        batch = fixed_batch(10 + k)
        torch.manual_seed(100 + k)
        agent.update(batch.clone(), settings)
        torch.manual_seed(100 + k)
        critic_opt.zero_grad()
        ref_loss.value_loss(batch.clone())[0].backward()
        critic_opt.step()
        if (k + 1) % agent.cfg.policy_delay == 0:
            actor_opt.zero_grad()
            loss, _ = ref_loss.actor_loss(batch.clone())
            with ref_loss.actor_network_params.to_module(ref_loss.actor_network):
                now = ref_loss.actor_network(batch.select("observation").clone())["action"]
            (loss + 0.3 * now.pow(2).mean()).backward()
            actor_opt.step()
            soft.step()
    assert agent.actor_updates == 5
    ref = ref_loss.state_dict()
    for name, t in agent.network_state().items():
        assert torch.allclose(t, ref[name], rtol=1e-4, atol=1e-5), name


def test_soft_update_is_torchrl_soft_update_bit_for_bit():
    agent = make_agent()
    ref_loss, soft = oracle(agent)
    for _ in range(2):
        soft.step()
        soft_update(agent.target_actor, agent.actor_net, agent.cfg.tau)
        soft_update(agent.target_critic, agent.critic, agent.cfg.tau)
    ref = ref_loss.state_dict()
    targets = [k for k in agent.network_state() if k.startswith("target_")]
    assert targets and all(torch.equal(agent.network_state()[k], ref[k]) for k in targets)


def test_twin_critics_start_as_torchrl_draws_them():
    """The same seed gives the networks TorchRL's TD3Loss gave (the twin critics redrawn within each tensor's
    range), so that a seed trains the agent it trained before."""
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16,)), OBS, ACT)
    torch.manual_seed(0)
    actor = make_actor(OBS, ACT, (16,))
    critic = ValueOperator(QCritic(OBS, ACT, (16,)), in_keys=["observation", "action"])
    loss = TD3Loss(actor, critic, action_spec=Bounded(-1.0, 1.0, shape=(ACT,)), num_qvalue_nets=2)
    ref = loss.state_dict()
    assert all(torch.equal(t, ref[k]) for k, t in agent.network_state().items() if "scale" not in k)
