"""Unit tests of the rl layer: the agent's updates, exploration, replay buffer, checkpoints and guards."""
from __future__ import annotations

import dataclasses

import pytest
import torch
from tensordict import TensorDict

from cyberdog import config as C
from cyberdog.rl.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from cyberdog.rl.collect import ProcessCollector
from cyberdog.rl.networks import Net, QCritic, TanhActor, critic_forward, make_actor, make_critics
from cyberdog.rl.replay import buffer_state, load_buffer_state, make_replay_buffer, sample_batches
from cyberdog.rl.run_state import Progress
from cyberdog.rl.td3 import TD3, NonFiniteError, UpdateSettings, metrics_to_float
from cyberdog.rl.trainer import Trainer
from rl_helpers import ACT, OBS, batch, changed, snapshot, tiny_config


@pytest.mark.parametrize("algorithm", ["td3", "ddpg"])
def test_update_schedule_changes_the_right_weights(algorithm):
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(algorithm=algorithm, hidden_sizes=(16, 16, 16), policy_delay=2), OBS, ACT)
    critic = "qvalue_network_params" if algorithm == "td3" else "value_network_params"
    b, settings = batch(), UpdateSettings.of(agent.cfg)
    for update in (1, 2, 3, 4):
        before = snapshot(agent)
        metrics = agent.update(b, settings)
        after = snapshot(agent)
        actor_turn = algorithm == "ddpg" or update % 2 == 0
        assert changed(before, after, critic), "critics learn at every update"
        assert changed(before, after, "actor_network_params") == actor_turn
        assert changed(before, after, "target_actor_network_params") == actor_turn
        assert changed(before, after, f"target_{critic}") == actor_turn
        assert metrics["critic_loss"] >= 0
    assert agent.updates == 4 and agent.actor_updates == (4 if algorithm == "ddpg" else 2)


