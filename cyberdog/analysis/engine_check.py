"""The two physics engines side by side, with no learned gait: a standing robot and the composite-cycloid trot.

- `stand`: the robot reset to its standing pose and held there by the trot controller's stance (`TrotStance`: its
  PD on the standing joint angles, at rest, with the stance gravity feedforward of four feet down), stepped by the
  walker for `duration` s; reports the mean joint torque, foot load, foot penetration (the foot sphere's centre below its radius) and body
  height over the second half.
- `cycloid_walks`: the trot controller's composite-cycloid walks (`cyberdog.analysis.walk.walk`) at each speed:
  mean speed, Eq. 7 and electrical J/m.

`python -m cyberdog.analysis.engine_check` prints both for PyBullet and MuJoCo (the calibration of the second
engine's contact, docs/design.md "The second engine").
"""
from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass

import numpy as np

from cyberdog.config import WalkConfig
from cyberdog.config.paper import PAPER_SPEEDS, PAPER_WALK_DURATION
from cyberdog.control.trot import TrotController
from cyberdog.core.drivers import JointCommand
from cyberdog.core.kinematics import add_stance_weight_torque, standing_joint_angles
from cyberdog.analysis.walk import walk
from cyberdog.loop.walker import Walker

ENGINE_NAMES = ("pybullet", "mujoco")


def on_engine(cfg: WalkConfig, engine: str) -> WalkConfig:
    """`cfg` with the physics engine `engine` (`SimConfig.engine`)."""
    return dataclasses.replace(cfg, sim=dataclasses.replace(cfg.sim, engine=engine))


@dataclass(frozen=True)
class Stand:
    """A standing robot's means over the second half of the stand."""

    joint_torque: np.ndarray  # (12,) N·m, motor torque applied
    foot_force: np.ndarray  # (4,) N, normal force of the ground on each foot
    penetration: np.ndarray  # (4,) m, foot radius − the foot-sphere centre's height (> 0: into the ground)
    body_height: float  # m, the body origin's height


class TrotStance:
    """The trot controller's stance held still, as a command source for `Walker`: its PD on the standing joint
    angles at zero speed, plus its stance feedforward with all four feet down at the joint angles read."""

    speed_correction = speed_correction_limit = 0.0  # m/s: no speed loop
    dropped_shifts = 0
    last_foot_targets = last_foot_offsets = None

    def __init__(self, cfg: WalkConfig):
        self.trot = TrotController(cfg)
        self.target = standing_joint_angles(cfg.robot).reshape(12).tolist()

    def reset(self, kp_factor: float = 1.0, kd_factor: float = 1.0) -> None:
        self.trot.reset(kp_factor, kd_factor)

    def command(self, t: float, q, body=None, periods: int = 1, dq=None) -> JointCommand:
        feedforward = [0.0] * 12
        add_stance_weight_torque(feedforward, list(q), [False] * 4, self.trot.robot, self.trot.body_weight)
        pid = self.trot.pid
        return JointCommand(self.target, [0.0] * 12, feedforward, pid.kp_list, pid.kd_list)


def stand(cfg: WalkConfig, duration: float = 2.0) -> Stand:
    """The robot of `cfg` (its engine) standing for `duration` s from a reset under `TrotStance` (module
    docstring)."""
    taus, forces, depths, heights = [], [], [], []
    with Walker(cfg, TrotStance(cfg), body_trace=False) as walker:
        periods = int(round(duration / walker.dt))
        for k in range(periods):
            tau = walker.step()
            if k >= periods // 2:
                taus.append(tau)
                forces.append(walker.robot.foot_contact_forces())
                depths.append(cfg.robot.foot_radius - walker.robot.foot_positions_world()[:, 2])
                heights.append(walker.reading.base_position[2])
    return Stand(np.mean(taus, axis=0), np.mean(forces, axis=0), np.mean(depths, axis=0), float(np.mean(heights)))


def cycloid_walks(cfg: WalkConfig, speeds=PAPER_SPEEDS, duration: float = PAPER_WALK_DURATION) -> list[dict]:
    """The composite-cycloid trot of `cfg` (its engine) at each speed: one row per walk (speed, band, J/m)."""
    rows = []
    for v in speeds:
        gait = dataclasses.replace(cfg.gait, trajectory="cycloid", speed=float(v))
        r = walk(dataclasses.replace(cfg, gait=gait), duration)
        rows.append({"engine": cfg.sim.engine, "speed_command_mps": float(v), "mean_speed_mps": r.mean_speed,
                     "in_band": r.speed_ok, "fell": r.fell, "eq7_J_per_m": r.energy_per_metre,
                     "electrical_J_per_m": r.electrical_energy / r.distance if r.distance > 0 else float("nan"),
                     "foot_slip_m_per_cycle": r.foot_slip_per_cycle, "non_foot_contacts": r.non_foot_contacts})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="The two physics engines side by side: a standing robot and the "
                                                 "composite-cycloid trot (no learned gait)")
    parser.add_argument("--duration", type=float, default=PAPER_WALK_DURATION, help="s per walk")
    parser.add_argument("--speeds", type=float, nargs="+", default=list(PAPER_SPEEDS), help="m/s")
    args = parser.parse_args(argv)
    cfg = WalkConfig()
    for engine in ENGINE_NAMES:
        s = stand(on_engine(cfg, engine))
        print(f"{engine:9s} stand: penetration {np.round(s.penetration * 1e3, 3)} mm, body {s.body_height:.4f} m, "
              f"foot load {np.round(s.foot_force, 1)} N\n{'':9s} torque {np.round(s.joint_torque, 3)} N·m")
    for engine in ENGINE_NAMES:
        for row in cycloid_walks(on_engine(cfg, engine), args.speeds, args.duration):
            print("  ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
