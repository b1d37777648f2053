"""Energy-minimising trot of the Xiaomi CyberDog (reproduction of Yan, Ji & Chang 2024, Actuators 13:18).

Importing the package registers the gymnasium environment `CyberDog-v0` (Table 4: 400 steps of 25 ms).
"""
import gymnasium as _gym

__version__ = "0.1.0"

if "CyberDog-v0" not in _gym.registry:
    _gym.register(id="CyberDog-v0", entry_point="cyberdog.envs.cyberdog_env:CyberDogEnv", max_episode_steps=400)
