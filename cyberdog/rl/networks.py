"""Actor and critic networks (paper Section 3: three fully connected hidden layers of 128 ReLU units).

The actor μ(s) maps the observation to an action in [−1, 1]^12 (tanh output, scaled later by the environment's
`action_scale`); a critic Q(s, a) maps (observation, action) to one value. Inputs are divided by a fixed typical
magnitude per observation entry (from the environment's layout), so that joint speeds of 10 rad/s and body
heights of 0.3 m reach the first layer on the same scale (+inf hides an entry from the actor). The actor's output
layer starts near zero (uniform ±3e-3, as in Lillicrap et al. 2016, DDPG): in residual mode the untrained policy
then adds almost nothing to the trot controller, and the first episodes walk instead of falling at once.

Two views of the same tensors:
- `ActorModule` is the actor as a TorchRL module (reads "observation", writes "action") for the collector and
  the exploration noise; `TanhActor` is its network, what rollouts load an actor file into.
- `Net` is one network's tensors as the update (`cyberdog.rl.td3`) uses them: (weight, bias) per linear layer
  and the input scale, with the functional forwards `actor_forward` and `critic_forward`. The critics are
  `n_critics` MLPs whose tensors are stacked along a leading dimension (TD3: 2), evaluated by one batched matrix
  product per layer; DDPG's one critic is unstacked.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import torch
import torch.nn.functional as F
from tensordict import TensorDictBase
from tensordict.nn import TensorDictModuleBase
from torch import nn

FINAL_LAYER_INIT = 3e-3  # actor output layer weights and biases start in ±this (DDPG paper)


def mlp(in_features: int, out_features: int, hidden_sizes: Sequence[int]) -> nn.Sequential:
    """Linear → ReLU for each hidden layer, then a linear output layer."""
    layers: list[nn.Module] = []
    width = in_features
    for h in hidden_sizes:
        layers += [nn.Linear(width, int(h)), nn.ReLU()]
        width = int(h)
    layers.append(nn.Linear(width, out_features))
    return nn.Sequential(*layers)


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
        return actor_forward(Net.of(self), observation)


class QCritic(nn.Module):
    """State-action value Q(s, a) = MLP([s / scale, a]): one critic, as built before `make_critics` stacks them."""

    def __init__(self, observation_size: int, action_size: int, hidden_sizes: Sequence[int],
                 observation_scale=None):
        super().__init__()
        self.net = mlp(observation_size + action_size, 1, hidden_sizes)
        self.register_buffer("observation_scale", _scale(observation_size, observation_scale))

    def forward(self, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        return self.net(torch.cat([observation / self.observation_scale, action], dim=-1))


class ActorModule(TensorDictModuleBase):
    """The actor as a TorchRL module: reads "observation", writes "action" (μ(s)) into the same tensordict."""

    in_keys = ["observation"]
    out_keys = ["action"]

    def __init__(self, module: TanhActor):
        super().__init__()
        self.module = module

    def forward(self, tensordict: TensorDictBase) -> TensorDictBase:
        return tensordict.set("action", self.module(tensordict.get("observation")))


def make_actor(observation_size: int, action_size: int, hidden_sizes: Sequence[int],
               observation_scale=None) -> ActorModule:
    return ActorModule(TanhActor(observation_size, action_size, hidden_sizes, observation_scale))


@dataclass
class Net:
    """One network's tensors: (weight, bias) per linear layer, and the input scale (a constant, not trained)."""

    layers: list[tuple[torch.Tensor, torch.Tensor]]
    scale: torch.Tensor

    @classmethod
    def of(cls, module: TanhActor | QCritic) -> "Net":
        """The module's own tensors (not copies: what trains one trains the other)."""
        return cls([(linear.weight, linear.bias) for linear in module.net[::2]], module.observation_scale)

    def named(self) -> dict[str, torch.Tensor]:
        """Name → tensor, named as in `TanhActor.state_dict()` under "module." (an actor file's names)."""
        out = {"module.observation_scale": self.scale}
        for i, (w, b) in enumerate(self.layers):
            out[f"module.net.{2 * i}.weight"], out[f"module.net.{2 * i}.bias"] = w, b
        return out

    def parameters(self) -> list[torch.Tensor]:
        return [t for wb in self.layers for t in wb]

    def detached_copy(self) -> "Net":
        """A copy that no gradient reaches: a target network."""
        return Net([(w.detach().clone(), b.detach().clone()) for w, b in self.layers], self.scale.clone())

    def detached(self) -> "Net":
        """The same tensors, cut from the graph (the critic as the actor's loss sees it)."""
        return Net([(w.detach(), b.detach()) for w, b in self.layers], self.scale)

    def first(self) -> "Net":
        """The first of stacked critics (itself if unstacked)."""
        if self.scale.dim() == 1:
            return self
        return Net([(w[0], b[0]) for w, b in self.layers], self.scale[0])


def make_critics(observation_size: int, action_size: int, hidden_sizes: Sequence[int], observation_scale=None,
                 n_critics: int = 2) -> Net:
    """`n_critics` critics as one `Net`. One critic is a `QCritic`'s tensors; for more, each tensor of a `QCritic`
    is stacked `n_critics` times and redrawn uniformly within its own range, one tensor after the other, as
    TorchRL's `TD3Loss` builds its twin critics (so that a seed gives the critics it gave there)."""
    critic = QCritic(observation_size, action_size, hidden_sizes, observation_scale)
    net = Net.of(critic)
    if n_critics == 1:
        return Net([(nn.Parameter(w.detach()), nn.Parameter(b.detach())) for w, b in net.layers], net.scale)

    def stacked(t: torch.Tensor) -> nn.Parameter:
        out = t.detach().expand(n_critics, *t.shape).clone()
        return nn.Parameter(out.uniform_(out.min().item(), out.max().item()))

    scale = net.scale.expand(n_critics, *net.scale.shape).clone()
    return Net([(stacked(w), stacked(b)) for w, b in net.layers], scale)


def actor_forward(net: Net, observation: torch.Tensor) -> torch.Tensor:
    """μ(s) = tanh(MLP(s / scale))."""
    x = observation / net.scale
    for w, b in net.layers[:-1]:
        x = torch.relu(F.linear(x, w, b))
    w, b = net.layers[-1]
    return torch.tanh(F.linear(x, w, b))


def critic_forward(net: Net, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
    """(n, B) values Q_i(s, a) of the n critics of `net` (n = 1 for one unstacked critic)."""
    if net.scale.dim() == 1:
        x = torch.cat([observation / net.scale, action], dim=-1)
        for w, b in net.layers[:-1]:
            x = torch.relu(F.linear(x, w, b))
        w, b = net.layers[-1]
        return F.linear(x, w, b).squeeze(-1).unsqueeze(0)
    n = net.scale.shape[0]
    x = torch.cat([observation.unsqueeze(0) / net.scale.unsqueeze(1), action.unsqueeze(0).expand(n, -1, -1)], dim=-1)
    for w, b in net.layers[:-1]:
        x = torch.relu(torch.baddbmm(b.unsqueeze(1), x, w.transpose(1, 2)))
    w, b = net.layers[-1]
    return torch.baddbmm(b.unsqueeze(1), x, w.transpose(1, 2)).squeeze(-1)


__all__ = ["ActorModule", "Net", "QCritic", "TanhActor", "actor_forward", "critic_forward", "make_actor",
           "make_critics", "mlp"]
