"""TD3 (Fujimoto et al. 2018) as one object, `TD3`: it owns the actor, the critics (TD3: two; DDPG, Lillicrap et
al. 2016: one), their target networks, the Adam optimizers, the exploration policy and the update counters, and
`TD3.update` is one update, top to bottom. With μ the actor, Q_1..Q_n the critics and μ', Q'_i their targets:

    a' = clip(μ'(s') + clip(ε, ±noise_clip), −1, 1), ε ~ N(0, policy_noise²)   target-policy smoothing (TD3;
                                                                               DDPG: a' = μ'(s'))
    y = r + γ · (1 − terminated) · min_i Q'_i(s', a')                          clipped double-Q
    L_Q = mean over the batch of Σ_i (Q_i(s, a) − y)²                          every update
    L_μ = −mean Q_1(s, μ(s)) + the actor's regularisers (`TD3.actor_loss`)    every d-th update (delayed actor:
                                                                               TD3 d = policy_delay, DDPG 1)
    θ' ← θ' + τ (θ − θ'), each target toward its network                       with each actor update (Polyak)

Everything an update reads is an `UpdateSettings`, resolved once when a stage starts (`UpdateSettings.of`: the
agent's `AgentConfig` with the stage's `StageConfig` values in place where it sets its own); `TD3.begin_stage` and
`TD3.set_learning_rates` put its learning rates into the optimizers there.

Speed (gradient updates dominate training on a CPU): the losses are written in torch over the networks' tensors,
the twin critics evaluated as one batched matrix product per layer (`cyberdog.rl.networks`); the optimizers are
fused Adam; `update` returns its metrics as 0-d tensors, so that nothing waits for the device until the caller
logs them (`metrics_to_float`). `tests/test_td3.py` checks the losses and their gradients against TorchRL's
`TD3Loss` and `DDPGLoss` (to 1e-5), whole updates against TorchRL's loss, Adam and `SoftUpdate`, and the soft
update bit for bit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from tensordict import TensorDictBase
from torch import nn

from cyberdog.config import AgentConfig, StageConfig
from cyberdog.envs.observation import observation_typical_magnitude
from cyberdog.rl.exploration import make_exploration
from cyberdog.rl.networks import Net, actor_forward, critic_forward, make_actor, make_critics
from cyberdog.rl.replay import TROT_ACTION_KEY


class NonFiniteError(RuntimeError):
    """A loss, Q-value or action became NaN or infinite."""


@dataclass(frozen=True)
class UpdateSettings:
    """What one update reads, resolved once as a stage starts (`of`): the agent's settings (`AgentConfig`) with the
    stage's own (`StageConfig`) in place where it sets them."""

    actor_lr: float  # Adam learning rate of the actor
    critic_lr: float  # Adam learning rate of the critic(s)
    gamma: float  # discount per agent step
    tau: float  # soft target update rate
    policy_delay: int  # the actor and the targets update every d-th update (DDPG: 1)
    target_smoothing: bool  # a' = μ'(s') + clipped noise (TD3); False: a' = μ'(s') (DDPG)
    policy_noise: float  # std of the smoothing noise (action units)
    noise_clip: float  # clip of the smoothing noise (action units)
    max_grad_norm: float  # gradient-norm clip of each optimizer step; 0 = off
    action_l2: float  # weight of mean(μ(s)²)
    action_smoothness: float  # weight of mean((μ(s') − μ(s))²), CAPS's temporal term
    action_spatial_smoothness: float  # weight of mean((μ(s̃) − μ(s))²), CAPS's spatial term
    spatial_smoothness_sigma: float  # s̃'s spread, in typical magnitudes of each observation entry
    trot_imitation: float  # weight of the pull toward the share of the trot's torque the prior leaves out
    actor_anchor: float  # weight of the pull toward the actor the stage started from (`TD3.anchor`)
    critic_warmup_end: int  # the agent's update count up to which the critics train alone (the stage's warm-up)
    critic_warmup_targets: bool  # during that warm-up the targets follow the critics (every d-th update)

    @classmethod
    def of(cls, agent: AgentConfig, stage: StageConfig | None = None, updates_done: int = 0) -> UpdateSettings:
        """The settings of `stage` (None: the agent's own, no warm-up) for an agent that had made `updates_done`
        updates when the stage started."""
        stage = stage or StageConfig()

        def own(name: str):  # the stage's value, None: the agent's
            return getattr(agent, name) if getattr(stage, name) is None else getattr(stage, name)

        td3 = agent.algorithm == "td3"
        return cls(actor_lr=own("actor_lr"), critic_lr=agent.critic_lr, gamma=agent.gamma, tau=agent.tau,
                   policy_delay=agent.policy_delay if td3 else 1, target_smoothing=td3,
                   policy_noise=agent.policy_noise, noise_clip=agent.noise_clip, max_grad_norm=agent.max_grad_norm,
                   action_l2=own("action_l2"), action_smoothness=agent.action_smoothness,
                   action_spatial_smoothness=agent.action_spatial_smoothness,
                   spatial_smoothness_sigma=agent.spatial_smoothness_sigma, trot_imitation=own("trot_imitation"),
                   actor_anchor=stage.actor_anchor, critic_warmup_end=updates_done + stage.critic_warmup_updates,
                   critic_warmup_targets=stage.critic_warmup_targets)


