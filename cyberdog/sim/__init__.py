"""The simulator layer: the only package that imports pybullet."""
from cyberdog.sim.robot import Robot, RobotState

__all__ = ["Robot", "RobotState"]
