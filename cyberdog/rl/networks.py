"""Actor and critic networks (paper Section 3: three fully connected hidden layers of 128 ReLU units).

The actor maps the observation to an action in [−1, 1]^12 (tanh output, scaled later by the environment's
`action_scale`); the critic maps (observation, action) to one Q-value. Both are `TensorDictModule`s reading
the keys "observation" (and "action") so that TorchRL's losses, collectors and exploration modules use them.
"""
from __future__ import annotations

from typing import Sequence

import torch
from tensordict.nn import TensorDictModule
from torch import nn
from torchrl.modules import ValueOperator


def mlp(in_features: int, out_features: int, hidden_sizes: Sequence[int]) -> nn.Sequential:
    """Linear → ReLU for each hidden layer, then a linear output layer."""
    layers: list[nn.Module] = []
    width = in_features
    for h in hidden_sizes:
        layers += [nn.Linear(width, int(h)), nn.ReLU()]
        width = int(h)
    layers.append(nn.Linear(width, out_features))
    return nn.Sequential(*layers)


class TanhActor(nn.Module):
    """Deterministic policy μ(s) = tanh(MLP(s)), bounded to [−1, 1]."""

    def __init__(self, observation_size: int, action_size: int, hidden_sizes: Sequence[int]):
        super().__init__()
        self.net = mlp(observation_size, action_size, hidden_sizes)

    def forward(self, observation: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.net(observation))


class QCritic(nn.Module):
    """State-action value Q(s, a) = MLP([s, a])."""

    def __init__(self, observation_size: int, action_size: int, hidden_sizes: Sequence[int]):
        super().__init__()
        self.net = mlp(observation_size + action_size, 1, hidden_sizes)

    def forward(self, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        return self.net(torch.cat([observation, action], dim=-1))


def make_actor(observation_size: int, action_size: int, hidden_sizes: Sequence[int]) -> TensorDictModule:
    return TensorDictModule(TanhActor(observation_size, action_size, hidden_sizes),
                            in_keys=["observation"], out_keys=["action"])


def make_critic(observation_size: int, action_size: int, hidden_sizes: Sequence[int]) -> ValueOperator:
    return ValueOperator(QCritic(observation_size, action_size, hidden_sizes),
                         in_keys=["observation", "action"], out_keys=["state_action_value"])
