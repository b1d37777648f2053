"""The direct TD3 losses (cyberdog.rl.fast_td3) equal TorchRL's TD3Loss, losses and gradients, on fixed batches."""
import dataclasses

import pytest
import torch
from tensordict import TensorDict

from cyberdog import config as C
from cyberdog.rl.agent import Agent

OBS, ACT, B = 62, 12, 64


def fixed_batch(seed: int = 0) -> TensorDict:
    g = torch.Generator().manual_seed(seed)
    terminated = torch.zeros(B, 1, dtype=torch.bool)
    terminated[::7] = True  # some transitions end the episode: no bootstrap there
    return TensorDict({
        "observation": torch.randn(B, OBS, generator=g), "action": torch.rand(B, ACT, generator=g) * 2 - 1,
        "next": {"observation": torch.randn(B, OBS, generator=g), "reward": torch.randn(B, 1, generator=g),
                 "terminated": terminated, "done": terminated.clone()}}, batch_size=[B])


def make_agent(fast: bool, **changes) -> Agent:
    torch.manual_seed(0)
    cfg = dataclasses.replace(C.AgentConfig(hidden_sizes=(32, 32, 32)), fast_update=fast, **changes)
    agent = Agent(cfg, OBS, ACT)
    with torch.no_grad():  # move the targets away from the online networks, as after some training
        for p in agent.loss.target_qvalue_network_params.flatten_keys().values():
            p.add_(0.05 * torch.randn_like(p))
        for p in agent.loss.target_actor_network_params.flatten_keys().values():
            p.add_(0.05 * torch.randn_like(p))
        agent.actor.module.net[-1].weight.mul_(100)  # an actor that acts, not the near-zero initial one
    return agent


def grads(params) -> list[torch.Tensor]:
    """The gradients of the trainable tensors (the observation scale is a buffer)."""
    trainable = [p for p in params if p.requires_grad]
    assert trainable and all(p.grad is not None for p in trainable)
    return [p.grad.clone() for p in trainable]


def test_critic_loss_and_gradients_equal_torchrl():
    agent = make_agent(fast=True)
    batch = fixed_batch()
    torch.manual_seed(1)  # the target-policy noise is drawn first in both
    ref, meta = agent.loss.value_loss(batch.clone())
    agent.critic_optimizer.zero_grad(set_to_none=True)
    ref.backward()
    ref_grads = grads(agent.critic_params)
    torch.manual_seed(1)
    fast, q = agent._fast.value_loss(batch.clone())
    agent.critic_optimizer.zero_grad(set_to_none=True)
    fast.backward()
    assert fast.item() == pytest.approx(ref.item(), rel=1e-5)
    assert torch.allclose(q, meta["pred_value"], rtol=1e-5, atol=1e-6)
    for g_fast, g_ref in zip(grads(agent.critic_params), ref_grads):
        assert torch.allclose(g_fast, g_ref, rtol=1e-5, atol=1e-6)


def test_actor_loss_and_gradients_equal_torchrl():
    agent = make_agent(fast=True)
    batch = fixed_batch(3)
    ref, _ = agent.loss.actor_loss(batch.clone())
    agent.actor_optimizer.zero_grad(set_to_none=True)
    ref.backward()
    ref_grads = grads(agent.actor_params)
    obs = batch["observation"]
    fast = agent._fast.actor_loss(obs, agent._fast.actor_actions(obs))
    agent.actor_optimizer.zero_grad(set_to_none=True)
    fast.backward()
    assert fast.item() == pytest.approx(ref.item(), rel=1e-5)
    for g_fast, g_ref in zip(grads(agent.actor_params), ref_grads):
        assert torch.allclose(g_fast, g_ref, rtol=1e-5, atol=1e-6)
    assert all(p.grad is None or not p.grad.any() for p in agent.critic_params)  # the critics stay put


def test_whole_updates_with_penalties_track_torchrl():
    """Ten TD3 updates (two actor updates with action_l2 and the smoothness term, soft target updates) from
    the same start on the same batches and noise: the parameters stay equal up to float rounding."""
    agents = [make_agent(fast=f, action_l2=0.3, action_smoothness=1.0) for f in (True, False)]
    for k in range(10):
        batch = fixed_batch(10 + k)
        for agent in agents:
            torch.manual_seed(100 + k)
            agent.update(batch.clone())
    fast, ref = agents
    assert fast.actor_updates == ref.actor_updates == 5
    for name in ("qvalue_network_params", "actor_network_params", "target_actor_network_params"):
        for a, b in zip(getattr(fast.loss, name).flatten_keys().values(),
                        getattr(ref.loss, name).flatten_keys().values()):
            assert torch.allclose(a, b, rtol=1e-4, atol=1e-5), name


def test_fast_update_is_td3_only():
    agent = Agent(dataclasses.replace(C.AgentConfig(hidden_sizes=(16,)), algorithm="ddpg"), OBS, ACT)
    assert agent._fast is None  # DDPG keeps TorchRL's DDPGLoss
    agent.update(fixed_batch())
