"""A foot path exported as the joint table a robot's drivers play, and that table replayed in the simulator.

`make_gait_table` writes one gait period of the trot's command (`cyberdog.control.gait_table.gait_table`) for a
foot path (a learned path's `walk_args`, a searched shape, a common trajectory) at a frame rate (500 Hz: the
CyberDog motor SDK's). The table is open loop: nothing in it reads the body. With `settle` (the default) it is the
trot's steady-state command: a closed-loop walk of the same path at the same rate first (`settled_command`), and
the table carries the speed integral and heading-loop input that walk settles to (their means over its last
half). Without it the table is the command with no correction at all, which walks slower and turns
(docs/evaluation.md, "export").

`replay_table` plays a table to the simulated drivers through the one simulation loop (`Walker` with a
`TablePlayer` in the trot's place), repeating its period, and reports the walk (`WalkResult`) with the speed
band, the fall, the heading it ended at and its speed over ground (an open-loop table turns: its forward speed
then falls short of its speed over ground). `load_limits` reads a limits file (configs/robots/cyberdog_limits.yaml).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cyberdog.config import PIDConfig, WalkConfig
from cyberdog.config.paper import SPEED_BAND, speed_within_band
from cyberdog.control.gait_table import TablePlayer, gait_table
from cyberdog.control.trot import TrotController
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.joint_table import JointLimitError, JointLimits, JointTable
from cyberdog.core.kinematics import UnreachableFootTarget
from cyberdog.core.trajectories import FootTrajectory
from cyberdog.loop.result import WalkResult, walk_result
from cyberdog.loop.walker import Walker
from cyberdog.provenance import portable_path

SETTLE_DURATION = 10.0  # s, the closed-loop walk whose last half's mean command the table carries


def table_walk_config(cfg: WalkConfig, rate: float, table: JointTable | None = None) -> WalkConfig:
    """`cfg` with the controller at `rate` (Hz: one table frame per period) and the physics step the largest whole
    fraction of that period at most `cfg`'s; with `table`, the PD gains set to its largest per joint type
    (the walker chooses the drivers' physics step for the gains: `driver_rate_config`)."""
    controller_dt = 1.0 / rate
    physics_dt = controller_dt / math.ceil(controller_dt / cfg.sim.physics_dt - 1e-9)
    out = dataclasses.replace(cfg, sim=dataclasses.replace(cfg.sim, controller_dt=controller_dt,
                                                           physics_dt=physics_dt))
    if table is not None:
        kp = tuple(float(table.kp[:, j::3].max()) for j in range(3))
        kd = tuple(float(table.kd[:, j::3].max()) for j in range(3))
        out = dataclasses.replace(out, pid=PIDConfig(kp=kp, kd=kd))
    return out


@dataclass(frozen=True)
class SettledCommand:
    """What the closed-loop trot's feedback settles to, walking a path: its means over the walk's last half."""

    speed_correction: float  # m/s, the speed integral added to the stride's speed
    heading_error: float  # rad, the heading loop's input: yaw + lateral_gain × lateral offset
    mean_speed: float  # m/s, of the closed-loop walk (its last half)
    fell: bool
    duration: float  # s

    def summary(self) -> dict:
        return {"speed_correction_mps": self.speed_correction, "heading_error_rad": self.heading_error,
                "closed_loop_mean_speed_mps": self.mean_speed, "closed_loop_fell": self.fell,
                "closed_loop_duration_s": self.duration,
                "taken_as": "means over the last half of a closed-loop walk of the same trot at the table's rate"}


def settled_command(cfg: WalkConfig, speed: float, rate: float, trajectory: FootTrajectory | None = None,
                    foot_offsets: FootOffsetPath | None = None, duration: float = SETTLE_DURATION) -> SettledCommand:
    """The closed-loop trot of `cfg` walks the path at `speed` (m/s) for `duration` s at `rate` (Hz) on the ideal
    robot from a stand; the means of its speed integral and heading-loop input over the last half."""
    walk_cfg = dataclasses.replace(table_walk_config(cfg, rate), gait=dataclasses.replace(cfg.gait, speed=speed))
    fell = False
    with Walker(walk_cfg, TrotController(walk_cfg, trajectory, foot_offsets), record=True) as walker:
        for _ in range(int(round(duration / walker.dt))):
            try:
                walker.step()
            except UnreachableFootTarget:
                fell = True
            if fell or walker.fallen():
                fell = True
                break
        half = walker.steps // 2
        correction = walker.speed_loop.view(half)[:, 0]
        yaw = walker.body.view(half)[:, 3]
        lateral = walker.traces()["base_position"][half:, 1] - walker.start[1]
        heading = yaw + walk_cfg.controller.lateral_gain * lateral
        mean_speed = float(walker.body.view(half)[:, 0].mean()) if walker.steps else 0.0
    return SettledCommand(float(correction.mean()), float(heading.mean()), mean_speed, fell, walker.steps * walker.dt)


def make_gait_table(cfg: WalkConfig, speed: float, rate: float, trajectory: FootTrajectory | None = None,
                    foot_offsets: FootOffsetPath | None = None, settle: bool = True,
                    header: dict | None = None) -> tuple[JointTable, SettledCommand | None]:
    """(the table, the settled command it carries or None): module docstring. ValueError where the closed-loop
    walk it settles on falls (the trot does not walk this path at this speed)."""
    settled = settled_command(cfg, speed, rate, trajectory, foot_offsets) if settle else None
    if settled is not None and settled.fell:
        raise ValueError(f"the closed-loop trot fell walking this path at {speed:g} m/s ({rate:g} Hz), so it has no "
                         f"steady-state command to export; --no-settle exports the uncorrected command")
    table = gait_table(cfg, speed, rate, trajectory, foot_offsets,
                       speed_correction=settled.speed_correction if settled else 0.0,
                       heading_error=settled.heading_error if settled else 0.0)
    g, c = cfg.gait, cfg.controller
    table.header.update({
        "speed_mps": float(speed), "gait_period_s": g.period, "swing_time_s": g.swing_time,
        "lift_height_m": g.lift_height, "trajectory": g.trajectory if trajectory is None else "sampled",
        "phase_offsets": list(g.phase_offsets), "trot_controller": dataclasses.asdict(c),
        "settled_command": settled.summary() if settled else None,
        "open_loop": "no body feedback: the speed loop, the heading loop and the foot placement do not act; "
                     + ("the table carries the speed and heading corrections the closed-loop trot settled to "
                        "(settled_command)" if settled else "the table carries no correction"),
        "start": "frame 0 is the trot's phase 0 (LF lifts off); the replay plays it from the standing pose",
        **(header or {})})
    return table, settled


@dataclass
class TableReplay:
    """A joint table replayed in the simulator (`replay_table`)."""

    result: WalkResult
    final_yaw: float  # rad, the body's heading when the walk ended
    rate: float  # Hz
    ground_speed: float  # m/s, the mean horizontal speed |v_xy| over the walk's last half, whatever the heading

    def summary(self) -> dict:
        r = self.result
        return {"duration_s": r.duration, "rate_hz": self.rate, "speed_command_mps": r.speed_command,
                "mean_speed_mps": r.mean_speed, "mean_speed_share_of_command": r.mean_speed / r.speed_command,
                "ground_speed_mps": self.ground_speed,
                "speed_band": SPEED_BAND, "in_band": bool(speed_within_band(r.mean_speed, r.speed_command)),
                "fell": r.fell, "lateral_drift_m": r.lateral_drift, "final_yaw_rad": self.final_yaw,
                "energy_J": r.energy, "electrical_energy_J": r.electrical_energy, "distance_m": r.distance,
                "mean_speed_over": "the walk's last half, forward (world x)", "robot": "ideal"}

    def line(self) -> str:
        s = self.summary()
        band = "within" if s["in_band"] else "outside"
        return (f"replay: {s['duration_s']:g} s at {s['speed_command_mps']:g} m/s: mean speed "
                f"{s['mean_speed_mps']:.3f} m/s ({100 * (s['mean_speed_share_of_command'] - 1):+.1f} %, {band} "
                f"±{100 * SPEED_BAND:g} %), {'fell' if s['fell'] else 'no fall'}, lateral drift "
                f"{s['lateral_drift_m']:.2f} m, heading at the end {math.degrees(s['final_yaw_rad']):+.0f} deg, speed "
                f"over ground {s['ground_speed_mps']:.3f} m/s")


def replay_table(table: JointTable, cfg: WalkConfig, speed: float, duration: float = 10.0) -> TableReplay:
    """Play `table` to the simulated drivers of the ideal robot of `cfg` (its robot, actuator, sim: the controller
    at the table's rate) from a stand for `duration` s, repeating its period; `speed` (m/s) is the command it is
    judged against. The walk ends early at a fall."""
    if not (duration > 0 and np.isfinite(duration)):
        raise ValueError(f"duration must be > 0 s and finite, got {duration!r}")
    walk_cfg = table_walk_config(cfg, table.rate, table)
    fell, ground = False, []
    with Walker(walk_cfg, TablePlayer(table), gait_metrics=True) as walker:
        for _ in range(int(round(duration / walker.dt))):
            walker.step()
            ground.append(math.hypot(*walker.reading.base_linear_velocity_world[:2]))
            if walker.fallen():
                fell = True
                break
        result = walk_result(walker, float(speed), fell)
        final_yaw = float(walker.state.base_rpy[2])
    result.traces = {}
    return TableReplay(result, final_yaw, table.rate, float(np.mean(ground[len(ground) // 2:])))


def load_limits(path: str | Path | None = None) -> JointLimits:
    """The limits in the YAML file `path` (configs/robots/cyberdog_limits.yaml's keys); None: the CyberDog's
    built-in ones (`JointLimits.cyberdog`, the same values). JointLimitError naming the file and the key."""
    if path is None:
        return JointLimits.cyberdog()
    import yaml

    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as err:
        raise JointLimitError(f"limits file {portable_path(path)} is unreadable: {err}") from None
    return JointLimits.from_dict(data, source=portable_path(path))


__all__ = ["SETTLE_DURATION", "SettledCommand", "TableReplay", "load_limits", "make_gait_table", "replay_table",
           "settled_command", "table_walk_config"]
