"""The tasks `import cyberdog` registers with gymnasium: the one the shipped agents learn, and the paper's MDP.

- `CyberDog-v0`, the shipped agents' task (`configs/table5.yaml`'s stage 2): the action shifts the trot
  controller's foot targets (foot mode, ±3 cm per axis), the observation appends the previous action (62),
  the commanded speed is drawn per episode from 1.0–1.4 m/s, and the reward is Eq. 10 with the presets'
  keep-moving bonus D = 300 and Eq. 11's energy weight E = −0.2 per J: walking scores above falling.
- `CyberDogPaper-v0`, the paper's MDP as written (Section 3, Tables 3–4): the action is the 12 joint torques
  (×25 N·m), the observation Table 3's 50, the reward Eq. 11. Its every term but the keep-moving bonus is a
  penalty, so a robot that falls at once scores above one that walks: trained from scratch, an agent learns
  to fall (docs/training.md, the torque recipe); `gym.make` says so unless a reward is passed.

Both are `CyberDogEnv` (its docstring is the specification; `CyberDogEnv()` is `CyberDog-v0`), 400 steps of 25 ms
(Table 4). A `config` passed to `gym.make` is taken as it is, its reward included (the task's settings then do
not apply); keyword options change single fields.
"""
from __future__ import annotations

import warnings

from cyberdog import config as C
from cyberdog.envs.cyberdog_env import TASK_REWARD, CyberDogEnv

SHIPPED_TASK = C.EnvConfig()  # the dataclass defaults are this task's
SHIPPED_REWARD = TASK_REWARD
PAPER_TASK = C.EnvConfig(action_mode="torque", action_scale=25.0, observe_last_action=False,  # Table 3's 50
                         target_speed_range=())  # a fixed command
PAPER_TASK_WARNING = (
    "CyberDogPaper-v0 is the paper's MDP: with Eq. 11's reward every term but the keep-moving bonus (D = 25) is a "
    "penalty, so a robot that falls at once scores above one that walks, and an agent trained on it from scratch "
    "learns to fall (docs/training.md, the torque recipe). Pass reward= to choose another (e.g. reward='stage1', or "
    "RewardConfig(keep_moving=...)); CyberDog-v0 is the task the shipped agents learn")


def shipped_task(config: C.EnvConfig | None = None, reward=None, render_mode=None, **overrides) -> CyberDogEnv:
    """`CyberDog-v0`: `CyberDogEnv` itself, whose defaults are this task (module docstring)."""
    return CyberDogEnv(config, reward, render_mode, **overrides)


def paper_task(config: C.EnvConfig | None = None, reward=None, render_mode=None, **overrides) -> CyberDogEnv:
    """`CyberDogPaper-v0`: the paper's MDP (module docstring); `config` replaces its settings."""
    if reward is None:
        warnings.warn(PAPER_TASK_WARNING, UserWarning, stacklevel=3)
    return CyberDogEnv(PAPER_TASK if config is None else config, C.STAGE2_REWARD if reward is None else reward,
                       render_mode, **overrides)


__all__ = ["PAPER_TASK", "PAPER_TASK_WARNING", "SHIPPED_REWARD", "SHIPPED_TASK", "paper_task", "shipped_task"]
