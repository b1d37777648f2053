"""Energy-minimising trot of the Xiaomi CyberDog (reproduction of Yan, Ji & Chang 2024, Actuators 13:18).

Importing the package registers two gymnasium tasks (Table 4: 400 steps of 25 ms): `CyberDog-v0`, the task
the shipped agents learn (foot targets, a reward under which walking beats falling), and `CyberDogPaper-v0`,
the paper's MDP (joint torques, Eq. 11). See `cyberdog.envs.registration` (imported by `gym.make` only: the
package itself stays light to import).
"""
import gymnasium as _gym

__version__ = "0.1.0"

for _task, _entry_point in (("CyberDog-v0", "cyberdog.envs.registration:shipped_task"),
                            ("CyberDogPaper-v0", "cyberdog.envs.registration:paper_task")):
    if _task not in _gym.registry:
        _gym.register(id=_task, entry_point=_entry_point, max_episode_steps=400)  # Table 4: 10 s of 25 ms