def test_td3_has_twin_critics():
    agent = TD3(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    w = agent.critic.layers[0][0]
    assert w.shape[0] == 2 and not torch.equal(w[0], w[1])


@pytest.mark.parametrize("exploration", ["gaussian", "ou"])
def test_exploration_stays_in_bounds(exploration):
    agent = TD3(C.AgentConfig(exploration=exploration, exploration_sigma=2.0, hidden_sizes=(8,)), OBS, ACT)
    td = TensorDict({"observation": torch.randn(OBS), "is_init": torch.ones(1, dtype=torch.bool)}, [])
    a = agent.policy(td)["action"]
    assert a.shape == (ACT,) and a.abs().max() <= 1.0


def test_non_finite_loss_raises():
    agent = TD3(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    with pytest.raises(NonFiniteError, match="not finite"):
        agent.update(batch(reward=float("nan")), UpdateSettings.of(agent.cfg))


def test_replay_buffer_round_trip_keeps_order_and_cursor(tmp_path):
    rb = make_replay_buffer(10)
    data = batch(13)
    rb.extend(data[:7])
    rb.extend(data[7:])  # wrapped: the next transition goes to slot 3
    state = buffer_state(rb)
    assert (state["size"], state["cursor"]) == (10, 3)
    save_checkpoint({"replay": state}, tmp_path / "c.pt")
    rb2 = make_replay_buffer(10)
    load_buffer_state(rb2, load_checkpoint(tmp_path / "c.pt")["replay"])
    assert torch.equal(rb[:10]["observation"], rb2[:10]["observation"])
    rb.extend(data[:2])
    rb2.extend(data[:2])
    assert torch.equal(rb[:10]["observation"], rb2[:10]["observation"])
    part = make_replay_buffer(10)  # not yet full: the cursor is its size
    part.extend(data[:4])
    assert (buffer_state(part)["size"], buffer_state(part)["cursor"]) == (4, 4)
    with pytest.raises(ValueError, match="capacity"):
        load_buffer_state(make_replay_buffer(20), buffer_state(rb))
    old_format = buffer_state(rb)  # written before the step energy was stored
    del old_format["data"]["next"]["energy_J"]
    with pytest.raises(ValueError, match=r"lack \[\('next', 'energy_J'\)\]"):
        load_buffer_state(make_replay_buffer(10), old_format)


def test_config_validation_names_the_field():
    with pytest.raises(ValueError, match="AgentConfig.algorithm"):
        C.AgentConfig(algorithm="ppo")
    with pytest.raises(ValueError, match="TrainConfig.batch_size"):
        C.TrainConfig(batch_size=10, buffer_size=5)
    with pytest.raises(ValueError, match="StageConfig.reward"):
        C.StageConfig(reward="stage3")
    with pytest.raises(ValueError, match="StageConfig.reward"):  # an earlier file's preset name other than these two
        C.from_dict(C.StageConfig, {"reward": "stage3"})


def test_corrupt_checkpoint_raises_clear_error(tmp_path):
    trainer = Trainer(tiny_config(), tmp_path / "run", progress=False)
    path = trainer.save()
    trainer.close()  # releases the run folder
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(CheckpointError, match="corrupt"):
        Trainer(tiny_config(), tmp_path / "run", resume=True, progress=False)
    path.write_bytes(b"")
    with pytest.raises(CheckpointError, match="corrupt"):
        load_checkpoint(path)
    with pytest.raises(CheckpointError, match="does not exist"):
        load_checkpoint(tmp_path / "missing.pt")


def test_mismatched_checkpoint_raises_clear_error(tmp_path):
    trainer = Trainer(tiny_config((8,)), tmp_path / "small", progress=False)
    path = trainer.save()
    trainer.close()  # releases the run folder
    with pytest.raises(CheckpointError, match="does not match the configured networks"):
        Trainer(tiny_config((16,)), tmp_path / "big", init_from=path, progress=False)
    actor_file = tmp_path / "small_actor.pt"  # an actor file of other networks: one line naming the tensor
    torch.save({"actor": {k: v for k, v in load_checkpoint(path)["agent"]["loss"].items()
                          if k.startswith("actor_network_params.")}}, actor_file)
    with pytest.raises(CheckpointError, match="small_actor.pt: the actor's parameters do not match"):
        Trainer(tiny_config((16,)), tmp_path / "big2", init_from=actor_file, progress=False)
    small = {k[len("actor_network_params."):]: v for k, v in load_checkpoint(path)["agent"]["loss"].items()
             if k.startswith("actor_network_params.")}
    torch.save({"actor": small}, actor_file)
    with pytest.raises(CheckpointError, match="small_actor.pt: the actor's .* has shape"):
        Trainer(tiny_config((16,)), tmp_path / "big3", init_from=actor_file, progress=False)
    # resuming with an edited config.yaml is refused too
    C.save(tiny_config((16,)), tmp_path / "small" / "config.yaml")
    with pytest.raises(CheckpointError, match="another configuration"):
        Trainer(tiny_config((16,)), tmp_path / "small", resume=True, progress=False)


def test_non_finite_update_stops_training_with_a_diagnostic_checkpoint(tmp_path, monkeypatch):
    cfg = C.override(tiny_config(), ["train.init_random_frames=0", "train.stage1.max_env_steps=100"])
    trainer = Trainer(cfg, tmp_path, stages=(1,), progress=False)

    def broken_update(*args, **kwargs):
        raise NonFiniteError("Q-value is not finite (NaN or inf); training stopped")

    monkeypatch.setattr(trainer.agent, "update", broken_update)
    with pytest.raises(NonFiniteError, match="diagnostic checkpoint"):
        trainer.run()
    state = load_checkpoint(tmp_path / "diagnostic.pt")
    assert state["counters"]["env_steps"] == 50 and state["replay"]["size"] == 50


# ---- the functional forwards must give the plain modules' numbers ----------------------------------------
def test_networks_give_the_outputs_of_plain_modules():
    torch.manual_seed(0)
    actor = make_actor(OBS, ACT, (16, 16))
    b = batch(8)
    out = actor(b.select("observation"))
    assert torch.equal(out["action"], torch.tanh(actor.module.net(b["observation"])))
    net = TanhActor(OBS, ACT, (16, 16))  # the module rollouts load actors into
    net.load_state_dict(actor.module.state_dict())
    assert torch.equal(net(b["observation"]), out["action"])
    scale = torch.linspace(0.5, 2.0, OBS)
    for n in (1, 2):  # DDPG's one critic, TD3's two stacked: each Q_i(s, a) is a plain QCritic's
        critics = make_critics(OBS, ACT, (16, 16), scale, n)
        q = critic_forward(critics, b["observation"], out["action"])
        assert q.shape == (n, 8)
        for i in range(n):
            one = QCritic(OBS, ACT, (16, 16), scale)
            layers = critics.layers if n == 1 else [(w[i], bias[i]) for w, bias in critics.layers]
            with torch.no_grad():
                for linear, (w, bias) in zip(one.net[::2], layers):
                    linear.weight.copy_(w)
                    linear.bias.copy_(bias)
            assert torch.allclose(q[i], one(b["observation"], out["action"]).squeeze(-1), atol=1e-6)
    assert isinstance(Net.of(net), Net)


def test_sample_batches_draws_independent_batches_from_the_buffer():
    rb = make_replay_buffer(1000)
    data = batch(100)
    data["observation"][:, 0] = torch.arange(100.0)
    rb.extend(data)
    batches = list(sample_batches(rb, 70, 16))  # more than one chunk
    assert len(batches) == 70 and all(b.batch_size == torch.Size([16]) for b in batches)
    seen = torch.cat([b["observation"][:, 0] for b in batches])
    assert set(seen.long().tolist()) <= set(range(100)) and len(set(seen.tolist())) > 90
    assert not torch.equal(batches[0]["observation"], batches[1]["observation"])
    assert list(sample_batches(rb, 0, 16)) == []


def test_update_returns_tensors_and_metrics_average_them():
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    settings = UpdateSettings.of(agent.cfg)
    m1, m2 = agent.update(batch(), settings), agent.update(batch(), settings)
    assert all(isinstance(v, torch.Tensor) and v.dim() == 0 for v in m1.values())
    avg = metrics_to_float([m1, m2])
    assert avg["critic_loss"] == pytest.approx((float(m1["critic_loss"]) + float(m2["critic_loss"])) / 2)
    assert avg["q_max"] == pytest.approx((float(m1["q_max"]) + float(m2["q_max"])) / 2)
    assert torch.isnan(m1["actor_loss"]) and not torch.isnan(m2["actor_loss"])  # policy_delay 2: actor at update 2
    assert agent.last_actor_loss == pytest.approx(float(m2["actor_loss"]))


def test_optimizers_stay_fused_after_loading_an_unfused_state():
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    settings = UpdateSettings.of(agent.cfg)
    agent.update(batch(), settings)
    state = agent.state_dict()
    for opt in ("actor_optimizer", "critic_optimizer"):  # as written by the per-tensor Adam of older code
        for group in state[opt]["param_groups"]:
            group["fused"], group["foreach"] = None, None
    other = TD3(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    other.load_state_dict(state)
    assert all(g["fused"] for g in other.critic_optimizer.param_groups + other.actor_optimizer.param_groups)
    other.update(batch(), settings)  # and they still step


def test_collector_process_reports_worker_errors():
    cfg = C.ExperimentConfig()
    collector = ProcessCollector(None, C.STAGE1_REWARD, 0, cfg.agent, TD3(cfg.agent, OBS, ACT).policy, OBS,
                                 ACT, 10, 0)  # no env config: the worker fails while building the env
    try:
        with pytest.raises(RuntimeError, match="collector process failed"):
            next(collector)
    finally:
        collector.shutdown()


def test_action_penalty_pulls_the_actor_toward_zero():
    """action_l2 acts through the parameters the actor optimizer steps: with a strong penalty the actor's
    outputs shrink; without it the same updates leave them far larger (a random critic drives them out)."""
    b = batch(32)
    mean_abs = {}
    for l2 in (0.0, 100.0):
        torch.manual_seed(0)
        agent = TD3(C.AgentConfig(action_l2=l2, policy_delay=1, hidden_sizes=(32, 32)), 50, 12)
        for _ in range(30):
            agent.update(b, UpdateSettings.of(agent.cfg))
        with torch.no_grad():
            mean_abs[l2] = float(agent.actor(b.select("observation").clone())["action"].abs().mean())
    assert mean_abs[100.0] < 0.01 < 0.1 < mean_abs[0.0]


def test_action_penalty_must_be_non_negative():
    with pytest.raises(ValueError, match="action_l2"):
        C.AgentConfig(action_l2=-1.0)


def test_a_stage_can_set_its_own_action_penalty(tmp_path):
    """StageConfig.action_l2 and actor_lr replace the agent's for that stage only (None keeps the agent's), the
    learning rate in the actor's optimizer from the stage's first update on; fresh_actor_optimizer starts the stage
    with new Adam moments."""
    cfg = C.override(tiny_config(), ["agent.action_l2=0.5", "train.stage2.action_l2=0.0", "train.init_random_frames=0",
                               "train.stage1.max_env_steps=100", "train.stage2.max_env_steps=100",
                               "agent.actor_lr=0.001", "train.stage2.actor_lr=0.0002",
                               "train.stage2.fresh_actor_optimizer=true"])
    trainer = Trainer(cfg, tmp_path, progress=False)
    seen = []
    update = trainer.agent.update

    def recording_update(batch, settings, prior_weight):
        opt = trainer.agent.actor_optimizer
        seen.append((trainer.progress.stage, settings.action_l2, opt.param_groups[0]["lr"],
                     max((int(st["step"]) for st in opt.state.values()), default=0)))
        return update(batch, settings, prior_weight)

    trainer.agent.update = recording_update
    trainer.run()
    trainer.logger.close()
    assert {(l2, lr) for stage, l2, lr, _ in seen if stage == 1} == {(0.5, 0.001)}
    assert {(l2, lr) for stage, l2, lr, _ in seen if stage == 2} == {(0.0, 0.0002)}
    first2 = next(i for i, row in enumerate(seen) if row[0] == 2)
    assert seen[first2 - 1][3] > 0 and seen[first2][3] == 0, "stage 2 starts with fresh Adam moments"
    with pytest.raises(ValueError, match="StageConfig.action_l2"):
        C.StageConfig(action_l2=-0.1)
    with pytest.raises(ValueError, match="StageConfig.actor_lr"):
        C.StageConfig(actor_lr=0.0)


def test_update_without_actor_trains_the_critics_only():
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16, 16, 16), policy_delay=1), OBS, ACT)
    before = snapshot(agent)
    agent.update(batch(), UpdateSettings.of(agent.cfg, C.StageConfig(critic_warmup_updates=1)))
    after = snapshot(agent)
    assert changed(before, after, "qvalue_network_params")
    assert not changed(before, after, "actor_network_params")
    assert not changed(before, after, "target_qvalue_network_params")
    assert agent.updates == 1 and agent.actor_updates == 0


