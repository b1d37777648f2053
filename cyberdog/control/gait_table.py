"""The trot as a joint table, and a joint table played to the motor drivers.

`gait_table` writes one gait period of the trot controller's command (`TrotController.command`: the foot path,
IK, joint speed feedforward, stance gravity compensation, the PID's gains) at a chosen frame rate, in steady
state: the commanded speed reached (no start-up ramp), the learned path's shift whole, and no body feedback. The
feedback the closed-loop trot runs on is replaced by constants: the speed integral by `speed_correction` (m/s
added to the stride's speed) and the heading loop's input by `heading_error` (rad: yaw + lateral_gain × lateral
offset), e.g. the values a closed-loop walk settles to (`cyberdog.analysis.gait_export.settled_command`); the
sideways and sagittal foot placement, which act on the body's speed, are left out. The stance feedforward's leg
Jacobian is taken at the frame's joint targets (the closed-loop trot takes it at the measured angles).

`TablePlayer` is a command source for `cyberdog.loop.walker.Walker` in the trot controller's place: at the
walker's period k it sends the table's frame k (modulo the period), so the table's rate must be the walker's
controller rate (`SimConfig.controller_dt` = 1 / rate). Pure numpy.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from cyberdog.config import WalkConfig
from cyberdog.control.trot import BodyFeedback, TrotController
from cyberdog.core.drivers import JointCommand
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.joint_table import JointTable
from cyberdog.core.trajectories import FootTrajectory


def frames_per_period(period: float, rate: float) -> int:
    """The frames of one gait period (s) at `rate` (Hz); ValueError unless the period is a whole number of them."""
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"rate must be > 0 Hz, got {rate!r}")
    n = int(round(period * rate))
    if n < 1 or abs(n - period * rate) > 1e-6:
        raise ValueError(f"rate {rate:g} Hz does not divide the gait period {period:g} s into whole frames "
                         f"(period × rate = {period * rate:g}); choose a rate that does, e.g. {round(n / period):g}")
    return n


def gait_table(cfg: WalkConfig, speed: float, rate: float, trajectory: FootTrajectory | None = None,
               foot_offsets: FootOffsetPath | None = None, speed_correction: float = 0.0,
               heading_error: float = 0.0, header: dict | None = None) -> JointTable:
    """One gait period of the trot's command at `speed` (m/s), `rate` frames per second (module docstring): the
    trot of `cfg` with `trajectory` (None: `cfg.gait`'s) and `foot_offsets` (a learned path's shift, or None)."""
    if not (np.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be > 0 m/s, got {speed!r}")
    n = frames_per_period(cfg.gait.period, rate)
    steady = dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, speed=float(speed)),
                                 controller=dataclasses.replace(cfg.controller, speed_ramp_time=0.0))
    controller = TrotController(steady, trajectory, foot_offsets)
    controller.reset()
    controller.speed_correction = float(speed_correction)
    body = BodyFeedback(yaw=float(heading_error))  # no forward speed: the integral stays at speed_correction
    rows = []
    for k in range(n):
        t = k / rate
        q_target = controller.targets(t, body).joint_angles.tolist()
        c = controller.command(t, q_target, body)  # the stance feedforward at the targets
        rows.append((c.q_target, c.dq_target, c.kp, c.kd, c.feedforward))
    q, dq, kp, kd, tau_ff = (np.array([r[i] for r in rows]) for i in range(5))
    return JointTable(float(rate), q, dq, kp, kd, tau_ff, header=dict(header or {}))


class TablePlayer:
    """A joint table played to the drivers by `Walker`, repeating its period (module docstring). It has what the
    walker asks of a controller: `command`, `reset`, and the records of a speed loop and a foot shift, which a
    table has not (zero, None)."""

    speed_correction = 0.0  # m/s: no speed loop
    speed_correction_limit = 0.0
    dropped_shifts = 0
    last_foot_targets = last_foot_offsets = None

    def __init__(self, table: JointTable):
        self.table = table
        self.rate = table.rate
        self._commands = [table.command(k) for k in range(table.frames)]
        self._frames = table.frames

    def reset(self, kp_factor: float = 1.0, kd_factor: float = 1.0) -> None:
        """A robot drawn with other gains (`RandomizationConfig`) runs the table's gains × the factors."""
        if kp_factor == 1.0 and kd_factor == 1.0:
            self._commands = [self.table.command(k) for k in range(self._frames)]
            return
        self._commands = [c._replace(kp=[g * kp_factor for g in c.kp], kd=[g * kd_factor for g in c.kd])
                          for c in (self.table.command(k) for k in range(self._frames))]

    def frame_at(self, t: float) -> int:
        """The table's frame at time t (s) since the reset."""
        return int(round(t * self.rate)) % self._frames

    def command(self, t: float, q=None, body=None, periods: int = 1, dq=None) -> JointCommand:
        """The frame of time t (s); the joint and body state are not read (the table is open loop)."""
        return self._commands[int(round(t * self.rate)) % self._frames]


__all__ = ["TablePlayer", "frames_per_period", "gait_table"]
