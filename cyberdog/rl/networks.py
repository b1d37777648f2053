"""Actor and critic networks (paper Section 3: three fully connected hidden layers of 128 ReLU units).

The actor maps the observation to an action in [−1, 1]^12 (tanh output, scaled later by the environment's
`action_scale`); the critic maps (observation, action) to one Q-value. Both are `TensorDictModule`s reading
the keys "observation" (and "action") so that TorchRL's losses, collectors and exploration modules use them.

Inputs are divided by a fixed typical magnitude per observation entry (from the environment's layout), so
that joint speeds of 10 rad/s and body heights of 0.3 m reach the first layer on the same scale. The actor's
output layer starts near zero (uniform ±3e-3, as in Lillicrap et al. 2016, DDPG): in residual mode the
untrained policy then adds almost nothing to the trot controller, and the first episodes walk instead of
falling at once.
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


FINAL_LAYER_INIT = 3e-3  # actor output layer weights and biases start in ±this (DDPG paper)


def _scale(observation_size: int, observation_scale) -> torch.Tensor:
    if observation_scale is None:
        return torch.ones(observation_size)
    scale = torch.as_tensor(observation_scale, dtype=torch.float32).reshape(-1)
    if scale.numel() != observation_size or not torch.all(scale > 0):
        raise ValueError(f"observation_scale must have {observation_size} positive entries, got {scale.numel()}")
    return scale


class TanhActor(nn.Module):
    """Deterministic policy μ(s) = tanh(MLP(s / scale)), bounded to [−1, 1]."""

    def __init__(self, observation_size: int, action_size: int, hidden_sizes: Sequence[int],
                 observation_scale=None):
        super().__init__()
        self.net = mlp(observation_size, action_size, hidden_sizes)
        nn.init.uniform_(self.net[-1].weight, -FINAL_LAYER_INIT, FINAL_LAYER_INIT)
        nn.init.uniform_(self.net[-1].bias, -FINAL_LAYER_INIT, FINAL_LAYER_INIT)
        self.register_buffer("observation_scale", _scale(observation_size, observation_scale))

    def forward(self, observation: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.net(observation / self.observation_scale))


class QCritic(nn.Module):
    """State-action value Q(s, a) = MLP([s, a])."""

    def __init__(self, observation_size: int, action_size: int, hidden_sizes: Sequence[int],
                 observation_scale=None):
        super().__init__()
        self.net = mlp(observation_size + action_size, 1, hidden_sizes)
        self.register_buffer("observation_scale", _scale(observation_size, observation_scale))

    def forward(self, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        return self.net(torch.cat([observation / self.observation_scale, action], dim=-1))


def make_actor(observation_size: int, action_size: int, hidden_sizes: Sequence[int],
               observation_scale=None) -> TensorDictModule:
    return TensorDictModule(TanhActor(observation_size, action_size, hidden_sizes, observation_scale),
                            in_keys=["observation"], out_keys=["action"])


def make_critic(observation_size: int, action_size: int, hidden_sizes: Sequence[int],
                observation_scale=None) -> ValueOperator:
    return ValueOperator(QCritic(observation_size, action_size, hidden_sizes, observation_scale),
                         in_keys=["observation", "action"], out_keys=["state_action_value"])
