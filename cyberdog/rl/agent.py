"""The learning agent: TorchRL loss (TD3 or DDPG), target updates, optimizers, exploration and one update.

`Agent.update(batch)` is one gradient step of the critic(s); the actor and the target networks are updated
on every `policy_delay`-th call for TD3 (Fujimoto et al. 2018) and on every call for DDPG. TD3's clipped
double-Q and target-policy smoothing live inside `torchrl.objectives.TD3Loss` (its twin critics are one
stacked set of parameters, evaluated with `vmap`).

Speed (gradient updates dominate training on a CPU): the optimizers are fused Adam (one kernel over all
parameters instead of ~8 small ops per tensor), the soft target update is one foreach kernel
(`ForeachSoftUpdate`), the parameter lists are built once, and `update` returns its metrics as 0-d tensors so
that nothing waits for the device until the caller logs them (`metrics_to_float`). None of this changes the
update rule. What remains (batch 256, 3x128 nets, one CPU core, ~10 ms per TD3 update) is about half tensor
work and half TorchRL/tensordict Python around it (functional parameter swaps, vmap over tensordicts), the
price of keeping `TD3Loss`; `torch.compile` of the losses was tried and was no faster on a CPU (and takes
~10-50 s to compile).
"""
from __future__ import annotations

import math

import torch
from tensordict import TensorDict, TensorDictBase
from tensordict.nn import TensorDictSequential
from torchrl.data import Bounded
from torchrl.modules import AdditiveGaussianModule, OrnsteinUhlenbeckProcessModule
from torchrl.objectives import DDPGLoss, SoftUpdate, TD3Loss

from cyberdog.config import AgentConfig
from cyberdog.envs.observation import observation_typical_magnitude
from cyberdog.rl.fast_td3 import FastTD3Losses
from cyberdog.rl.networks import make_actor, make_critic
from cyberdog.rl.replay import TROT_ACTION_KEY


class NonFiniteError(RuntimeError):
    """A loss, Q-value or action became NaN or infinite."""


def action_spec(action_size: int, device: torch.device | str = "cpu") -> Bounded:
    return Bounded(-1.0, 1.0, shape=(action_size,), dtype=torch.float32, device=device)


def make_loss(cfg: AgentConfig, observation_size: int, action_size: int, observation_scale=None,
              actor_observation_scale=None):
    """Actor, critic, the loss module holding them and their targets, and the soft target updater.
    `observation_scale`: typical magnitude of each observation entry (default: the env's, for 50 entries);
    `actor_observation_scale`: the actor's own (default: the same; +inf hides an entry from the actor, see
    `cyberdog.envs.cyberdog_env.actor_observation_scale`)."""
    scale = observation_scale
    if scale is None and observation_size == len(observation_typical_magnitude()):
        scale = observation_typical_magnitude()
    actor_scale = scale if actor_observation_scale is None else actor_observation_scale
    actor = make_actor(observation_size, action_size, cfg.hidden_sizes, actor_scale)
    critic = make_critic(observation_size, action_size, cfg.hidden_sizes, scale)
    if cfg.algorithm == "td3":
        loss = TD3Loss(actor, critic, action_spec=action_spec(action_size), num_qvalue_nets=2,
                       policy_noise=cfg.policy_noise, noise_clip=cfg.noise_clip, loss_function="l2",
                       delay_actor=True, delay_qvalue=True)
    else:
        loss = DDPGLoss(actor, critic, loss_function="l2", delay_actor=True, delay_value=True)
    loss.make_value_estimator(gamma=cfg.gamma)
    return actor, loss, ForeachSoftUpdate(loss, tau=cfg.tau)


