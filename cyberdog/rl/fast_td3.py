"""TD3's two losses written directly in torch, over the parameters of a TorchRL `TD3Loss`.

`TD3Loss` keeps its twin critics as one stacked set of parameters (leading dimension 2) and evaluates them by
`vmap` over tensordicts; with 3×128 networks at batch 256 on one CPU core about half of an update is that
Python machinery, not arithmetic. `FastTD3Losses` computes the same two losses from the same parameter
tensors (those the optimizers step and `SoftUpdate` blends), with the twin critics as one batched matrix
product per layer (`baddbmm` over the stacked weights), so it is a drop-in replacement for
`TD3Loss.value_loss` / `TD3Loss.actor_loss`:

- critic loss (Fujimoto et al. 2018): y = r + γ·(1 − terminated)·min_i Q'_i(s', clip(μ'(s') + ε)), with
  ε = clip(N(0, policy_noise), ±noise_clip) drawn by `randn_like(action)` first, as TorchRL does (so the same
  generator state gives the same noise); loss = mean over the batch of Σ_i (Q_i(s, a) − y)²;
- actor loss: −mean Q_1(s, μ(s)) through the critic's detached parameters.

`tests/test_fast_td3.py` checks both losses and their gradients against `TD3Loss` on fixed batches (to 1e-5).
The networks must be those of `cyberdog.rl.networks` (an MLP on [s / scale, a] and a tanh MLP on s / scale).
"""
from __future__ import annotations

import torch
import torch.nn.functional as F
from tensordict import TensorDictBase
from torchrl.objectives import TD3Loss

Layers = list[tuple[torch.Tensor, torch.Tensor]]  # (weight, bias) per linear layer


def _layers(params, prefix: str = "module.net.") -> tuple[Layers, torch.Tensor]:
    """The (weight, bias) pairs of an `mlp` in layer order, and its observation scale, from loss parameters."""
    flat = params.flatten_keys()
    index = sorted({int(k[len(prefix):].split(".")[0]) for k in flat.keys() if k.startswith(prefix)})
    return [(flat[f"{prefix}{i}.weight"], flat[f"{prefix}{i}.bias"]) for i in index], flat["module.observation_scale"]


def actor_forward(layers: Layers, scale: torch.Tensor, observation: torch.Tensor) -> torch.Tensor:
    """μ(s) = tanh(MLP(s / scale)), as `TanhActor`."""
    x = observation / scale
    for w, b in layers[:-1]:
        x = torch.relu(F.linear(x, w, b))
    w, b = layers[-1]
    return torch.tanh(F.linear(x, w, b))


def twin_critic_forward(layers: Layers, scale: torch.Tensor, observation: torch.Tensor,
                        action: torch.Tensor) -> torch.Tensor:
    """(2, B) Q-values of the stacked critics (weights (2, out, in)), as `QCritic` per critic."""
    n = scale.shape[0]
    x = torch.cat([observation.unsqueeze(0) / scale.unsqueeze(1), action.unsqueeze(0).expand(n, -1, -1)], dim=-1)
    for w, b in layers[:-1]:
        x = torch.relu(torch.baddbmm(b.unsqueeze(1), x, w.transpose(1, 2)))
    w, b = layers[-1]
    return torch.baddbmm(b.unsqueeze(1), x, w.transpose(1, 2)).squeeze(-1)


def first_critic_forward(layers: Layers, scale: torch.Tensor, observation: torch.Tensor,
                         action: torch.Tensor) -> torch.Tensor:
    """(B,) Q-values of the first critic only."""
    x = torch.cat([observation / scale[0], action], dim=-1)
    for w, b in layers[:-1]:
        x = torch.relu(F.linear(x, w[0], b[0]))
    w, b = layers[-1]
    return F.linear(x, w[0], b[0]).squeeze(-1)


class FastTD3Losses:
    """`value_loss(batch)` and `actor_loss(batch, observation_extra=None)` of a `TD3Loss`, computed directly."""

    def __init__(self, loss: TD3Loss):
        if not isinstance(loss, TD3Loss) or loss.num_qvalue_nets != 2:
            raise TypeError("FastTD3Losses needs a TD3Loss with num_qvalue_nets=2")
        if loss.loss_function != "l2":
            raise ValueError(f"FastTD3Losses implements the l2 critic loss, the loss has {loss.loss_function!r}")
        self.loss = loss
        self.refresh()

    def refresh(self) -> None:
        """Re-read the parameter tensors (after anything that may have replaced them rather than written them
        in place; optimizer steps, soft updates and `load_state_dict` write in place)."""
        L = self.loss
        self.critic, self.critic_scale = _layers(L.qvalue_network_params)
        self.target_critic, self.target_critic_scale = _layers(L.target_qvalue_network_params)
        self.actor, self.actor_scale = _layers(L.actor_network_params)
        self.target_actor, self.target_actor_scale = _layers(L.target_actor_network_params)
        self.gamma = float(L.value_estimator.gamma)
        self.policy_noise, self.noise_clip = float(L.policy_noise), float(L.noise_clip)
        self.min_action, self.max_action = L.min_action, L.max_action

    def value_loss(self, batch: TensorDictBase) -> tuple[torch.Tensor, torch.Tensor]:
        """(critic loss, Q-values (2, B) detached)."""
        action = batch["action"]
        noise = (torch.randn_like(action) * self.policy_noise).clamp(-self.noise_clip, self.noise_clip)
        next_observation = batch["next", "observation"]
        with torch.no_grad():
            next_action = (actor_forward(self.target_actor, self.target_actor_scale, next_observation) + noise
                           ).clamp(self.min_action, self.max_action)
            next_q = twin_critic_forward(self.target_critic, self.target_critic_scale, next_observation,
                                         next_action).min(0)[0]
            reward = batch["next", "reward"].reshape(next_q.shape)
            alive = (~batch["next", "terminated"]).reshape(next_q.shape).to(next_q.dtype)
            target = reward + self.gamma * alive * next_q
        q = twin_critic_forward(self.critic, self.critic_scale, batch["observation"], action)
        return (q - target).pow(2).sum(0).mean(), q.detach()

    def actor_actions(self, observation: torch.Tensor) -> torch.Tensor:
        """μ(s) through the trained actor's parameters (with gradient)."""
        return actor_forward(self.actor, self.actor_scale, observation)

    def actor_loss(self, observation: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        """−mean Q_1(s, μ(s)) for μ(s) = `action` (from `actor_actions`), critic parameters detached."""
        layers = [(w.detach(), b.detach()) for w, b in self.critic]
        return -first_critic_forward(layers, self.critic_scale, observation, action).mean()


__all__ = ["FastTD3Losses", "actor_forward", "first_critic_forward", "twin_critic_forward"]
