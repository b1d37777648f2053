"""Walk a path under another joint PD as it walks under its own: its command re-solved for the new gains.

A foot path (a common trajectory, a searched shape, a learned commanded path) is a command: what the robot does
with it depends on the joint PD that follows it. A user who sets other gains than the path was made under (a
stiffer PD, `PIDConfig.stiffness_scaled`) and wants the path's gait keeps the *executed* motion and re-solves
the command for the new gains (`cyberdog.core.pd_match_solver`). Here that motion is recorded on the ideal robot
under the path's own PD (`RECORD_S` s, the first `SETTLE_S` s left out: the speed ramp and the blend into the
path) and averaged over its gait cycles; the answer is the path's foot shifts plus the change of command, a
`FootOffsetPath` the trot walks like any learned path's. The recording never uses the robots a comparison
reports on, and every trajectory of a comparison goes through it alike (`run_prototype(pd_matched=True)`).
"""
from __future__ import annotations

import hashlib
import pickle

import numpy as np

from cyberdog.analysis.walk import walk
from cyberdog.config import PIDConfig, WalkConfig
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler
from cyberdog.core.pd_match_solver import pd_matched_offsets
from cyberdog.core.trajectories import FootTrajectory

RECORD_S = 8.0  # s walked on the ideal robot under the path's own PD
SETTLE_S = 3.0  # s of it left out (the prototype's run-up: the speed ramp, the blend into a learned path)
PHASES = 100  # phases of the shift table for a trajectory that has none of its own (0.4 s cycle: 4 ms apart)

_cache: dict[str, FootOffsetPath | None] = {}  # per process: the draws of one comparison share their answer


def pd_matched_foot_offsets(cfg: WalkConfig, trajectory: FootTrajectory | None, offsets: FootOffsetPath | None,
                            new_pid: PIDConfig) -> FootOffsetPath | None:
    """The foot shifts that make (trajectory, offsets) walk under the joint PD `new_pid` as it walks under
    `cfg.pid`; `offsets` itself where the two are the same. `cfg` is the walk's config with the path's own PD
    (its trot, gait and speed). Raises RuntimeError if the recording walk falls."""
    if new_pid == cfg.pid:
        return offsets
    table = offsets if offsets is not None else FootOffsetPath(np.zeros((4, PHASES, 3)), cfg.gait.period)
    torque = None if table.feedforward is None else table.feedforward.tobytes()
    key = hashlib.sha256(pickle.dumps((cfg, trajectory, table.offsets.tobytes(), torque, table.period, new_pid)))
    key = key.hexdigest()
    if key in _cache:
        return _cache[key]
    result = walk(cfg, RECORD_S, trajectory, record=True, foot_offsets=table)  # the ideal robot
    if result.fell:
        raise RuntimeError(f"the recording walk for the PD-matched command fell at {result.duration:.1f} s "
                           f"(speed {cfg.gait.speed:g} m/s): the path has no executed motion to keep")
    traces = result.traces
    keep = traces["t"] >= SETTLE_S
    phases = GaitScheduler.from_config(cfg.gait).leg_phases(traces["t"][keep])
    matched = pd_matched_offsets(phases, traces["q"][keep], traces["foot_targets"][keep], table, cfg.pid, new_pid,
                                 cfg.robot, cfg.controller.velocity_feedforward)
    _cache[key] = matched
    return matched


__all__ = ["PHASES", "RECORD_S", "SETTLE_S", "pd_matched_foot_offsets"]