def test_a_stage_resolves_its_update_settings_from_the_agent_and_its_own():
    """A stage's own value replaces the agent's where it sets one; its warm-up counts from the agent's updates at
    its start; DDPG's settings have no delay and no target smoothing; the settings cannot change afterwards."""
    agent = C.AgentConfig(actor_lr=1e-3, action_l2=0.5, trot_imitation=0.2, policy_delay=3)
    stage = C.StageConfig(actor_lr=2e-4, action_l2=0.0, critic_warmup_updates=7, actor_anchor=0.4)
    s = UpdateSettings.of(agent, stage, updates_done=100)
    assert (s.actor_lr, s.action_l2, s.trot_imitation, s.actor_anchor) == (2e-4, 0.0, 0.2, 0.4)
    assert (s.critic_warmup_end, s.policy_delay, s.target_smoothing) == (107, 3, True)
    ddpg = UpdateSettings.of(dataclasses.replace(agent, algorithm="ddpg"))
    assert (ddpg.actor_lr, ddpg.action_l2, ddpg.policy_delay, ddpg.target_smoothing, ddpg.critic_warmup_end) == (
        1e-3, 0.5, 1, False, 0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.actor_lr = 1.0


def test_the_warm_up_counts_from_the_stage_start_and_the_learning_rate_is_set_as_it_begins():
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(8,), policy_delay=1, actor_lr=1e-3), OBS, ACT)
    for _ in range(3):
        agent.update(batch(), UpdateSettings.of(agent.cfg))
    s = UpdateSettings.of(agent.cfg, C.StageConfig(critic_warmup_updates=2, actor_lr=5e-5), updates_done=3)
    agent.begin_stage(s)
    assert [g["lr"] for g in agent.actor_optimizer.param_groups] == [5e-5]
    actor_updates = []
    for _ in range(3):
        agent.update(batch(), s)
        actor_updates.append(agent.actor_updates)
    assert actor_updates == [3, 3, 4]  # the stage's first two updates train the critics only