class ForeachSoftUpdate(SoftUpdate):
    """TorchRL's `SoftUpdate`, θ_target ← θ_target + τ (θ − θ_target), over the same (source, target) pairs,
    applied by one `torch._foreach_lerp_` over all of them (the same kernel as `lerp_`, bit-identical results)
    instead of `SoftUpdate.step`'s tensordict `.data` views and `lerp_` per network: ~0.5 ms → ~0.03 ms of CPU
    per target update.

    The pairs are collected at the first `step`, after the loss was moved to its device; the parameters are
    updated in place afterwards (optimizers, `load_state_dict`), so they stay valid.
    """

    _pairs: tuple[list[torch.Tensor], list[torch.Tensor]] | None = None

    def _collect_pairs(self) -> tuple[list[torch.Tensor], list[torch.Tensor]]:
        targets, sources = [], []
        for key, source in self._sources.items(True, True):
            key = key if isinstance(key, tuple) else (key,)
            target = self._targets[("target_" + key[0], *key[1:])]
            if target.requires_grad:
                raise RuntimeError("the target parameter is part of a graph.")
            targets.append(target.data)
            sources.append(source.data)
        return targets, sources

    def step(self) -> None:
        if not self.initialized:
            return super().step()  # raises the usual error
        if self._pairs is None:
            self._pairs = self._collect_pairs()
        with torch.no_grad():
            torch._foreach_lerp_(self._pairs[0], self._pairs[1], 1 - self.eps)


def critic_parameters(loss) -> list[torch.nn.Parameter]:
    params = loss.qvalue_network_params if isinstance(loss, TD3Loss) else loss.value_network_params
    return list(params.flatten_keys().values())


def actor_parameters(loss) -> list[torch.nn.Parameter]:
    return list(loss.actor_network_params.flatten_keys().values())


def _adam(params: list[torch.nn.Parameter], lr: float) -> torch.optim.Adam:
    """Fused Adam where the parameters' device supports it (CPU, CUDA), else the multi-tensor (foreach) one.

    The same update rule as the default per-tensor Adam (equal up to float rounding); on a CPU its step costs
    ~0.15 ms instead of ~1-2 ms, and the whole TD3 update was ~1.2-1.3x faster with it."""
    try:
        return torch.optim.Adam(params, lr=lr, fused=True)
    except RuntimeError:
        return torch.optim.Adam(params, lr=lr, foreach=True)


def make_optimizers(cfg: AgentConfig, loss) -> tuple[torch.optim.Adam, torch.optim.Adam]:
    """Separate Adam optimizers (Table 4: actor 4e-4, critic 2e-3)."""
    return _adam(actor_parameters(loss), cfg.actor_lr), _adam(critic_parameters(loss), cfg.critic_lr)


def make_exploration(cfg: AgentConfig, actor, action_size: int) -> TensorDictSequential:
    """Actor followed by exploration noise (Gaussian or Ornstein–Uhlenbeck), annealed over env steps."""
    spec = action_spec(action_size)
    if cfg.exploration == "gaussian":
        # AdditiveGaussianModule draws std · sigma(t) · N(0, 1); sigma(t) anneals 1 → end/start
        ratio = cfg.exploration_sigma_end / cfg.exploration_sigma if cfg.exploration_sigma else 1.0
        noise = AdditiveGaussianModule(spec=spec, sigma_init=1.0, sigma_end=ratio, std=cfg.exploration_sigma,
                                       annealing_num_steps=cfg.exploration_annealing_steps)
    else:
        noise = OrnsteinUhlenbeckProcessModule(spec=spec, eps_init=1.0, theta=cfg.ou_theta,
                                               sigma=max(cfg.exploration_sigma, 1e-12), dt=cfg.ou_dt,
                                               annealing_num_steps=cfg.exploration_annealing_steps,
                                               eps_end=(cfg.exploration_sigma_end / cfg.exploration_sigma
                                                        if cfg.exploration_sigma else 1.0))
    return TensorDictSequential(actor, noise)


def _finite(**values: torch.Tensor) -> None:
    """Raise `NonFiniteError` naming the first non-finite value; one device sync for all of them."""
    if not bool(torch.stack([torch.isfinite(v).all() for v in values.values()]).all()):
        name = next(n for n, v in values.items() if not torch.isfinite(v).all())
        raise NonFiniteError(f"{name.replace('_', ' ')} is not finite (NaN or inf); training stopped")


def metrics_to_float(metrics: list[dict[str, torch.Tensor]]) -> dict[str, float]:
    """Mean of each metric over several `Agent.update` results, as Python floats (one device sync)."""
    if not metrics:
        return {}
    keys = list(metrics[0])
    means = torch.stack([torch.stack([torch.as_tensor(m[k], dtype=torch.float32) for m in metrics]).mean()
                         for k in keys]).tolist()
    return dict(zip(keys, means))


