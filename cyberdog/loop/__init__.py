"""The simulation loop: the one place where the robot is stepped under the trot controller at the physics
rate (`Walker`), and the one record of a walk (`WalkResult`). Used by the learning environment, the scripted
walks, the videos and the policy rollouts."""
from cyberdog.loop.result import WalkResult, walk_result  # noqa: F401
from cyberdog.loop.walker import FALL_HEIGHT, FALL_TILT, Walker  # noqa: F401