def test_the_trainers_counters_are_saved_as_a_plain_dict(tmp_path):
    trainer = Trainer(tiny_config(), tmp_path / "run", progress=False)
    trainer.progress.env_steps = 7
    path = trainer.save()
    trainer.close()
    counters = load_checkpoint(path)["counters"]
    assert counters == {**dataclasses.asdict(Progress(stage=1)), "env_steps": 7, "last_checkpoint": 7}
    without_credit = {k: v for k, v in counters.items() if k != "update_credit"}  # as a checkpoint may lack it
    assert Progress.from_dict(without_credit) == Progress(stage=1, env_steps=7, last_checkpoint=7)


def without_critic_gradient(agent: TD3) -> None:
    """Critics whose output layer is zero (and that barely learn: critic_lr 1e-12) give the actor no gradient."""
    with torch.no_grad():
        for w in agent.critic.layers[-1]:
            w.zero_()


def test_action_smoothness_pulls_consecutive_actions_together():
    """CAPS's temporal term: with only it in the actor loss (critic gradient removed), μ(s') − μ(s) shrinks."""
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16, 16, 16), policy_delay=1, action_smoothness=10.0,
                              actor_lr=1e-2, critic_lr=1e-12), OBS, ACT)
    without_critic_gradient(agent)  # the penalty alone drives the actor
    b = batch(64)
    gap = lambda: (agent.actor(b["next"].select("observation").clone())["action"]  # noqa: E731
                   - agent.actor(b.select("observation").clone())["action"]).pow(2).mean().item()
    before = gap()
    for _ in range(50):
        agent.update(b, UpdateSettings.of(agent.cfg))
    assert gap() < 0.2 * before
    with pytest.raises(ValueError, match="action_smoothness"):
        C.AgentConfig(action_smoothness=-1.0)


