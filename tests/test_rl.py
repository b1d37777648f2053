"""Unit tests of the rl layer: agent updates, exploration, replay buffer, checkpoints and guards."""
from __future__ import annotations

import pytest
import torch
from tensordict import TensorDict

from cyberdog import config as C
from cyberdog.rl.agent import Agent, NonFiniteError
from cyberdog.rl.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from cyberdog.rl.replay import buffer_state, load_buffer_state, make_replay_buffer
from cyberdog.rl.trainer import Trainer

OBS, ACT = 50, 12


def batch(n: int = 16, reward: float | None = None) -> TensorDict:
    g = torch.Generator().manual_seed(1)
    r = torch.randn(n, 1, generator=g) if reward is None else torch.full((n, 1), reward)
    return TensorDict({"observation": torch.randn(n, OBS, generator=g),
                       "action": torch.rand(n, ACT, generator=g) * 2 - 1,
                       "next": {"observation": torch.randn(n, OBS, generator=g), "reward": r,
                                "done": torch.zeros(n, 1, dtype=torch.bool),
                                "terminated": torch.zeros(n, 1, dtype=torch.bool)}}, [n])


def snapshot(agent: Agent) -> dict[str, torch.Tensor]:
    return {k: v.detach().clone() for k, v in agent.loss.state_dict().items()}


def changed(before: dict, after: dict, prefix: str) -> bool:
    keys = [k for k in before if k.startswith(prefix)]
    assert keys, prefix
    return any(not torch.equal(before[k], after[k]) for k in keys)


@pytest.mark.parametrize("algorithm", ["td3", "ddpg"])
def test_update_schedule_changes_the_right_weights(algorithm):
    torch.manual_seed(0)
    agent = Agent(C.AgentConfig(algorithm=algorithm, hidden_sizes=(16, 16, 16), policy_delay=2), OBS, ACT)
    critic = "qvalue_network_params" if algorithm == "td3" else "value_network_params"
    b = batch()
    for update in (1, 2, 3, 4):
        before = snapshot(agent)
        metrics = agent.update(b)
        after = snapshot(agent)
        actor_turn = algorithm == "ddpg" or update % 2 == 0
        assert changed(before, after, critic), "critics learn at every update"
        assert changed(before, after, "actor_network_params") == actor_turn
        assert changed(before, after, "target_actor_network_params") == actor_turn
        assert changed(before, after, f"target_{critic}") == actor_turn
        assert metrics["critic_loss"] >= 0
    assert agent.updates == 4 and agent.actor_updates == (4 if algorithm == "ddpg" else 2)


def test_td3_has_twin_critics():
    agent = Agent(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    w = agent.loss.qvalue_network_params["module", "net", "0", "weight"]
    assert w.shape[0] == 2 and not torch.equal(w[0], w[1])


@pytest.mark.parametrize("exploration", ["gaussian", "ou"])
def test_exploration_stays_in_bounds(exploration):
    agent = Agent(C.AgentConfig(exploration=exploration, exploration_sigma=2.0, hidden_sizes=(8,)), OBS, ACT)
    td = TensorDict({"observation": torch.randn(OBS), "is_init": torch.ones(1, dtype=torch.bool)}, [])
    a = agent.policy(td)["action"]
    assert a.shape == (ACT,) and a.abs().max() <= 1.0


def test_non_finite_loss_raises():
    agent = Agent(C.AgentConfig(hidden_sizes=(8,)), OBS, ACT)
    with pytest.raises(NonFiniteError, match="not finite"):
        agent.update(batch(reward=float("nan")))


def test_replay_buffer_round_trip_keeps_order_and_cursor(tmp_path):
    rb = make_replay_buffer(10, 4)
    data = batch(13)
    rb.extend(data[:7])
    rb.extend(data[7:])
    save_checkpoint({"replay": buffer_state(rb)}, tmp_path / "c.pt")
    rb2 = make_replay_buffer(10, 4)
    load_buffer_state(rb2, load_checkpoint(tmp_path / "c.pt")["replay"])
    rb.extend(data[:2])
    rb2.extend(data[:2])
    assert torch.equal(rb._storage[:10]["observation"], rb2._storage[:10]["observation"])
    with pytest.raises(ValueError, match="capacity"):
        load_buffer_state(make_replay_buffer(20, 4), buffer_state(rb))


def test_config_validation_names_the_field():
    with pytest.raises(ValueError, match="AgentConfig.algorithm"):
        C.AgentConfig(algorithm="ppo")
    with pytest.raises(ValueError, match="TrainConfig.batch_size"):
        C.TrainConfig(batch_size=10, buffer_size=5)
    with pytest.raises(ValueError, match="StageConfig.reward"):
        C.StageConfig(reward="stage3")


def _tiny(hidden=(8,)) -> C.ExperimentConfig:
    cfg = C.load(C.ExperimentConfig, "configs/tiny.yaml")
    return C.override(cfg, [f"agent.hidden_sizes={list(hidden)}"])


def test_corrupt_checkpoint_raises_clear_error(tmp_path):
    trainer = Trainer(_tiny(), tmp_path / "run", progress=False)
    path = trainer.save()
    trainer.logger.close()
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(CheckpointError, match="corrupt"):
        Trainer(_tiny(), tmp_path / "run", resume=True, progress=False)
    path.write_bytes(b"")
    with pytest.raises(CheckpointError, match="corrupt"):
        load_checkpoint(path)
    with pytest.raises(CheckpointError, match="does not exist"):
        load_checkpoint(tmp_path / "missing.pt")


def test_mismatched_checkpoint_raises_clear_error(tmp_path):
    trainer = Trainer(_tiny((8,)), tmp_path / "small", progress=False)
    path = trainer.save()
    trainer.logger.close()
    with pytest.raises(CheckpointError, match="does not match the configured networks"):
        Trainer(_tiny((16,)), tmp_path / "big", init_from=path, progress=False)
    # resuming with an edited config.yaml is refused too
    C.save(_tiny((16,)), tmp_path / "small" / "config.yaml")
    with pytest.raises(CheckpointError, match="another configuration"):
        Trainer(_tiny((16,)), tmp_path / "small", resume=True, progress=False)


def test_non_finite_update_stops_training_with_a_diagnostic_checkpoint(tmp_path, monkeypatch):
    cfg = C.override(_tiny(), ["train.init_random_frames=0", "train.stage1.max_env_steps=100"])
    trainer = Trainer(cfg, tmp_path, stages=(1,), progress=False)

    def broken_update(batch):
        raise NonFiniteError("Q-value is not finite (NaN or inf); training stopped")

    monkeypatch.setattr(trainer.agent, "update", broken_update)
    with pytest.raises(NonFiniteError, match="diagnostic checkpoint"):
        trainer.run()
    state = load_checkpoint(tmp_path / "diagnostic.pt")
    assert state["counters"]["env_steps"] == 50 and state["replay"]["size"] == 50
