"""Small builders the rl layer's tests share (imported as `from rl_helpers import ...`): a batch of
transitions, a snapshot of an agent's weights, and the tiny experiment config."""
from __future__ import annotations

import torch
from tensordict import TensorDict

from cyberdog import config as C

OBS, ACT = 50, 12  # Table 3's observation and action sizes


def batch(n: int = 16, reward: float | None = None) -> TensorDict:
    """n transitions with random observations and actions in [-1, 1], each with its step energy (J)."""
    g = torch.Generator().manual_seed(1)
    r = torch.randn(n, 1, generator=g) if reward is None else torch.full((n, 1), reward)
    return TensorDict({"observation": torch.randn(n, OBS, generator=g),
                       "action": torch.rand(n, ACT, generator=g) * 2 - 1,
                       "next": {"observation": torch.randn(n, OBS, generator=g), "reward": r,
                                "done": torch.zeros(n, 1, dtype=torch.bool),
                                "terminated": torch.zeros(n, 1, dtype=torch.bool),
                                "energy_J": torch.rand(n, 1, generator=g) * 5}}, [n])


def snapshot(agent) -> dict[str, torch.Tensor]:
    """A copy of every weight of `agent`'s networks (actor, critics and their targets), by checkpoint name."""
    return {k: v.clone() for k, v in agent.network_state().items()}


def changed(before: dict, after: dict, prefix: str) -> bool:
    """Whether any weight whose name starts with `prefix` differs between two snapshots."""
    keys = [k for k in before if k.startswith(prefix)]
    assert keys, prefix
    return any(not torch.equal(before[k], after[k]) for k in keys)


def tiny_config(hidden=(8,)) -> C.ExperimentConfig:
    """configs/tiny.yaml with the given hidden layer sizes."""
    cfg = C.load(C.ExperimentConfig, "configs/tiny.yaml")
    return C.override(cfg, [f"agent.hidden_sizes={list(hidden)}"])