def test_spatial_smoothness_makes_the_policy_react_less_to_the_state():
    """CAPS's spatial term: with only it in the actor loss (critic gradient removed), μ moves less when the
    observation moves by spatial_smoothness_sigma of its scale."""
    def sensitivity(agent, b):
        obs = b["observation"]
        torch.manual_seed(1)
        near = obs + 0.05 * torch.randn_like(obs)
        with torch.no_grad():
            act = lambda o: agent.actor(b.select("observation").clone().set("observation", o))["action"]  # noqa: E731
            return (act(near) - act(obs)).pow(2).mean().item()

    b = batch(64)
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16, 16, 16), policy_delay=1, action_spatial_smoothness=10.0,
                              spatial_smoothness_sigma=0.05, actor_lr=1e-2, critic_lr=1e-12), OBS, ACT)
    without_critic_gradient(agent)  # the penalty alone drives the actor
    before = sensitivity(agent, b)
    for _ in range(50):
        agent.update(b, UpdateSettings.of(agent.cfg))
    assert sensitivity(agent, b) < 0.2 * before
    with pytest.raises(ValueError, match="action_spatial_smoothness"):
        C.AgentConfig(action_spatial_smoothness=-1.0)
    with pytest.raises(ValueError, match="spatial_smoothness_sigma"):
        C.AgentConfig(spatial_smoothness_sigma=-0.1)
