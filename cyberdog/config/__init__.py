"""Every setting of the project as typed, frozen dataclasses, with units, loaded from and saved to YAML.

SI units everywhere (m, kg, s, rad, N·m, J). The robot's numbers and their sources are in `docs/robot.md` ([X]
Xiaomi's open-source controller files, [SPEC] marketing spec, [G] guess); paper numbers cite "Yan, Ji & Chang
2024, Actuators 13:18" by table or equation.

Every dataclass checks its own values in `__post_init__` and raises `ValueError` naming the field and the
allowed range, so that bad input fails before any long work starts.

The settings live in these modules: `walk_settings` (one scripted walk on the paper's ideal robot: robot, actuator,
sim, gait, PID, controller, energy), `hardware` (sensors, the hardware model, domain randomisation), `env`
(reward and environment), `learning` (agent, training, experiment), `schedule` (when a training updates),
`preset` (a recipe: `base:`, phases, extraction), `walked` (a walk config with its hardware model, as one file)
and `io` (YAML and overrides); everything is re-exported here, so `from cyberdog import config as C;
C.EnvConfig()` works.
"""
from cyberdog.config.io import add_override_option, from_dict, override, replace, save, to_dict  # noqa: F401
from cyberdog.config.env import *  # noqa: F401,F403
from cyberdog.config.env import STAGE1_REWARD, STAGE2_REWARD  # noqa: F401
from cyberdog.config.learning import *  # noqa: F401,F403
from cyberdog.config.learning import stage_reward  # noqa: F401
from cyberdog.config.walk_settings import *  # noqa: F401,F403
from cyberdog.config.hardware import *  # noqa: F401,F403
from cyberdog.config.schedule import *  # noqa: F401,F403
from cyberdog.config.walked import *  # noqa: F401,F403
from cyberdog.config.preset import (Phase, Preset, changed_settings, current_run, describe, final_run,  # noqa: F401
                                    is_lineage, load, load_preset, phase_names, read_phases, write_phases)
