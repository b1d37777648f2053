#!/usr/bin/env python3
"""Env steps per second of the env that users train (the shipped preset's), against the engine's floor.

Both run in this process on the same machine, timed in CPU time (time.process_time: on a shared machine the
wall clock counts the time other processes held the CPU) and in wall-clock time:

  env    CyberDog-v0 as configs/table5.yaml builds it (foot mode, 62 observations, stage-2 reward), at
         the config's controller rate; zero action, episodes restarted where they end. Its joint controller
         runs every `walk.sim.controller_dt`; the motor drivers close their PD at every physics step
         (`walk.sim.physics_dt`), one engine step each, in the engine `--engine` names (default the
         preset's: PyBullet).
  floor  raw PyBullet at 1 kHz, as a controller at the physics rate would drive it: the project's URDF in the
         same world, and at every 1 ms physics step the state reads a controller needs (getJointStates,
         getBasePositionAndOrientation, getBaseVelocity), one torque write (setJointMotorControlArray) and
         stepSimulation. The torque is a joint PD about the standing pose (one numpy expression), so that the
         robot stands on its four feet as a walking robot's contacts load the solver; a robot left without
         torque lies on the ground, where the solver runs about half as fast. 25 physics steps make one
         agent-step equivalent (Ts = 25 ms).

The ratio env / floor above 1 means that the env, with its controller, hardware model, reward and
observation, runs faster than bare PyBullet can be stepped from Python at 1 kHz (the floor is PyBullet's
whatever the env's engine). Several repetitions; the medians are printed.

    python bench/env_throughput.py [--steps 400] [--repeats 5] [--config configs/table5.yaml] [--engine mujoco]
                                   [--set env.walk.sim.controller_dt=0.001 env.walk.sim.physics_dt=0.001]
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
import pybullet

from cyberdog import config as C
from cyberdog.config.preset import load_preset
from cyberdog.config.walk_settings import ENGINES
from cyberdog.core.kinematics import standing_joint_angles
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.sim.robot import Robot

ROOT = Path(__file__).resolve().parents[1]
FLOOR_DT = 0.001  # s, the physics step of the floor
AGENT_DT = 0.025  # s, Ts: physics steps per agent-step equivalent = AGENT_DT / FLOOR_DT
PD_GAINS = (60.0, 2.0)  # N·m/rad, N·m·s/rad: the trot's PID gains (PIDConfig), holding the standing pose


def env_config(path: str, sets: list[str]) -> C.EnvConfig:
    """The env of a preset (its `base:` resolved), with `--set` overrides."""
    return load_preset(ROOT / path if not Path(path).is_absolute() else path, sets).config.env


def time_env(env: CyberDogEnv, steps: int, seed: int) -> tuple[float, float]:
    """(wall s, CPU s) of `steps` env steps with zero action from a reset."""
    env.reset(seed=seed)
    action = np.zeros(12, dtype=np.float32)
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        if env.step(action)[2]:
            env.reset()
    return time.perf_counter() - t0, time.process_time() - c0


def time_floor(robot: Robot, steps: int) -> tuple[float, float]:
    """(wall s, CPU s) of `steps` agent-step equivalents of raw PyBullet at 1 kHz (see the docstring)."""
    c, body, joints = robot.client, robot.body_id, robot.joint_ids
    c.setPhysicsEngineParameter(fixedTimeStep=FLOOR_DT, numSubSteps=0)
    robot.reset()
    q_stand = standing_joint_angles(robot.robot_config).ravel()
    kp, kd = PD_GAINS
    get_joints, get_pose, get_velocity = c.getJointStates, c.getBasePositionAndOrientation, c.getBaseVelocity
    set_motors, step, torque_control = c.setJointMotorControlArray, c.stepSimulation, pybullet.TORQUE_CONTROL
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps * round(AGENT_DT / FLOOR_DT)):
        states = get_joints(body, joints)
        get_pose(body)
        get_velocity(body)
        q = np.array([s[0] for s in states])
        dq = np.array([s[1] for s in states])
        set_motors(body, joints, torque_control, forces=(kp * (q_stand - q) - kd * dq).tolist())
        step()
    return time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=400, help="env steps per repetition (default 400 = one episode)")
    p.add_argument("--repeats", type=int, default=5, help="repetitions (default 5)")
    p.add_argument("--config", default="configs/table5.yaml", help="the preset whose env is timed "
                   "(default configs/table5.yaml, the shipped policies')")
    p.add_argument("--set", nargs="+", default=[], metavar="SECTION.FIELD=VALUE",
                   help="overrides of the preset, e.g. env.walk.sim.controller_dt=0.001 (default: none)")
    p.add_argument("--engine", choices=ENGINES, default=None,
                   help="the env's physics engine (env.walk.sim.engine; default the preset's)")
    args = p.parse_args()
    cfg = env_config(args.config, args.set + ([f"env.walk.sim.engine={args.engine}"] if args.engine else []))
    sim = cfg.walk.sim
    print(f"env: {args.config} in {sim.engine}, action_mode={cfg.action_mode}, "
          f"controller {1 / sim.controller_dt:.0f} Hz, "
          f"physics {1 / sim.physics_dt:.0f} Hz ({sim.physics_substeps} substeps); floor: PyBullet at 1 kHz")
    env = CyberDogEnv(cfg, reward="stage2")
    walk = C.EnvConfig().walk
    floor_robot = Robot(walk.robot, walk.actuator, walk.sim)
    env_times, floor_times = [], []  # (wall, cpu) per repetition
    n = args.steps
    for i in range(args.repeats):
        env_times.append(time_env(env, n, seed=i))
        floor_times.append(time_floor(floor_robot, n))
        (ew, ec), (fw, fc) = env_times[-1], floor_times[-1]
        print(f"rep {i}: env {n / ec:7.1f} env steps/s (wall {n / ew:7.1f})   floor {n / fc:7.1f} agent-step "
              f"equivalents/s (wall {n / fw:7.1f})", flush=True)
    env.close()
    floor_robot.close()
    for label, k in (("CPU time", 1), ("wall clock", 0)):
        te = statistics.median(t[k] for t in env_times)
        tf = statistics.median(t[k] for t in floor_times)
        print(f"[{label}] median env: {n / te:.1f} env steps/s; floor: {n / tf:.1f} agent-step equivalents/s; "
              f"env / floor = {tf / te:.2f}")


if __name__ == "__main__":
    main()