def _widened(actor_state: dict, mine: dict) -> dict:
    """An actor whose observation had fewer entries at the end than this agent's (an input appended since, e.g.
    `EnvConfig.observe_pd_stiffness`): its first layer gains zero-weight columns and its input scale this
    agent's scale for the new entries, so that it acts exactly as before and may learn to use them."""
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


class Agent:
    """Loss, optimizers and the update schedule of one TD3 or DDPG agent."""

    def __init__(self, cfg: AgentConfig, observation_size: int, action_size: int, device: str = "cpu",
                 observation_scale=None, actor_observation_scale=None):
        self.cfg = cfg
        self.device = torch.device(device)
        self.actor, self.loss, self.target_updater = make_loss(cfg, observation_size, action_size,
                                                               observation_scale, actor_observation_scale)
        self.loss.to(self.device)
        self.critic_params, self.actor_params = critic_parameters(self.loss), actor_parameters(self.loss)
        self.actor_optimizer, self.critic_optimizer = make_optimizers(cfg, self.loss)
        self.policy = make_exploration(cfg, self.actor, action_size).to(self.device)
        self.policy_delay = cfg.policy_delay if cfg.algorithm == "td3" else 1
        self.action_l2 = cfg.action_l2  # the trainer sets a stage's own (StageConfig.action_l2)
        self.trot_imitation = cfg.trot_imitation  # the trainer sets a stage's own (StageConfig.trot_imitation)
        self.imitation_scale = 1.0  # 1 − the trot prior's weight now (the trainer sets it before each round)
        td3 = isinstance(self.loss, TD3Loss)
        self._value_loss = self.loss.value_loss if td3 else self.loss.loss_value
        self._actor_loss = self.loss.actor_loss if td3 else self.loss.loss_actor
        self._fast = FastTD3Losses(self.loss) if td3 and cfg.fast_update else None
        self.updates = 0  # critic updates done
        self.actor_updates = 0  # actor (and target) updates done
        self.actor_from_file = False  # the actor came from an actor file (`load_actor`): it needs no random start
        self.actor_anchor = 0.0  # the pull toward `anchor` (the trainer sets a stage's own: StageConfig.actor_anchor)
        self.anchor = None  # frozen copy of the actor's parameters the pull is toward (`set_anchor`)
        self._last_actor_loss = torch.tensor(math.nan, device=self.device)

    @property
    def last_actor_loss(self) -> float:
        """Actor loss of the latest actor update (NaN before the first)."""
        return float(self._last_actor_loss)

    def _step(self, optimizer: torch.optim.Optimizer, loss: torch.Tensor, params) -> None:
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        if self.cfg.max_grad_norm > 0:
            torch.nn.utils.clip_grad_norm_(params, self.cfg.max_grad_norm, foreach=True)
        optimizer.step()

    def update(self, batch: TensorDictBase, actor: bool = True, targets: bool | None = None) -> dict[str, torch.Tensor]:
        """One critic update; actor + soft target update every `policy_delay`-th call (if `actor`; with
        `actor=False` the critics alone learn, e.g. while they catch up with a new reward, and the targets follow
        only if `targets` (default: as `actor`): the critics then evaluate the actor as it is, their values
        propagating through the targets, instead of regressing on one step's reward over frozen targets).

        Returns the metrics as detached 0-d tensors (critic_loss, actor_loss, q_mean, q_max); convert them with
        `metrics_to_float` when logging. Raises `NonFiniteError` before any step that would write NaN/inf."""
        if batch.device != self.device:
            batch = batch.to(self.device)
        if self._fast is not None:
            value_loss, q = self._fast.value_loss(batch)
        else:
            value_loss, meta = self._value_loss(batch)
            q = meta["pred_value"].detach()
        _finite(critic_loss=value_loss, Q_value=q)
        self._step(self.critic_optimizer, value_loss, self.critic_params)
        self.updates += 1
        if actor and self.updates % self.policy_delay == 0:
            actor_loss = self._actor_objective(batch)
            _finite(actor_loss=actor_loss)
            self._step(self.actor_optimizer, actor_loss, self.actor_params)
            self.target_updater.step()
            self.actor_updates += 1
            self._last_actor_loss = actor_loss.detach()
        elif targets and self.updates % self.policy_delay == 0:  # the actor waits; the targets follow
            self.target_updater.step()
        return {"critic_loss": value_loss.detach(), "actor_loss": self._last_actor_loss, "q_mean": q.mean(),
                "q_max": q.max()}

    def _actor_objective(self, batch: TensorDictBase) -> torch.Tensor:
        """The actor loss (−Q₁(s, μ(s)), by `FastTD3Losses` or the TorchRL loss's own) plus `_penalties`, with
        μ(s) (and μ(s') and μ(s̃) for the smoothness terms) from one forward pass through the loss's actor
        parameters."""
        obs = batch["observation"]
        parts = [obs]
        if self.cfg.action_smoothness > 0:
            parts.append(batch["next", "observation"])
        if self.cfg.action_spatial_smoothness > 0:
            parts.append(self._perturbed(obs))
        both = torch.cat(parts) if len(parts) > 1 else obs
        if self._fast is not None:
            actions = self._fast.actor_actions(both)
        else:
            with self.loss.actor_network_params.to_module(self.loss.actor_network):
                actions = self.loss.actor_network(TensorDict({"observation": both},
                                                             batch_size=both.shape[:1]))["action"]
        chunks = list(actions.chunk(len(parts)))
        now = chunks.pop(0)
        nxt = chunks.pop(0) if self.cfg.action_smoothness > 0 else None
        near = chunks.pop(0) if self.cfg.action_spatial_smoothness > 0 else None
        if self._fast is not None:
            loss = self._fast.actor_loss(obs, now)
        else:
            loss, _ = self._actor_loss(batch)
        return self._with_penalties(loss, now, nxt, batch, near)

    def _perturbed(self, obs: torch.Tensor) -> torch.Tensor:
        """s̃ = s + σ·scale·ε, ε ~ N(0, I): each observation entry moved by `spatial_smoothness_sigma` of its
        typical magnitude (the actor's input scale; an entry hidden from the actor, scale +inf, is left as is)."""
        scale = self.actor.module.observation_scale
        scale = torch.where(torch.isfinite(scale), scale, torch.zeros_like(scale))
        return obs + self.cfg.spatial_smoothness_sigma * scale * torch.randn_like(obs)

    def _with_penalties(self, loss: torch.Tensor, now: torch.Tensor, nxt: torch.Tensor | None,
                        batch: TensorDictBase, near: torch.Tensor | None = None) -> torch.Tensor:
        """`loss` (−Q) plus, in this order, over the batch's actions μ(s) (`now`) and μ(s') (`nxt`):
        - `action_l2 · mean(μ(s)²)`: keeps a residual policy near the trot controller unless the critic's
          gradient says otherwise (without it the actor ran to the ±1 bounds within a few thousand updates,
          where the critic, trained on actions near 0, only extrapolates: configs/quick_residual.yaml);
        - `action_smoothness · mean((μ(s') − μ(s))²)`: CAPS's temporal term (Mysore et al. 2021): a jump of
          the foot targets makes the PID jerk;
        - `action_spatial_smoothness · mean((μ(s̃) − μ(s))²)` over s̃ near s (`_perturbed`, `near` = μ(s̃)):
          CAPS's spatial term, here a brake on the policy's feedback: a policy that hardly reacts to the state
          commands what a fixed path commands, so its gait must hold without feedback (a fixed path replayed
          open loop loses the orbits that policies hold with sub-millimetre corrections:
          notebook/tools/replay_orbit.py);
        - `trot_imitation · mean((μ(s) − (1 − w)·a_trot(s))²)` over the transitions with a reference: pulls a
          torque policy toward the share of the trot controller's torque a_trot (stored per transition,
          `EnvConfig.trot_reference`) that the prior of weight w (`imitation_scale` = 1 − w) no longer gives;
          TD3+BC's regulariser (Fujimoto & Gu 2021) with the trot as the behaviour;
        - `actor_anchor · mean((μ(s) − μ₀(s))²)`: the pull toward the frozen actor `anchor` (`set_anchor`), the
          same regulariser with the actor a stage started from as the behaviour."""
        if self.action_l2 > 0:
            loss = loss + self.action_l2 * now.pow(2).mean()
        if nxt is not None:
            loss = loss + self.cfg.action_smoothness * (nxt - now).pow(2).mean()
        if near is not None:
            loss = loss + self.cfg.action_spatial_smoothness * (near - now).pow(2).mean()
        if self.actor_anchor > 0 and self.anchor is not None:
            with torch.no_grad(), self.anchor.to_module(self.loss.actor_network):
                start = self.loss.actor_network(TensorDict({"observation": batch["observation"]},
                                                           batch_size=batch.batch_size[:1]))["action"]
            loss = loss + self.actor_anchor * (now - start).pow(2).mean()
        if self.trot_imitation > 0:
            reference = batch[TROT_ACTION_KEY]
            known = torch.isfinite(reference).all(-1)
            if known.any():
                target = torch.nan_to_num(reference) * self.imitation_scale
                error = (now - target).pow(2).mean(-1)
                loss = loss + self.trot_imitation * (error * known).sum() / known.sum()
        return loss

    def set_anchor(self) -> None:
        """Freeze a copy of the actor's parameters as it is now: what `actor_anchor` pulls toward."""
        self.anchor = self.loss.actor_network_params.detach().clone()

    def set_actor_lr(self, lr: float, fresh: bool = False) -> None:
        """The actor's learning rate from now on; `fresh=True` also drops Adam's moments (a new optimizer)."""
        if fresh:
            self.actor_optimizer = _adam(self.actor_params, lr)
        for group in self.actor_optimizer.param_groups:
            group["lr"] = lr

    # ---- checkpoint state (tensors and plain containers only) ----
    def state_dict(self) -> dict:
        return {"loss": self.loss.state_dict(), "actor_optimizer": self.actor_optimizer.state_dict(),
                "critic_optimizer": self.critic_optimizer.state_dict(), "exploration": self.policy.state_dict(),
                "updates": self.updates, "actor_updates": self.actor_updates,
                **({"anchor": self.anchor.flatten_keys().to_dict()} if self.anchor is not None else {})}

    def load_actor(self, actor_state: dict) -> int:
        """Start from an actor alone (an actor file's `actor`, e.g. a shipped policy; one that observed fewer
        entries at the end is widened, `_widened`; returns the parameters that widening added, 0 without): the
        actor and its target take its weights; the critics, their targets, the optimizers, the exploration noise
        and the counters stay as built (new). The critics then know nothing of this actor's returns: a stage
        started so wants `critic_warmup_updates` before the actor follows them."""
        mine = self.loss.state_dict()
        given = sum(v.numel() for v in actor_state.values())
        actor_state = _widened(actor_state, {k[len("actor_network_params."):]: v for k, v in mine.items()
                                             if k.startswith("actor_network_params.")})
        added = sum(v.numel() for v in actor_state.values()) - given
        expected = {k[len("actor_network_params."):] for k in mine if k.startswith("actor_network_params.")}
        if set(actor_state) != expected:
            raise ValueError(f"the actor's parameters do not match this agent's: missing "
                             f"{sorted(expected - set(actor_state))}, unknown {sorted(set(actor_state) - expected)}")
        for prefix in ("actor_network_params.", "target_actor_network_params."):
            for k, v in actor_state.items():
                if mine[prefix + k].shape != v.shape:
                    raise ValueError(f"the actor's {k} has shape {tuple(v.shape)}, this agent's "
                                     f"{tuple(mine[prefix + k].shape)}")
                mine[prefix + k] = v
        self.loss.load_state_dict(mine)
        if self._fast is not None:
            self._fast.refresh()
        self.actor_from_file = True
        return added

    def load_state_dict(self, state: dict, optimizers: bool = True) -> None:
        self.loss.load_state_dict(state["loss"])
        if self._fast is not None:
            self._fast.refresh()
        if optimizers:
            self.actor_optimizer.load_state_dict(state["actor_optimizer"])
            self.critic_optimizer.load_state_dict(state["critic_optimizer"])
            for opt in (self.actor_optimizer, self.critic_optimizer):  # a checkpoint may predate fused Adam
                fused = opt.defaults.get("fused")
                for group in opt.param_groups:
                    group["fused"], group["foreach"] = fused, opt.defaults.get("foreach")
            self.policy.load_state_dict(state["exploration"])
            self.updates, self.actor_updates = int(state["updates"]), int(state["actor_updates"])
            if "anchor" in state:  # a stage pulled toward the actor it started from: the same actor after a resume
                self.anchor = self.loss.actor_network_params.detach().clone()
                for key, value in state["anchor"].items():
                    self.anchor.set(tuple(key.split(".")), value.to(self.device))
