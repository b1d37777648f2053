"""What the walk books from the rows the loop keeps: Eq. (7), the positive work, the electrical energy and the
per-step traces (`Walker`'s energy and trace readers).

Over a physics step the torque is constant, so the joint's work is exactly τ·Δq: Eq. (7) is
Σ_k |τ_k·Δq_k| = Σ_k |τ_k·ω̄_k|·h per joint over the physics steps k (h = `SimConfig.physics_dt`, ω̄ = Δq / h,
the speed PyBullet reports after the step: tests/test_drivers.py). The electrical energy takes the same τ_k
and ω̄_k. The per-period rows (`tau`, `traces`) are the periods' means of the physics steps'.
"""
from __future__ import annotations

import numpy as np

from cyberdog.core import energy as en


class WalkBooks:
    """The readers of a walk's rows, mixed into `cyberdog.loop.walker.Walker`, which keeps the rows: `physics_tau`
    (the motor torque applied over each physics step, N·m), `physics_q` (joint angles at the reset and after
    each physics step, rad), `q_rows` and `tau` (their per-period views), `_traces` (with `record`), and
    `substeps`, `physics_dt`, `dt`, `cfg`."""

    def joint_speeds(self, since: int = 0) -> np.ndarray:
        """(n, 12) rad/s, each step's mean joint speed Δq / dt from step `since` on; computed from the joint-angle
        rows when asked."""
        q = self.q_rows.view(since)
        return (q[1:] - q[:-1]) * (1.0 / self.dt)

    def physics_traces(self, since: int = 0) -> dict:
        """Every physics step's t (s since the reset), tau (the motor torque applied over it, N·m) and dq (the
        joint's mean speed over it, Δq / physics_dt, rad/s), from controller period `since` on: what Eq. (7) and
        the electrical energy integrate."""
        n = self.substeps
        q = self.physics_q.view(since * n)
        tau = self.physics_tau.view(since * n)
        return {"t": (np.arange(len(tau)) + since * n) * self.physics_dt, "tau": tau,
                "dq": (q[1:] - q[:-1]) * (1.0 / self.physics_dt)}

    def energy_per_joint(self, since: int = 0) -> np.ndarray:
        """(12,) J, Eq. (7) Σ_k |τ_k·Δq_k| per joint over the physics steps from controller period `since` on."""
        p = self.physics_traces(since)
        return en.joint_energy(p["tau"], p["dq"], self.physics_dt)

    def energy(self, since: int = 0) -> float:
        """J, Eq. (7) Σ∫|τ·ω|dt = Σ_k |τ_k·Δq_k| over the physics steps from controller period `since` to now."""
        return float(self.energy_per_joint(since).sum())

    def positive_work(self, since: int = 0) -> float:
        """J, Σ∫max(τ·ω, 0)dt over the physics steps from controller period `since` on."""
        p = self.physics_traces(since)
        return en.positive_work(p["tau"], p["dq"], self.physics_dt)

    def electrical_energy(self, since: int = 0) -> float:
        """J drawn from the battery over the physics steps from controller period `since` (copper loss,
        friction, driver)."""
        c, p = self.cfg, self.physics_traces(since)
        return float(np.sum(en.electrical_power(p["tau"], p["dq"], c.actuator, c.energy))) * self.physics_dt

    def traces(self) -> dict:
        """Every step's t, tau (its mean motor torque), dq (its mean joint speed), power (its mean of |τ·ω| over
        its physics steps, so that Σ power·dt is Eq. 7) per joint (and with `record`: q, base_position,
        contacts, foot_targets, foot_offsets, feedforward: the drivers' τ_ff, joint_torque: a policy's added to it),
        arrays with the step as the first axis."""
        tau, dq, p = self.tau.view(), self.joint_speeds(), self.physics_traces()
        power = np.abs(p["tau"] * p["dq"]).reshape(len(tau), self.substeps, 12).mean(axis=1)
        out = {"t": np.arange(len(tau)) * self.dt, "tau": tau, "dq": dq, "power": power}
        if self._traces:  # with `record`: q at each step's start is the joint-angle rows but the last
            out["q"] = self.q_rows.view()[:-1]
        out.update({name: rows.view() for name, rows in self._traces.items()})
        return out
