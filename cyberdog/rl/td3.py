"""One TD3 update (Fujimoto et al. 2018), or with one critic DDPG's (Lillicrap et al. 2016), top to bottom.

With μ the actor, Q_1..Q_n the critics (TD3: n = 2; DDPG: n = 1) and μ', Q'_i their target networks:

    a' = clip(μ'(s') + clip(ε, ±noise_clip), −1, 1), ε ~ N(0, policy_noise²)   target-policy smoothing (TD3;
                                                                               DDPG: a' = μ'(s'))
    y = r + γ · (1 − terminated) · min_i Q'_i(s', a')                          clipped double-Q
    L_Q = mean over the batch of Σ_i (Q_i(s, a) − y)²                          every update
    L_μ = −mean Q_1(s, μ(s)) + the actor's penalties (`with_penalties`)        every d-th update (delayed actor:
                                                                               TD3 d = policy_delay, DDPG 1)
    θ' ← θ' + τ (θ − θ'), each target toward its network                       with each actor update (Polyak)

A stage's own settings come in as `StageSettings` (built from its `StageConfig` by `StageSettings.of`); the
agent-wide ones (γ, τ, d, the noise, the smoothness terms) are `agent.cfg`'s (`AgentConfig`). The networks'
forward passes are `cyberdog.rl.networks`' `actor_forward` and `critic_forward`; the agent that holds the
networks, optimizers and counters is `cyberdog.rl.agent.Agent`. `tests/test_td3.py` checks the losses and their
gradients against TorchRL's `TD3Loss` and `DDPGLoss` (to 1e-5), whole updates against TorchRL's loss, Adam and
`SoftUpdate`, and the soft update bit for bit.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

import torch
from tensordict import TensorDictBase

from cyberdog.config import AgentConfig, StageConfig
from cyberdog.rl.networks import Net, actor_forward, critic_forward
from cyberdog.rl.replay import TROT_ACTION_KEY

if TYPE_CHECKING:
    from cyberdog.rl.agent import Agent


class NonFiniteError(RuntimeError):
    """A loss, Q-value or action became NaN or infinite."""


@dataclass(frozen=True)
class StageSettings:
    """What a stage sets for its updates (`StageConfig`, else the agent's `AgentConfig` values)."""

    actor_lr: float  # Adam learning rate of the actor
    action_l2: float = 0.0  # weight of mean(μ(s)²)
    trot_imitation: float = 0.0  # weight of the pull toward the trot's torque
    actor_anchor: float = 0.0  # weight of the pull toward the actor the stage started from (`Agent.anchor`)
    critic_warmup_updates: int = 0  # the stage's first updates train the critics only
    critic_warmup_targets: bool = False  # during that warm-up the targets follow the critics
    imitation_scale: float = 1.0  # 1 − the trot prior's weight now (torque mode; it decays over stage 1)

    @classmethod
    def of(cls, agent: AgentConfig, stage: StageConfig | None = None, imitation_scale: float = 1.0) -> StageSettings:
        """The settings of `stage` (None: the agent's own, no warm-up)."""
        if stage is None:
            return cls(agent.actor_lr, agent.action_l2, agent.trot_imitation, imitation_scale=imitation_scale)
        return cls(actor_lr=agent.actor_lr if stage.actor_lr is None else stage.actor_lr,
                   action_l2=agent.action_l2 if stage.action_l2 is None else stage.action_l2,
                   trot_imitation=agent.trot_imitation if stage.trot_imitation is None else stage.trot_imitation,
                   actor_anchor=stage.actor_anchor, critic_warmup_updates=stage.critic_warmup_updates,
                   critic_warmup_targets=stage.critic_warmup_targets, imitation_scale=imitation_scale)

    def replace(self, **changes) -> StageSettings:
        return dataclasses.replace(self, **changes)


def update(agent: Agent, batch: TensorDictBase, s: StageSettings, stage_update: int = 0) -> dict[str, torch.Tensor]:
    """One critic update; the actor's and the soft target update on every d-th one (d = `agent.policy_delay`).

    `stage_update`: the updates the stage made before this one; during its first `s.critic_warmup_updates` the
    actor waits, and the targets follow only if `s.critic_warmup_targets` (the critics then evaluate the actor as
    it is, their values propagating through the targets). Returns the metrics as detached 0-d tensors
    (critic_loss, actor_loss of the latest actor update, q_mean, q_max); raises `NonFiniteError` before a step
    that would write NaN or inf."""
    if batch.device != agent.device:
        batch = batch.to(agent.device)
    value_loss, q = critic_loss(agent, batch)
    _finite(critic_loss=value_loss, Q_value=q)
    _step(agent.critic_optimizer, value_loss, agent.critic.parameters(), agent.cfg.max_grad_norm)
    agent.updates += 1
    warm = stage_update >= s.critic_warmup_updates
    if agent.updates % agent.policy_delay == 0 and (warm or s.critic_warmup_targets):
        if warm:
            loss = actor_loss(agent, batch, s)
            _finite(actor_loss=loss)
            for group in agent.actor_optimizer.param_groups:
                group["lr"] = s.actor_lr
            _step(agent.actor_optimizer, loss, agent.actor_net.parameters(), agent.cfg.max_grad_norm)
            agent.actor_updates += 1
            agent.latest_actor_loss = loss.detach()
        soft_update(agent.target_actor, agent.actor_net, agent.cfg.tau)
        soft_update(agent.target_critic, agent.critic, agent.cfg.tau)
    return {"critic_loss": value_loss.detach(), "actor_loss": agent.latest_actor_loss, "q_mean": q.mean(),
            "q_max": q.max()}


def critic_loss(agent: Agent, batch: TensorDictBase) -> tuple[torch.Tensor, torch.Tensor]:
    """L_Q and the Q-values Q_i(s, a), (n, B), detached. The smoothing noise is one `randn_like(action)`, as
    TorchRL's `TD3Loss` draws it (the same generator state gives the same noise)."""
    cfg, action, next_observation = agent.cfg, batch["action"], batch["next", "observation"]
    with torch.no_grad():
        next_action = actor_forward(agent.target_actor, next_observation)
        if agent.twin:
            noise = (torch.randn_like(action) * cfg.policy_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
            next_action = (next_action + noise).clamp(-1.0, 1.0)
        next_q = critic_forward(agent.target_critic, next_observation, next_action).min(0).values
        reward = batch["next", "reward"].reshape(next_q.shape)
        alive = (~batch["next", "terminated"]).reshape(next_q.shape).to(next_q.dtype)
        target = reward + cfg.gamma * alive * next_q
    q = critic_forward(agent.critic, batch["observation"], action)
    return (q - target).pow(2).sum(0).mean(), q.detach()


def actor_loss(agent: Agent, batch: TensorDictBase, s: StageSettings) -> torch.Tensor:
    """L_μ: −mean Q_1(s, μ(s)) through the critic's detached tensors, plus `with_penalties`. μ(s), and μ(s') and
    μ(s̃) for the smoothness terms, come from one forward pass of the actor."""
    cfg, obs = agent.cfg, batch["observation"]
    parts = [obs]
    if cfg.action_smoothness > 0:
        parts.append(batch["next", "observation"])
    if cfg.action_spatial_smoothness > 0:
        parts.append(perturbed(agent.actor_net, obs, cfg.spatial_smoothness_sigma))
    actions = actor_forward(agent.actor_net, torch.cat(parts) if len(parts) > 1 else obs)
    chunks = list(actions.chunk(len(parts)))
    now = chunks.pop(0)
    nxt = chunks.pop(0) if cfg.action_smoothness > 0 else None
    near = chunks.pop(0) if cfg.action_spatial_smoothness > 0 else None
    loss = -critic_forward(agent.critic.detached().first(), obs, now).mean()
    return with_penalties(agent, s, loss, batch, now, nxt, near)


def perturbed(actor: Net, obs: torch.Tensor, sigma: float) -> torch.Tensor:
    """s̃ = s + σ·scale·ε, ε ~ N(0, I): each observation entry moved by σ of its typical magnitude (the actor's
    input scale; an entry hidden from the actor, scale +inf, is left as is)."""
    scale = torch.where(torch.isfinite(actor.scale), actor.scale, torch.zeros_like(actor.scale))
    return obs + sigma * scale * torch.randn_like(obs)


def with_penalties(agent: Agent, s: StageSettings, loss: torch.Tensor, batch: TensorDictBase, now: torch.Tensor,
                   nxt: torch.Tensor | None = None, near: torch.Tensor | None = None) -> torch.Tensor:
    """`loss` (−Q) plus, in this order, over the batch's actions μ(s) (`now`), μ(s') (`nxt`), μ(s̃) (`near`):
    - `s.action_l2 · mean(μ(s)²)`: keeps a residual policy near the trot controller unless the critic's
      gradient says otherwise (without it the actor ran to the ±1 bounds within a few thousand updates,
      where the critic, trained on actions near 0, only extrapolates);
    - `action_smoothness · mean((μ(s') − μ(s))²)`: CAPS's temporal term (Mysore et al. 2021): a jump of
      the foot targets makes the PID jerk;
    - `action_spatial_smoothness · mean((μ(s̃) − μ(s))²)` over s̃ near s (`perturbed`): CAPS's spatial term,
      here a brake on the policy's feedback: a policy that hardly reacts to the state commands what a fixed
      path commands, so its gait must hold without feedback;
    - `s.actor_anchor · mean((μ(s) − μ₀(s))²)`: the pull toward the frozen actor `agent.anchor` (the actor a
      stage started from: TD3+BC's regulariser, Fujimoto & Gu 2021, with it as the behaviour);
    - `s.trot_imitation · mean((μ(s) − (1 − w)·a_trot(s))²)` over the transitions with a reference: pulls a
      torque policy toward the share of the trot controller's torque a_trot (stored per transition,
      `EnvConfig.trot_reference`) that the prior of weight w (`s.imitation_scale` = 1 − w) no longer gives."""
    cfg = agent.cfg
    if s.action_l2 > 0:
        loss = loss + s.action_l2 * now.pow(2).mean()
    if nxt is not None:
        loss = loss + cfg.action_smoothness * (nxt - now).pow(2).mean()
    if near is not None:
        loss = loss + cfg.action_spatial_smoothness * (near - now).pow(2).mean()
    if s.actor_anchor > 0 and agent.anchor is not None:
        with torch.no_grad():
            start = actor_forward(agent.anchor, batch["observation"])
        loss = loss + s.actor_anchor * (now - start).pow(2).mean()
    if s.trot_imitation > 0:
        reference = batch[TROT_ACTION_KEY]
        known = torch.isfinite(reference).all(-1)
        if known.any():
            target = torch.nan_to_num(reference) * s.imitation_scale
            error = (now - target).pow(2).mean(-1)
            loss = loss + s.trot_imitation * (error * known).sum() / known.sum()
    return loss


def soft_update(target: Net, source: Net, tau: float) -> None:
    """θ' ← θ' + τ (θ − θ') over the layers' weights and biases, in place."""
    weight = 1 - (1 - tau)  # τ as TorchRL's SoftUpdate computes it (from its ε = 1 − τ): the same rounding
    with torch.no_grad():
        for t, p in zip(target.parameters(), source.parameters()):
            t.lerp_(p, weight)


def _step(optimizer: torch.optim.Optimizer, loss: torch.Tensor, params: list[torch.Tensor],
          max_grad_norm: float) -> None:
    optimizer.zero_grad(set_to_none=True)
    loss.backward()
    if max_grad_norm > 0:
        torch.nn.utils.clip_grad_norm_(params, max_grad_norm, foreach=True)
    optimizer.step()


def _finite(**values: torch.Tensor) -> None:
    """Raise `NonFiniteError` naming the first non-finite value; one device sync for all of them."""
    if not bool(torch.stack([torch.isfinite(v).all() for v in values.values()]).all()):
        name = next(n for n, v in values.items() if not torch.isfinite(v).all())
        raise NonFiniteError(f"{name.replace('_', ' ')} is not finite (NaN or inf); training stopped")


def metrics_to_float(metrics: list[dict[str, torch.Tensor]]) -> dict[str, float]:
    """Mean of each metric over several `update` results, as Python floats (one device sync)."""
    if not metrics:
        return {}
    keys = list(metrics[0])
    means = torch.stack([torch.stack([torch.as_tensor(m[k], dtype=torch.float32) for m in metrics]).mean()
                         for k in keys]).tolist()
    return dict(zip(keys, means))


__all__ = ["NonFiniteError", "StageSettings", "actor_loss", "critic_loss", "metrics_to_float",
           "soft_update", "update", "with_penalties"]
