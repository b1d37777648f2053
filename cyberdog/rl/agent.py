"""The learning agent: the actor, the critics (TD3: two; DDPG: one), their targets, the Adam optimizers, the
exploration noise and the update counters; its checkpoint state. One update is `cyberdog.rl.td3.update`.

The actor is a TorchRL module (`ActorModule`) that the collector runs with exploration noise (TorchRL's
`AdditiveGaussianModule` or `OrnsteinUhlenbeckProcessModule`); the update trains the same tensors in place
(`Agent.actor_net`), so the collector always acts with the latest weights.

Speed (gradient updates dominate training on a CPU): the losses are written directly in torch over the networks'
tensors, the twin critics evaluated as one batched matrix product per layer (`cyberdog.rl.networks`), the
optimizers are fused Adam (one kernel over all parameters instead of ~8 small ops per tensor), and `update`
returns its metrics as 0-d tensors so that nothing waits for the device until the caller logs them
(`metrics_to_float`). `torch.compile` of the losses was tried and was no faster on a CPU (and takes ~10-50 s to
compile).
"""
from __future__ import annotations

import math

import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictSequential
from torch import nn
from torchrl.data import Bounded
from torchrl.modules import AdditiveGaussianModule, OrnsteinUhlenbeckProcessModule

from cyberdog.config import AgentConfig
from cyberdog.envs.observation import observation_typical_magnitude
from cyberdog.rl import td3
from cyberdog.rl.networks import Net, make_actor, make_critics
from cyberdog.rl.td3 import NonFiniteError, StageSettings, metrics_to_float


def action_spec(action_size: int, device: torch.device | str = "cpu") -> Bounded:
    return Bounded(-1.0, 1.0, shape=(action_size,), dtype=torch.float32, device=device)


def _adam(params: list[torch.nn.Parameter], lr: float) -> torch.optim.Adam:
    """Fused Adam where the parameters' device supports it (CPU, CUDA), else the multi-tensor (foreach) one.

    The same update rule as the default per-tensor Adam (equal up to float rounding); on a CPU its step costs
    ~0.15 ms instead of ~1-2 ms, and the whole TD3 update was ~1.2-1.3x faster with it."""
    try:
        return torch.optim.Adam(params, lr=lr, fused=True)
    except RuntimeError:
        return torch.optim.Adam(params, lr=lr, foreach=True)


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
    """Networks, optimizers, exploration and counters of one TD3 or DDPG agent; `update` is one TD3 update.

    `observation_scale`: typical magnitude of each observation entry (default: the env's, for 50 entries);
    `actor_observation_scale`: the actor's own (default: the same; +inf hides an entry from the actor, see
    `cyberdog.envs.observation.actor_observation_scale`)."""

    def __init__(self, cfg: AgentConfig, observation_size: int, action_size: int, device: str = "cpu",
                 observation_scale=None, actor_observation_scale=None):
        self.cfg, self.device = cfg, torch.device(device)
        scale = observation_scale
        if scale is None and observation_size == len(observation_typical_magnitude()):
            scale = observation_typical_magnitude()
        actor_scale = scale if actor_observation_scale is None else actor_observation_scale
        self.twin = cfg.algorithm == "td3"  # two critics, clipped double-Q, target smoothing, delayed actor
        self.policy_delay = cfg.policy_delay if self.twin else 1
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
        self.anchor: Net | None = None  # frozen copy of the actor that StageSettings.actor_anchor pulls toward

    @property
    def _actor_tensors(self) -> list[torch.Tensor]:
        return list(self.actor_net.named().values())

    @property
    def last_actor_loss(self) -> float:
        """Actor loss of the latest actor update (NaN before the first)."""
        return float(self.latest_actor_loss)

    def update(self, batch: TensorDictBase, settings: StageSettings | None = None,
               stage_update: int = 0) -> dict[str, torch.Tensor]:
        """One TD3 update (`cyberdog.rl.td3.update`) with a stage's `settings` (default: the agent's own)."""
        return td3.update(self, batch, settings or StageSettings.of(self.cfg), stage_update)

    def set_anchor(self) -> None:
        """Freeze a copy of the actor as it is now: what `StageSettings.actor_anchor` pulls toward."""
        self.anchor = self.actor_net.detached_copy()

    def begin_stage(self, anchor: bool, fresh_actor_optimizer: bool) -> None:
        """A stage starts: with `anchor`, the actor as it is now is what `StageSettings.actor_anchor` pulls toward
        (`set_anchor`); with `fresh_actor_optimizer`, the actor's Adam moments are dropped (its learning rate is
        set by each update, `StageSettings.actor_lr`)."""
        if anchor:
            self.set_anchor()
        if fresh_actor_optimizer:
            self.actor_optimizer = _adam(self._actor_tensors, self.actor_optimizer.param_groups[0]["lr"])

    # ---- checkpoint state (tensors and plain containers only) ----
    def _networks(self) -> dict[str, Net]:
        """The networks under the names of TorchRL's loss modules, which held them in earlier versions (so that
        their checkpoints load): actor, critic(s) and their targets."""
        critic = "qvalue_network" if self.twin else "value_network"
        return {"actor_network": self.actor_net, "target_actor_network": self.target_actor, critic: self.critic,
                f"target_{critic}": self.target_critic}

    def network_state(self) -> dict[str, torch.Tensor]:
        """Every network's tensors, flat: "actor_network_params.module.net.0.weight", ... (detached, not copies)."""
        return {f"{group}_params.{name}": t.detach() for group, net in self._networks().items()
                for name, t in net.named().items()}

    def load_network_state(self, state: dict[str, torch.Tensor]) -> None:
        """Copy `network_state`'s tensors in place (other keys, e.g. an earlier version's loss constants, are
        ignored)."""
        with torch.no_grad():
            for name, t in self.network_state().items():
                t.copy_(state[name])

    def state_dict(self) -> dict:
        return {"loss": self.network_state(), "actor_optimizer": self.actor_optimizer.state_dict(),
                "critic_optimizer": self.critic_optimizer.state_dict(), "exploration": self.policy.state_dict(),
                "updates": self.updates, "actor_updates": self.actor_updates,
                **({"anchor": self.anchor.named()} if self.anchor is not None else {})}

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

    def load_state_dict(self, state: dict, optimizers: bool = True) -> None:
        self.load_network_state(state["loss"])
        if not optimizers:
            return
        self.actor_optimizer.load_state_dict(state["actor_optimizer"])
        self.critic_optimizer.load_state_dict(state["critic_optimizer"])
        for opt in (self.actor_optimizer, self.critic_optimizer):  # a checkpoint may predate fused Adam
            for group in opt.param_groups:
                group["fused"], group["foreach"] = opt.defaults.get("fused"), opt.defaults.get("foreach")
        self.policy.load_state_dict(state["exploration"])
        self.updates, self.actor_updates = int(state["updates"]), int(state["actor_updates"])
        if "anchor" in state:  # a stage pulled toward the actor it started from: the same actor after a resume
            self.anchor = self.actor_net.detached_copy()
            with torch.no_grad():
                for name, t in self.anchor.named().items():
                    t.copy_(state["anchor"][name])


def _on(net: Net, device: torch.device) -> Net:
    """`net` with its tensors on `device` (trained tensors stay parameters)."""
    if all(t.device == device for t in net.named().values()):
        return net
    return Net([(nn.Parameter(w.detach().to(device)), nn.Parameter(b.detach().to(device))) for w, b in net.layers],
               net.scale.to(device))


__all__ = ["Agent", "NonFiniteError", "StageSettings", "action_spec", "make_exploration", "metrics_to_float"]
