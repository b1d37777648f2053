"""The collecting policy: the actor followed by TorchRL's exploration noise (Gaussian or Ornstein–Uhlenbeck),
annealed over env steps. The trainer's collector and the asynchronous collector's worker build it alike."""
from __future__ import annotations

import torch
from tensordict.nn import TensorDictSequential
from torchrl.data import Bounded
from torchrl.modules import AdditiveGaussianModule, OrnsteinUhlenbeckProcessModule

from cyberdog.config import AgentConfig


def action_spec(action_size: int, device: torch.device | str = "cpu") -> Bounded:
    """Actions in [−1, 1] per entry (the env scales them)."""
    return Bounded(-1.0, 1.0, shape=(action_size,), dtype=torch.float32, device=device)


def make_exploration(cfg: AgentConfig, actor, action_size: int) -> TensorDictSequential:
    """`actor` followed by exploration noise (`cfg.exploration`), annealed over `cfg.exploration_annealing_steps`
    env steps from `exploration_sigma` to `exploration_sigma_end` (the trainer steps it per collected step)."""
    spec = action_spec(action_size)
    ratio = cfg.exploration_sigma_end / cfg.exploration_sigma if cfg.exploration_sigma else 1.0
    if cfg.exploration == "gaussian":  # std · sigma(t) · N(0, 1), sigma(t) annealed 1 → end/start
        noise = AdditiveGaussianModule(spec=spec, sigma_init=1.0, sigma_end=ratio, std=cfg.exploration_sigma,
                                       annealing_num_steps=cfg.exploration_annealing_steps)
    else:
        noise = OrnsteinUhlenbeckProcessModule(spec=spec, eps_init=1.0, theta=cfg.ou_theta,
                                               sigma=max(cfg.exploration_sigma, 1e-12), dt=cfg.ou_dt,
                                               annealing_num_steps=cfg.exploration_annealing_steps,
                                               eps_end=ratio)
    return TensorDictSequential(actor, noise)


__all__ = ["action_spec", "make_exploration"]
