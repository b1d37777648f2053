"""Joint actuator model: torque clip, torque–speed envelope and joint friction. No simulator.

PyBullet does not enforce the URDF effort or velocity limits under TORQUE_CONTROL (measured, see
`docs/robot.md`), so the limits of the CyberDog's actuators are applied here, in one place, before
the torque reaches the simulator.

Sources (`docs/robot.md`):
- torque command limit 25 N·m: the paper's Table 4 (Xiaomi's software limit is 23.9994 N·m [X]);
- torque–speed envelope: full torque up to n1 = 11.4145 rad/s, falling linearly to zero at n2 = 20.9136 rad/s
  (joint speed; `cyberdog.hpp` [X]); it limits the torque only while the motor drives the joint
  (motoring, τ·ω > 0); a braking torque (τ·ω < 0) is only clipped;
- joint friction: viscous 0.01 N·m·s/rad and dry (Coulomb) 0.246 N·m [X], off by default because the
  paper ignores it (its Section 2).
"""
from __future__ import annotations

import math

import numpy as np

from cyberdog.config import ActuatorConfig

DRY_FRICTION_SMOOTHING = 0.01  # rad/s: the Coulomb term is dry_friction · tanh(ω / this), smooth through 0


def joint_friction(joint_velocity, viscous: float, dry: float) -> np.ndarray:
    """The one joint-friction law, N·m, of magnitude b·ω + f·tanh(ω / 0.01 rad/s) and the sign of ω: what a
    joint moving at ω loses to friction (viscous b, N·m·s/rad; dry f, N·m [X] cyberdog.hpp). The simulated
    joint feels its negative (`ActuatorModel.joint_torque`); the electrical model adds it to what the motor
    must produce where the simulation leaves friction out (`cyberdog.core.energy.drive_torque`)."""
    omega = np.asarray(joint_velocity, dtype=float)
    return viscous * omega + dry * np.tanh(omega / DRY_FRICTION_SMOOTHING)


class ActuatorModel:
    """Turns joint torque commands into the torques the 12 actuators produce, and their friction.

    The law works on the 12 joints of one controller period, in floats; inputs are not modified.
    """

    def __init__(self, config: ActuatorConfig):
        self.config = config
        self.torque_limit = float(config.torque_limit)
        self._n1 = float(config.full_torque_speed)
        self._n2 = float(config.zero_torque_speed)
        self.set_scales()

    def set_scales(self, friction_scale: float = 1.0, strength: float = 1.0) -> None:
        """A drawn actuator (domain randomisation): joint friction × `friction_scale`, and the torque the
        motors produce × `strength` (after the clip and the envelope: a weaker or stronger motor for the same
        command). 1 and 1: the nominal actuator of the config."""
        if not (np.isfinite(friction_scale) and friction_scale >= 0 and np.isfinite(strength) and strength > 0):
            raise ValueError(f"friction scale must be >= 0 and strength > 0, got {friction_scale!r}, {strength!r}")
        self.friction_scale, self.strength = float(friction_scale), float(strength)

    def joint_torque(self, torque_command, joint_velocity) -> tuple[list, list]:
        """(motor torque, motor torque + friction torque), N·m, 12 floats each: what the motors produce for a
        command (12 numbers) at joint velocities ω (rad/s), and what acts on the joints.

        1. clip to ±torque_limit;
        2. if `torque_speed_curve`: where the motor drives the joint (τ·ω > 0), limit |τ| to the envelope:
           torque_limit up to full_torque_speed, linearly down to 0 at zero_torque_speed ([X] n1, n2); braking
           torques keep the clipped value;
        3. × `strength` (1 unless a drawn actuator, `set_scales`);
        4. the joint also feels −`joint_friction` (× the drawn `friction_scale`) when `friction` is on.

        In Python floats, joint by joint: for 12 joints this takes under 2 µs against about 16 µs for numpy,
        whose per-call overhead exceeds the arithmetic at this size (tests/oracles.py holds the array law that
        tests/test_fast_paths.py checks it against)."""
        limit, n1, n2 = self.torque_limit, self._n1, self._n2
        curve, inv_span = self.config.torque_speed_curve, 1.0 / (n2 - n1)
        motor = []
        for tau, omega in zip(torque_command, joint_velocity):
            if tau > limit:
                tau = limit
            elif tau < -limit:
                tau = -limit
            if curve and (omega > n1 or omega < -n1) and tau * omega > 0.0:  # motoring beyond full torque
                envelope = limit * min(max((n2 - abs(omega)) * inv_span, 0.0), 1.0)
                tau = envelope if tau > envelope else -envelope if tau < -envelope else tau
            motor.append(tau)
        if self.strength != 1.0:
            motor = [tau * self.strength for tau in motor]
        if not self.config.friction:
            return motor, motor
        k, tanh, smooth = self.friction_scale, math.tanh, DRY_FRICTION_SMOOTHING
        b, f = k * self.config.viscous_damping, k * self.config.dry_friction
        # `joint_friction` in floats
        return motor, [tau - (b * omega + f * tanh(omega / smooth)) for tau, omega in zip(motor, joint_velocity)]
