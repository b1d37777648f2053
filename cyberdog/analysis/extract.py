"""Extraction of the learned foot path from a policy rollout (paper Section 3, after Figure 6): the commanded
path, and what both ways of extraction share. Numpy only.

Two ways, reported side by side:

- **commanded** (`extract_commanded`, here: the default for foot-mode policies): the trot controller's foot
  targets are what the policy changed, and the rollout records them at the physics rate (the base trot path
  plus the policy's shift of each foot). The rollout is cut into gait-clock cycles (each leg's phase runs once;
  the cycle opens at LF's lift-off); the settled cycles within ±5 % of the command are kept, and the shift of
  each leg over its phase is averaged over them (`cycle="mean"`, the default) or taken from the cheapest one
  (`cycle="cheapest"`, the paper's choice). The result, a `CommandedPath`, replays through IK + PID with no
  policy in the loop. Each leg keeps its own path: the policy shifts the four feet differently.
  Measured on the shipped 1.0 m/s policy (10 s rollout): settled cycles cost 39.81 J on average (cheapest
  39.28 J); replaying the mean path costs 39.98 J per cycle (+0.4 %), the cheapest cycle's path 39.94 J
  (+1.7 % over that cycle): the cheapest cycle is cheap by noise, not by a better path, hence the default.
- **measured** (`cyberdog.analysis.extract_measured.extract_trajectory`, the paper's way): the feet's
  measured path, forward kinematics of the recorded joint angles, of the cheapest cycle. Replayed as a new
  target through IK + PID it applies the tracking lag and stance wiggles a second time, and loses most of the
  saving.

Both cut a rollout into gait cycles (`Cycle`: its Eq. (7) energy and speed), raise `ExtractionError` when no
cycle qualifies, and record the rollout in the path's provenance (`rollout_provenance`); `cycle_rows` tabulates
the cycles of either.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from cyberdog.config import FOOT_MODES, GaitConfig
from cyberdog.config.paper import SPEED_BAND, speed_within_band
from cyberdog.core import energy as en
from cyberdog.core.commanded_path import CommandedPath
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.gait import GaitScheduler

SPEED_TOLERANCE = SPEED_BAND  # ± share of the command (the acceptance band of every walk); the CLIs' default
CYCLE_CHOICES = ("mean", "cheapest")  # how extract_commanded builds the path from the in-band cycles


class ExtractionError(ValueError):
    """No gait cycle of the rollout qualifies (too short, fell, no cycle in the speed band, ...)."""


@dataclass
class Cycle:
    """One gait cycle of the reference leg: touch-down to the next touch-down."""

    index: int  # 0, 1, ... in time order
    start: int  # sample index of the touch-down that opens it
    end: int  # sample index of the next touch-down (exclusive)
    lift_off: int  # sample index of the lift-off inside the cycle, -1 if none
    t_start: float  # s
    duration: float  # s
    energy: float  # J, Eq. (7) over all 12 joints
    speed: float  # m/s, forward body displacement / duration
    speed_ok: bool  # within the tolerance of the command
    valid: bool  # usable: settled, one lift-off, plausible duration
    reason: str = ""  # why not valid ("" when valid)

    def row(self) -> dict:
        return {"cycle": self.index, "t_start_s": self.t_start, "duration_s": self.duration,
                "energy_J": self.energy, "speed_mps": self.speed, "speed_ok": self.speed_ok,
                "valid": self.valid, "reason": self.reason}


def cycle_speed(base_x: np.ndarray, start: int, end: int, dt: float) -> float:
    """m/s, forward displacement of the body from sample `start` to sample `end` over (end − start)·dt.
    `end` may be one past the last sample (then the last one is used: the rollout's end)."""
    end_x = base_x[min(end, len(base_x) - 1)]
    n = min(end, len(base_x) - 1) - start
    return float(end_x - base_x[start]) / (n * dt) if n > 0 else float("nan")


def rollout_provenance(rollout, env_config, provenance: dict | None = None) -> dict:
    """What an extracted trajectory records of the rollout it came from: its walk, the trot controller it walked
    under (`controller`, e.g. with foot placement) and a warning if it fell."""
    prov = {"rollout_mean_speed_mps": rollout.mean_speed, "rollout_fell": bool(rollout.fell),
            "rollout_duration_s": rollout.duration, "rollout_energy_J": rollout.energy,
            "action_mode": env_config.action_mode, "controller": asdict(env_config.walk.controller),
            **(provenance or {})}
    if rollout.fell:
        prov["warning"] = f"the rollout fell after {rollout.duration:.2f} s"
    return prov


@dataclass
class CommandedExtraction:
    """What `extract_commanded` found: every gait-clock cycle, those used, and the path built from them."""

    path: CommandedPath
    cycles: list[Cycle]
    used: list[int]  # indices of the cycles the path was built from
    energy: float  # J, the mean Eq. (7) energy of the used cycles (the closed-loop figure to reproduce)


def clock_cycles(traces: dict, dt: float, speed_command: float, period: float, speed_tolerance: float =
                 SPEED_TOLERANCE, settle_time: float = 2.0) -> list[Cycle]:
    """The rollout cut into whole gait-clock cycles [k·T, (k+1)·T) (LF lifts off at each start), each with its
    Eq. (7) energy and speed; valid after `settle_time` s (the 1 s speed ramp and the controller's speed
    integral settle first)."""
    per = int(round(period / dt))
    n = len(traces["tau"])
    power = en.mechanical_power(traces["tau"], traces["dq"]).sum(axis=1)
    base_x = np.asarray(traces["base_position"], dtype=float)[:, 0]
    cycles = []
    for k in range(n // per):
        a, b = k * per, (k + 1) * per
        speed = cycle_speed(base_x, a, b, dt)
        settled = a * dt >= settle_time - 1e-9
        cycles.append(Cycle(index=k, start=a, end=b, lift_off=a, t_start=a * dt, duration=per * dt,
                            energy=float(power[a:b].sum() * dt), speed=speed,
                            speed_ok=speed_within_band(speed, speed_command, speed_tolerance),
                            valid=settled, reason="" if settled else f"before settle time {settle_time:g} s"))
    return cycles


def extract_commanded(traces: dict, dt: float, speed_command: float, gait: GaitConfig, cycle: str = "mean",
                      speed_tolerance: float = SPEED_TOLERANCE, settle_time: float = 2.0,
                      provenance: dict | None = None) -> CommandedExtraction:
    """The policy's commanded foot path (see the module docstring) from a rollout's traces: t, tau, dq
    (n, 12), base_position (n, 3) and foot_offsets (n, 4, 3) m at the physics rate dt (s), with the trot the
    policy's controller ran (`gait`: base trajectory, period, swing time, lift height). The offset table has
    one sample per controller period of a cycle. Raises ExtractionError when no settled cycle is in the band."""
    if cycle not in CYCLE_CHOICES:
        raise ValueError(f"cycle must be one of {CYCLE_CHOICES}, got {cycle!r}")
    if not (np.isfinite(speed_command) and speed_command > 0):
        raise ValueError(f"speed_command must be > 0 m/s, got {speed_command!r}")
    if "foot_offsets" not in traces:
        raise ExtractionError("the rollout has no recorded foot targets (foot_offsets): roll it out with "
                              "cyberdog.rl.rollout.rollout")
    offsets = np.asarray(traces["foot_offsets"], dtype=float)
    if not np.all(np.isfinite(offsets)):
        raise ExtractionError("the recorded foot offsets are not finite (a torque-mode policy commands no foot "
                              "path: use the measured-path extraction)")
    cycles = clock_cycles(traces, dt, speed_command, gait.period, speed_tolerance, settle_time)
    usable = [c for c in cycles if c.valid and c.speed_ok]
    if not usable:
        speeds = ", ".join(f"{c.speed:.3f}" for c in cycles if c.valid) or "none"
        raise ExtractionError(f"no settled gait cycle within ±{speed_tolerance:.0%} of {speed_command:g} m/s "
                              f"({len(cycles)} cycles; speeds after {settle_time:g} s (m/s): {speeds})")
    used = usable if cycle == "mean" else [min(usable, key=lambda c: c.energy)]
    # the cycles are whole gait-clock periods, so sample j of every cycle is at the same phase of each leg:
    # average them sample by sample, then order each leg's samples by its phase
    per = used[0].end - used[0].start
    mean_offsets = np.mean([offsets[c.start:c.end] for c in used], axis=0)  # (per, 4, 3)
    # a foot_torque policy's joint torque, tabulated the same way (the path's own feedforward); none when zero
    torque = np.asarray(traces.get("joint_torque", np.zeros((len(offsets), 12))), dtype=float)
    mean_torque = (np.mean([torque[c.start:c.end] for c in used], axis=0).reshape(per, 4, 3) if torque.any()
                   else None)
    first = used[0]
    phases = GaitScheduler.from_config(gait).leg_phases(np.asarray(traces["t"], dtype=float)[first.start:first.end])
    table = FootOffsetPath.from_samples(phases, mean_offsets, gait.period, per, mean_torque)
    energy = float(np.mean([c.energy for c in used]))
    prov = {"source": "cyberdog.analysis.extract.extract_commanded", "path": "commanded", "cycle": cycle,
            "speed_command_mps": float(speed_command), "cycles_total": len(cycles),
            "cycles_in_band": len(usable), "cycles_used": [c.index for c in used],
            "cycle_energy_J": energy, "cycle_speed_mps": float(np.mean([c.speed for c in used])),
            "speed_tolerance": float(speed_tolerance), "settle_time_s": float(settle_time),
            "offset_rms_mm": np.round(1e3 * table.rms(), 3).tolist(), "controller_dt_s": float(dt),
            **({} if table.feedforward is None else
               {"feedforward_rms_Nm": np.round(np.sqrt(np.mean(table.feedforward ** 2, axis=1)), 3).tolist()}),
            **(provenance or {})}
    path = CommandedPath(float(speed_command), gait, table, prov)
    return CommandedExtraction(path, cycles, [c.index for c in used], energy)


def commanded_from_rollout(rollout, env_config, cycle: str = "mean", speed_tolerance: float = SPEED_TOLERANCE,
                           settle_time: float = 2.0, provenance: dict | None = None) -> CommandedExtraction:
    """`extract_commanded` on a policy rollout (a WalkResult of `cyberdog.rl.rollout.rollout`) in `env_config`."""
    if env_config.action_mode not in FOOT_MODES:
        raise ExtractionError(f"a policy of action_mode {env_config.action_mode!r} commands no foot path; "
                              "use the measured-path extraction")
    prov = rollout_provenance(rollout, env_config, provenance)
    return extract_commanded(rollout.traces, rollout.trace_dt, rollout.speed_command, env_config.walk.gait,
                             cycle, speed_tolerance, settle_time, prov)


def cycle_rows(extraction) -> list[dict]:
    """One row per cycle (CSV-ready) of an extraction of either way (`CommandedExtraction`,
    `extract_measured.Extraction`), the cycles it used marked as chosen."""
    return [{**c.row(), "chosen": c.index in extraction.used} for c in extraction.cycles]


__all__ = ["CYCLE_CHOICES", "CommandedExtraction", "Cycle", "ExtractionError", "SPEED_TOLERANCE", "clock_cycles",
           "commanded_from_rollout", "cycle_rows", "cycle_speed", "extract_commanded", "rollout_provenance"]
