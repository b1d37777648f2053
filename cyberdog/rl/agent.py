"""The learning agent: TorchRL loss (TD3 or DDPG), target updates, optimizers, exploration and one update.

`Agent.update(batch)` is one gradient step of the critic(s); the actor and the target networks are updated
on every `policy_delay`-th call for TD3 (Fujimoto et al. 2018) and on every call for DDPG. TD3's clipped
double-Q and target-policy smoothing live inside `torchrl.objectives.TD3Loss`.
"""
from __future__ import annotations

import math

import torch
from tensordict import TensorDictBase
from tensordict.nn import TensorDictSequential
from torchrl.data import Bounded
from torchrl.modules import AdditiveGaussianModule, OrnsteinUhlenbeckProcessModule
from torchrl.objectives import DDPGLoss, SoftUpdate, TD3Loss

from cyberdog.config import AgentConfig
from cyberdog.envs.cyberdog_env import observation_typical_magnitude
from cyberdog.rl.networks import make_actor, make_critic


class NonFiniteError(RuntimeError):
    """A loss, Q-value or action became NaN or infinite."""


def action_spec(action_size: int, device: torch.device | str = "cpu") -> Bounded:
    return Bounded(-1.0, 1.0, shape=(action_size,), dtype=torch.float32, device=device)


def make_loss(cfg: AgentConfig, observation_size: int, action_size: int):
    """Actor, critic, the loss module holding them and their targets, and the soft target updater."""
    scale = observation_typical_magnitude() if observation_size == len(observation_typical_magnitude()) else None
    actor = make_actor(observation_size, action_size, cfg.hidden_sizes, scale)
    critic = make_critic(observation_size, action_size, cfg.hidden_sizes, scale)
    if cfg.algorithm == "td3":
        loss = TD3Loss(actor, critic, action_spec=action_spec(action_size), num_qvalue_nets=2,
                       policy_noise=cfg.policy_noise, noise_clip=cfg.noise_clip, loss_function="l2",
                       delay_actor=True, delay_qvalue=True)
    else:
        loss = DDPGLoss(actor, critic, loss_function="l2", delay_actor=True, delay_value=True)
    loss.make_value_estimator(gamma=cfg.gamma)
    return actor, loss, SoftUpdate(loss, tau=cfg.tau)


def critic_parameters(loss) -> list[torch.nn.Parameter]:
    params = loss.qvalue_network_params if isinstance(loss, TD3Loss) else loss.value_network_params
    return list(params.flatten_keys().values())


def actor_parameters(loss) -> list[torch.nn.Parameter]:
    return list(loss.actor_network_params.flatten_keys().values())


def make_optimizers(cfg: AgentConfig, loss) -> tuple[torch.optim.Adam, torch.optim.Adam]:
    """Separate Adam optimizers (Table 4: actor 4e-4, critic 2e-3)."""
    return (torch.optim.Adam(actor_parameters(loss), lr=cfg.actor_lr),
            torch.optim.Adam(critic_parameters(loss), lr=cfg.critic_lr))


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


def _finite(name: str, value: torch.Tensor) -> None:
    if not torch.isfinite(value).all():
        raise NonFiniteError(f"{name} is not finite (NaN or inf); training stopped")


class Agent:
    """Loss, optimizers and the update schedule of one TD3 or DDPG agent."""

    def __init__(self, cfg: AgentConfig, observation_size: int, action_size: int, device: str = "cpu"):
        self.cfg = cfg
        self.device = torch.device(device)
        self.actor, self.loss, self.target_updater = make_loss(cfg, observation_size, action_size)
        self.loss.to(self.device)
        self.actor_optimizer, self.critic_optimizer = make_optimizers(cfg, self.loss)
        self.policy = make_exploration(cfg, self.actor, action_size).to(self.device)
        self.policy_delay = cfg.policy_delay if cfg.algorithm == "td3" else 1
        self.updates = 0  # critic updates done
        self.actor_updates = 0  # actor (and target) updates done
        self.last_actor_loss = math.nan

    def _step(self, optimizer: torch.optim.Optimizer, loss: torch.Tensor, params) -> None:
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        if self.cfg.max_grad_norm > 0:
            torch.nn.utils.clip_grad_norm_(params, self.cfg.max_grad_norm)
        optimizer.step()

    def update(self, batch: TensorDictBase) -> dict[str, float]:
        """One critic update; actor + soft target update every `policy_delay`-th call. Returns metrics."""
        batch = batch.to(self.device)
        if isinstance(self.loss, TD3Loss):
            value_loss, meta = self.loss.value_loss(batch)
        else:
            value_loss, meta = self.loss.loss_value(batch)
        q = meta["pred_value"].detach()
        _finite("critic loss", value_loss)
        _finite("Q-value", q)
        self._step(self.critic_optimizer, value_loss, critic_parameters(self.loss))
        self.updates += 1
        if self.updates % self.policy_delay == 0:
            if isinstance(self.loss, TD3Loss):
                actor_loss, _ = self.loss.actor_loss(batch)
            else:
                actor_loss, _ = self.loss.loss_actor(batch)
            _finite("actor loss", actor_loss)
            self._step(self.actor_optimizer, actor_loss, actor_parameters(self.loss))
            self.target_updater.step()
            self.actor_updates += 1
            self.last_actor_loss = float(actor_loss.detach())
        return {"critic_loss": float(value_loss.detach()), "actor_loss": self.last_actor_loss,
                "q_mean": float(q.mean()), "q_max": float(q.max())}

    # ---- checkpoint state (tensors and plain containers only) ----
    def state_dict(self) -> dict:
        return {"loss": self.loss.state_dict(), "actor_optimizer": self.actor_optimizer.state_dict(),
                "critic_optimizer": self.critic_optimizer.state_dict(), "exploration": self.policy.state_dict(),
                "updates": self.updates, "actor_updates": self.actor_updates}

    def load_state_dict(self, state: dict, optimizers: bool = True) -> None:
        self.loss.load_state_dict(state["loss"])
        if optimizers:
            self.actor_optimizer.load_state_dict(state["actor_optimizer"])
            self.critic_optimizer.load_state_dict(state["critic_optimizer"])
            self.policy.load_state_dict(state["exploration"])
            self.updates, self.actor_updates = int(state["updates"]), int(state["actor_updates"])