class TD3:
    """Networks, optimizers, exploration and counters of one TD3 or DDPG agent; `update` is one update.

    `observation_scale`: typical magnitude of each observation entry (default: the env's, for 50 entries);
    `actor_observation_scale`: the actor's own (default: the same; +inf hides an entry from the actor, see
    `cyberdog.envs.observation.actor_observation_scale`). The collector acts with `policy` (the actor and its
    exploration noise), whose actor tensors the update trains in place: it always acts with the latest weights."""

    def __init__(self, cfg: AgentConfig, observation_size: int, action_size: int, device: str = "cpu",
                 observation_scale=None, actor_observation_scale=None):
        self.cfg, self.device = cfg, torch.device(device)
        scale = observation_scale
        if scale is None and observation_size == len(observation_typical_magnitude()):
            scale = observation_typical_magnitude()
        actor_scale = scale if actor_observation_scale is None else actor_observation_scale
        self.twin = cfg.algorithm == "td3"  # two critics (DDPG: one)
        self.actor = make_actor(observation_size, action_size, cfg.hidden_sizes, actor_scale).to(self.device)
        self.actor_net = Net.of(self.actor.module)  # the same tensors, as the update uses them
        critic = make_critics(observation_size, action_size, cfg.hidden_sizes, scale, 2 if self.twin else 1)
        self.critic = _on(critic, self.device)
        self.target_actor, self.target_critic = self.actor_net.detached_copy(), self.critic.detached_copy()
        # each optimizer over its network's tensors in checkpoint order (the input scale among them: a constant
        # that gets no gradient, which Adam leaves as it is), so that the Adam state of a checkpoint maps back
        self.actor_optimizer = _adam(self._actor_tensors, cfg.actor_lr)
        self.critic_optimizer = _adam(list(self.critic.named().values()), cfg.critic_lr)
        self.policy = make_exploration(cfg, self.actor, action_size).to(self.device)
        self.updates = 0  # critic updates done
        self.actor_updates = 0  # actor (and target) updates done
        self.latest_actor_loss = torch.tensor(math.nan, device=self.device)  # of the latest actor update
        self.actor_from_file = False  # the actor came from an actor file (`load_actor`): it needs no random start
        self.anchor: Net | None = None  # frozen copy of the actor that `UpdateSettings.actor_anchor` pulls toward

    def update(self, batch: TensorDictBase, s: UpdateSettings, prior_weight: float = 0.0) -> dict[str, torch.Tensor]:
        """One critic update; the actor's and the soft target update on every d-th one (d = `s.policy_delay`),
        once the stage's critic warm-up is over (the targets also during it with `s.critic_warmup_targets`).

        `prior_weight`: the trot prior's weight now (torque mode), for the imitation term (`actor_loss`). Returns
        the metrics as detached 0-d tensors (critic_loss, actor_loss of the latest actor update, q_mean, q_max);
        raises `NonFiniteError` before a step that would write NaN or inf."""
        if batch.device != self.device:
            batch = batch.to(self.device)
        action, next_observation = batch["action"], batch["next", "observation"]
        with torch.no_grad():  # the target y, from the target networks
            next_action = actor_forward(self.target_actor, next_observation)
            if s.target_smoothing:  # one randn_like(action), as TorchRL's TD3Loss draws it
                noise = (torch.randn_like(action) * s.policy_noise).clamp(-s.noise_clip, s.noise_clip)
                next_action = (next_action + noise).clamp(-1.0, 1.0)
            next_q = critic_forward(self.target_critic, next_observation, next_action).min(0).values
            reward = batch["next", "reward"].reshape(next_q.shape)
            alive = (~batch["next", "terminated"]).reshape(next_q.shape).to(next_q.dtype)
            target = reward + s.gamma * alive * next_q
        q = critic_forward(self.critic, batch["observation"], action)  # (n, B)
        critic_loss = (q - target).pow(2).sum(0).mean()
        _finite(critic_loss=critic_loss, Q_value=q.detach())
        _step(self.critic_optimizer, critic_loss, self.critic.parameters(), s.max_grad_norm)
        self.updates += 1

        actor_turn = self.updates % s.policy_delay == 0
        warming_up = self.updates <= s.critic_warmup_end  # the critics learn the stage's reward first
        if actor_turn and not warming_up:
            actor_loss = self.actor_loss(batch, s, prior_weight)
            _finite(actor_loss=actor_loss)
            _step(self.actor_optimizer, actor_loss, self.actor_net.parameters(), s.max_grad_norm)
            self.actor_updates += 1
            self.latest_actor_loss = actor_loss.detach()
        if actor_turn and (not warming_up or s.critic_warmup_targets):
            soft_update(self.target_actor, self.actor_net, s.tau)
            soft_update(self.target_critic, self.critic, s.tau)
        q = q.detach()
        return {"critic_loss": critic_loss.detach(), "actor_loss": self.latest_actor_loss, "q_mean": q.mean(),
                "q_max": q.max()}

    def actor_loss(self, batch: TensorDictBase, s: UpdateSettings, prior_weight: float = 0.0) -> torch.Tensor:
        """L_μ = −mean Q_1(s, μ(s)), through the critic's detached tensors, plus in this order (each with its
        weight in `s`; 0 turns it off):
        - `action_l2 · mean(μ(s)²)`: keeps a residual policy near the trot controller;
        - `action_smoothness · mean((μ(s') − μ(s))²)`: CAPS's temporal term (Mysore et al. 2021);
        - `action_spatial_smoothness · mean((μ(s̃) − μ(s))²)`, s̃ = s + σ·scale·ε, ε ~ N(0, I): CAPS's spatial
          term, each observation entry moved by σ of its typical magnitude (an entry hidden from the actor is not);
        - `actor_anchor · mean((μ(s) − μ₀(s))²)`: the pull toward the frozen actor `anchor` the stage started
          from (TD3+BC's regulariser, Fujimoto & Gu 2021, with it as the behaviour);
        - `trot_imitation · mean((μ(s) − (1 − w)·a_trot(s))²)` over the transitions with a reference: the pull
          toward the share of the trot controller's torque a_trot (stored per transition, `EnvConfig.trot_reference`)
          that the prior of weight w (`prior_weight`) leaves out.
        μ(s), and μ(s') and μ(s̃) for the smoothness terms, come from one forward pass of the actor."""
        obs = batch["observation"]
        parts = [obs]
        if s.action_smoothness > 0:
            parts.append(batch["next", "observation"])
        if s.action_spatial_smoothness > 0:
            scale = self.actor_net.scale
            scale = torch.where(torch.isfinite(scale), scale, torch.zeros_like(scale))
            parts.append(obs + s.spatial_smoothness_sigma * scale * torch.randn_like(obs))
        actions = list(actor_forward(self.actor_net, torch.cat(parts) if len(parts) > 1 else obs).chunk(len(parts)))
        now = actions.pop(0)
        loss = -critic_forward(self.critic.detached().first(), obs, now).mean()
        if s.action_l2 > 0:
            loss = loss + s.action_l2 * now.pow(2).mean()
        if s.action_smoothness > 0:
            loss = loss + s.action_smoothness * (actions.pop(0) - now).pow(2).mean()
        if s.action_spatial_smoothness > 0:
            loss = loss + s.action_spatial_smoothness * (actions.pop(0) - now).pow(2).mean()
        if s.actor_anchor > 0 and self.anchor is not None:
            with torch.no_grad():
                start = actor_forward(self.anchor, obs)
            loss = loss + s.actor_anchor * (now - start).pow(2).mean()
        if s.trot_imitation > 0:
            reference = batch[TROT_ACTION_KEY]
            known = torch.isfinite(reference).all(-1)
            if known.any():
                error = (now - torch.nan_to_num(reference) * (1.0 - prior_weight)).pow(2).mean(-1)
                loss = loss + s.trot_imitation * (error * known).sum() / known.sum()
        return loss

    # ---- a stage's start ----
    def begin_stage(self, s: UpdateSettings, fresh_actor_optimizer: bool = False) -> None:
        """A stage starts with settings `s`: with `s.actor_anchor`, the actor as it is now is what it pulls
        toward (`anchor`); with `fresh_actor_optimizer`, the actor's Adam moments are dropped; the optimizers
        take the stage's learning rates."""
        if s.actor_anchor > 0:
            self.anchor = self.actor_net.detached_copy()
        if fresh_actor_optimizer:
            self.actor_optimizer = _adam(self._actor_tensors, s.actor_lr)
        self.set_learning_rates(s)

    def set_learning_rates(self, s: UpdateSettings) -> None:
        """The optimizers' learning rates are `s`'s (a stage starts or resumes)."""
        for optimizer, lr in ((self.actor_optimizer, s.actor_lr), (self.critic_optimizer, s.critic_lr)):
            for group in optimizer.param_groups:
                group["lr"] = lr

    @property
    def _actor_tensors(self) -> list[torch.Tensor]:
        return list(self.actor_net.named().values())

    @property
    def last_actor_loss(self) -> float:
        """Actor loss of the latest actor update (NaN before the first)."""
        return float(self.latest_actor_loss)

    # ---- checkpoint state (tensors and plain containers only) ----
    def _networks(self) -> dict[str, Net]:
        """The networks under the names TorchRL's loss modules (`TD3Loss`, `DDPGLoss`) give them, the names a
        checkpoint holds: actor, critic(s) and their targets."""
        critic = "qvalue_network" if self.twin else "value_network"
        return {"actor_network": self.actor_net, "target_actor_network": self.target_actor, critic: self.critic,
                f"target_{critic}": self.target_critic}

    def network_state(self) -> dict[str, torch.Tensor]:
        """Every network's tensors, flat: "actor_network_params.module.net.0.weight", ... (detached, not copies)."""
        return {f"{group}_params.{name}": t.detach() for group, net in self._networks().items()
                for name, t in net.named().items()}

    def load_network_state(self, state: dict[str, torch.Tensor]) -> None:
        """Copy `network_state`'s tensors in place (other keys of `state` are ignored)."""
        with torch.no_grad():
            for name, t in self.network_state().items():
                t.copy_(state[name])

    def state_dict(self) -> dict:
        return {"loss": self.network_state(), "actor_optimizer": self.actor_optimizer.state_dict(),
                "critic_optimizer": self.critic_optimizer.state_dict(), "exploration": self.policy.state_dict(),
                "updates": self.updates, "actor_updates": self.actor_updates,
                **({"anchor": self.anchor.named()} if self.anchor is not None else {})}

    def load_state_dict(self, state: dict, optimizers: bool = True) -> None:
        """`state_dict`'s state; without `optimizers`, the networks only."""
        self.load_network_state(state["loss"])
        if not optimizers:
            return
        self.actor_optimizer.load_state_dict(state["actor_optimizer"])
        self.critic_optimizer.load_state_dict(state["critic_optimizer"])
        for opt in (self.actor_optimizer, self.critic_optimizer):  # fused (or foreach) whatever the state says
            for group in opt.param_groups:
                group["fused"], group["foreach"] = opt.defaults.get("fused"), opt.defaults.get("foreach")
        self.policy.load_state_dict(state["exploration"])
        self.updates, self.actor_updates = int(state["updates"]), int(state["actor_updates"])
        if "anchor" in state:  # a stage pulled toward the actor it started from: the same actor after a resume
            self.anchor = self.actor_net.detached_copy()
            with torch.no_grad():
                for name, t in self.anchor.named().items():
                    t.copy_(state["anchor"][name])

    def load_actor(self, actor_state: dict) -> int:
        """Start from an actor alone (an actor file's `actor`, e.g. a shipped policy; one that observed fewer
        entries at the end is widened, `_widened`; returns the parameters that widening added, 0 without): the
        actor and its target take its weights; the critics, their targets, the optimizers, the exploration noise
        and the counters stay as built (new). The critics then know nothing of this actor's returns: a stage
        started so wants `critic_warmup_updates` before the actor follows them."""
        mine = self.actor_net.named()
        given = sum(v.numel() for v in actor_state.values())
        actor_state = _widened(actor_state, mine)
        added = sum(v.numel() for v in actor_state.values()) - given
        if set(actor_state) != set(mine):
            raise ValueError(f"the actor's parameters do not match this agent's: missing "
                             f"{sorted(set(mine) - set(actor_state))}, unknown {sorted(set(actor_state) - set(mine))}")
        for k, v in actor_state.items():
            if mine[k].shape != v.shape:
                raise ValueError(f"the actor's {k} has shape {tuple(v.shape)}, this agent's {tuple(mine[k].shape)}")
        with torch.no_grad():
            for net in (self.actor_net, self.target_actor):
                for k, t in net.named().items():
                    t.copy_(actor_state[k])
        self.actor_from_file = True
        return added


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


