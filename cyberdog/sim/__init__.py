"""The simulator layer: the only package that imports a physics engine (pybullet, mujoco)."""
from cyberdog.config import ActuatorConfig, RobotConfig, SimConfig
from cyberdog.sim.engine import EngineRobot
from cyberdog.sim.robot import Robot, RobotState


def make_robot(robot: RobotConfig, actuator: ActuatorConfig, sim: SimConfig, gui: bool = False) -> EngineRobot:
    """The robot in the engine `sim.engine` names: PyBullet's `Robot` or MuJoCo's `MujocoRobot` (imported only
    when asked for)."""
    if sim.engine == "mujoco":
        from cyberdog.sim.mujoco_robot import MujocoRobot
        return MujocoRobot(robot, actuator, sim, gui=gui)
    return Robot(robot, actuator, sim, gui=gui)


__all__ = ["EngineRobot", "Robot", "RobotState", "make_robot"]
