"""One scripted walk: the trot controller drives the simulated CyberDog; energy and gait metrics are recorded.

This is the experiment behind `evaluate.py baselines` and the trajectory comparison (paper Section 4.1):
walk `duration` seconds at the commanded speed, integrate Eq. (7) over every physics step (the motor drivers
close their PD at that rate on the controller's held command), and report speed, drift, posture and energy.

The prototype experiment (Section 4.2, `cyberdog.analysis.prototype`) adds two options: `distance` ends the
walk after that much forward travel (the paper's 100 m; `duration` is then the time cap), and `hardware`
(a `HardwareConfig`) makes the robot hardware-like: joint friction, actuation latency, encoder noise,
Kalman-estimated speed feedback and a mass-scale draw (`cyberdog.sim.hardware_model`). Without them the walk
is exactly the ideal one. The stepping itself is `cyberdog.loop.walker.Walker`'s, the same as the env's.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cyberdog.config import HardwareConfig, WalkConfig
from cyberdog.control.trot import TrotController
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.kinematics import UnreachableFootTarget
from cyberdog.core.trajectories import FootTrajectory
from cyberdog.loop.result import WalkResult, walk_result
from cyberdog.loop.walker import Walker
from cyberdog.sim.robot import Robot


def _check_walk(duration: float, distance: float | None, hardware, run_up: float) -> None:
    """`walk`'s arguments, refused before the robot is built."""
    if not (duration > 0 and np.isfinite(duration)):
        raise ValueError(f"duration must be > 0 s and finite, got {duration!r}")
    if distance is not None and not (distance > 0 and np.isfinite(distance)):
        raise ValueError(f"distance must be None or > 0 m and finite, got {distance!r}")
    if hardware is not None and not isinstance(hardware, HardwareConfig):
        raise TypeError(f"hardware must be a HardwareConfig or None, got {type(hardware).__name__}")
    if not (0.0 <= run_up < duration):
        raise ValueError(f"run_up must be >= 0 s and shorter than duration ({duration!r} s), got {run_up!r}")


def walk(cfg: WalkConfig, duration: float = 10.0, trajectory: FootTrajectory | None = None,
         robot: Robot | None = None, record: bool = False, hardware: HardwareConfig | None = None,
         distance: float | None = None, foot_offsets: FootOffsetPath | None = None, run_up: float = 0.0,
         progress: Callable[[float, float], None] | None = None) -> WalkResult:
    """Walk at `cfg.gait.speed` with the trot controller; reuse `robot` if given.

    duration: s; the walk's length, or with `distance` its time cap.
    distance: m of forward travel (body x from the start) after which the walk ends; None = a timed walk.
    foot_offsets: a periodic shift of each foot target over its phase (a learned path's, see
        `cyberdog.core.foot_offsets`) added to `trajectory`'s targets; None = the plain trajectory.
    hardware: the hardware-like robot (HardwareConfig; None or HardwareConfig() = ideal). With friction on,
        a given `robot` must have been built with `hardware_walk_config(cfg, hardware).actuator`; its mass is
        set to the hardware's draw for the walk.
    record: keep the traces (t, tau, dq, power, q, base_position, contacts) in the result.
    run_up: s walked first and left out of the result's time, distance, energies and speed (the start from a
        stand: the speed ramp and the blend into a learned path); `distance` counts from its end, `duration`
        (the time cap) includes it. A fall in the run-up is the walk's fall.
    progress: called with (s walked, m travelled from the start) after every simulated second, so that a long
        walk (100 m is minutes of wall time on a loaded machine) can report that it is alive.

    The walk ends as a fall when the body falls (`Walker.fallen`) or when the trot asks for a foot target beyond
    the leg's reach (`UnreachableFootTarget`: a robot going down can make it step too far).
    """
    _check_walk(duration, distance, hardware, run_up)
    with Walker(cfg, TrotController(cfg, trajectory, foot_offsets), robot=robot, hardware=hardware,
                record=record, gait_metrics=True) as walker:
        n_steps = int(round(duration / walker.dt))
        run_up_steps = int(round(run_up / walker.dt))
        since, since_x, goal_x = 0, None, None
        steps_per_second = max(1, int(round(1.0 / walker.dt)))
        start_x = float(walker.state.base_position[0]) if progress is not None else 0.0
        fell = False
        for k in range(n_steps):
            if k == run_up_steps:  # the measured walk starts here
                since, x = k, float(walker.state.base_position[0])
                since_x = x if k > 0 else None
                goal_x = None if distance is None else x + distance
            if goal_x is not None and walker.state.base_position[0] >= goal_x:
                break  # the energy of exactly the steps that carried the body to the goal
            try:
                walker.step()
            except UnreachableFootTarget:  # the trot asks for a foot beyond the leg's reach: the robot is going down
                fell = True
                break
            if walker.fallen():
                fell = True
                break
            if progress is not None and (k + 1) % steps_per_second == 0:
                progress((k + 1) * walker.dt, float(walker.state.base_position[0]) - start_x)
        result = walk_result(walker, walker.controller.speed, fell, target_distance=distance, since=since,
                             since_x=since_x)
    if not record:
        result.traces = {}
    return result


__all__ = ["WalkResult", "walk"]