def _adam(params: list[torch.nn.Parameter], lr: float) -> torch.optim.Adam:
    """Fused Adam where the parameters' device supports it (CPU, CUDA), else the multi-tensor (foreach) one: the
    same update rule as the per-tensor Adam (equal up to float rounding), its step ~0.15 ms instead of ~1-2 ms."""
    try:
        return torch.optim.Adam(params, lr=lr, fused=True)
    except RuntimeError:
        return torch.optim.Adam(params, lr=lr, foreach=True)


def _on(net: Net, device: torch.device) -> Net:
    """`net` with its tensors on `device` (trained tensors stay parameters)."""
    if all(t.device == device for t in net.named().values()):
        return net
    return Net([(nn.Parameter(w.detach().to(device)), nn.Parameter(b.detach().to(device))) for w, b in net.layers],
               net.scale.to(device))


def _widened(actor_state: dict, mine: dict) -> dict:
    """An actor whose observation has fewer entries at the end than this agent's (e.g. one trained without
    `EnvConfig.observe_pd_stiffness`): its first layer gains zero-weight columns and its input scale this agent's
    scale for the extra entries, so that it acts exactly as it did and may learn to use them."""
    first = next((k for k in actor_state if k.endswith("net.0.weight")), None)
    scale = next((k for k in actor_state if k.endswith("observation_scale")), None)
    if first is None or scale is None or first not in mine or scale not in mine:
        return actor_state
    extra = mine[first].shape[1] - actor_state[first].shape[1]
    if extra <= 0 or mine[first].shape[0] != actor_state[first].shape[0]:
        return actor_state
    out = dict(actor_state)
    out[first] = torch.cat([actor_state[first], actor_state[first].new_zeros(actor_state[first].shape[0], extra)], 1)
    out[scale] = torch.cat([actor_state[scale], mine[scale][-extra:].to(actor_state[scale])])
    return out


__all__ = ["NonFiniteError", "TD3", "UpdateSettings", "metrics_to_float", "soft_update"]
