#!/usr/bin/env python3
"""Where does a learned path save, and where does a doubled damping cost it? Energy and the drivers' terms by phase.

For a commanded path (its own trot), the composite cycloid at the path's lift and the trot's own path (the searched
shape the battery recipe starts from, `--start`), each walked under the gains asked (`--gains KP:KD` factors of the
configured PD), this splits the electrical energy per joint type (abad, hip, knee) into the legs' stance and swing
(by each leg's gait phase), and gives the RMS of the motor torque and of the drivers' law's three terms at the
controller periods: kp·e (e = q_des − q), kd·ė (ė = q̇_des − q̇) and the command's feedforward (stance gravity
compensation), each per joint type in stance, for the command as computed (before the hardware-like robot's latency)
and the true joint state. 12 s walked, the first 3 s left out.

    python notebook/tools/stance_terms.py results/battery_searched_pick/paths/seed20_1.2mps.json --gains 1:1 1:2

Finding: notebook/2026-12-07_trajectory_actor.md ("Where the saving and the kd 2× loss sit").
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from cyberdog.config import HARDWARE_LIKE, WalkConfig
from cyberdog.control.trot import TrotController
from cyberdog.core import energy as en
from cyberdog.core.learned_set import LearnedSet
from cyberdog.core.trajectories import SampledTrajectory
from cyberdog.evaluation.learned import load_learned
from cyberdog.evaluation.recorded_trot import recorded_trot, with_trot
from cyberdog.loop.walker import Walker

JOINT_TYPES = ("abad", "hip", "knee")
WALK_S, RUN_UP_S = 12.0, 3.0
START = Path("results/searched_shapes/optimized_trajectory_H0.085_electrical_hardware_placed_loop.json")


def by_joint_type(values: np.ndarray, mask: np.ndarray, dt: float) -> list[float]:
    """Σ values·dt over the rows where `mask` holds, per joint type (values, mask: (n, 12), legs × abad/hip/knee)."""
    return (en.per_joint_type((values * mask).sum(axis=0)) * dt).tolist()


def rms_by_joint_type(values: np.ndarray, mask: np.ndarray) -> list[float]:
    """RMS of `values` over the entries where `mask` holds, per joint type ((n, 12) each); nan where none holds."""
    out = []
    for j in range(3):
        m = mask[:, j::3]
        out.append(float(np.sqrt((values[:, j::3] ** 2 * m).sum() / m.sum())) if m.any() else float("nan"))
    return out


def swing_mask(controller: TrotController, times) -> np.ndarray:
    """(n, 12) True where the joint's leg is in swing at each time (s), by the trot's gait clock."""
    beta = controller.scheduler.gait.swing_fraction
    phases = np.array([controller.scheduler.phases_at(float(t)) for t in times])
    return np.repeat(phases < beta, 3, axis=1)


def walk_terms(cfg: WalkConfig, trajectory, offsets, hardware) -> dict:
    """One walk's split: electrical energy J per joint type in stance and swing, J/m, and the stance RMS terms."""
    controller = TrotController(cfg, trajectory, offsets)
    commands = []
    command = controller.command

    def recording(*args, **kwargs):
        c = command(*args, **kwargs)
        commands.append((c.q_target, c.dq_target, c.feedforward, c.kp, c.kd))
        return c

    controller.command = recording
    with Walker(cfg, controller, hardware=hardware) as w:
        n, since = int(round(WALK_S / w.dt)), int(round(RUN_UP_S / w.dt))
        q, dq, fell, x0 = [], [], False, None
        for k in range(n):
            if k == since:
                x0 = float(w.state.base_position[0])
            q.append(list(w.reading.q))
            dq.append(list(w.reading.dq))
            w.step()
            if w.fallen():
                fell = True
                break
        if x0 is None:
            raise RuntimeError(f"the walk fell in its {RUN_UP_S:g} s run-up: nothing to split")
        distance = float(w.state.base_position[0]) - x0
        p = w.physics_traces(since)
        power = en.electrical_joint_power(p["tau"], p["dq"], w.cfg.actuator, w.cfg.energy)
        swing_p = swing_mask(controller, p["t"])
        steps = len(commands)
        tau = np.array([w.tau.view(i)[0] for i in range(since, steps)])
        q_t, dq_t, ff, kp, kd = (np.array([c[i] for c in commands[since:]]) for i in range(5))
        e, e_rate = q_t - np.array(q[since:steps]), dq_t - np.array(dq[since:steps])
        stance = ~swing_mask(controller, np.arange(since, steps) * w.dt)
        return {"fell": fell, "distance_m": distance,
                "electrical_J_per_m": float(power.sum() * w.physics_dt / distance),
                "stance_J": by_joint_type(power, ~swing_p, w.physics_dt),
                "swing_J": by_joint_type(power, swing_p, w.physics_dt),
                "stance_rms_Nm": {"torque": rms_by_joint_type(tau, stance), "kp_e": rms_by_joint_type(kp * e, stance),
                                  "kd_e_rate": rms_by_joint_type(kd * e_rate, stance),
                                  "feedforward": rms_by_joint_type(ff, stance)}}


def gains(text: str) -> tuple[float, float]:
    try:
        kp, kd = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"gains must be KP:KD factors, e.g. 1:2, got {text!r}") from None
    if not (kp > 0 and kd > 0):
        raise argparse.ArgumentTypeError(f"gain factors must be > 0, got {text!r}")
    return kp, kd


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("path", type=Path, help="a commanded path file (evaluate.py extract's learned/<label>_<v>mps.json)")
    ap.add_argument("--gains", type=gains, nargs="+", default=[(1.0, 1.0), (1.0, 2.0)],
                    help="kp:kd factors of the configured PD each walk runs under (default 1:1 1:2)")
    ap.add_argument("--start", type=Path, default=START,
                    help="the trot's own path, walked as a third gait (default: the battery recipe's start)")
    ap.add_argument("--robot", choices=("ideal", "hardware"), default="ideal",
                    help="the ideal robot or the prototype's hardware-like one (HARDWARE_LIKE)")
    args = ap.parse_args(argv)
    learned: LearnedSet = load_learned([args.path])
    path, = learned.paths()
    if not path.commanded:
        ap.error(f"{args.path} is a sampled path; this walks a commanded one (a policy's shift of its trot)")
    base = with_trot(WalkConfig(), recorded_trot(learned))
    cfg, _, offsets = path.walk_args(base, path.speed)
    matched = dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, trajectory="cycloid", sampled_file="",
                                                                lift_height=path.lift_height))
    start = SampledTrajectory.load(args.start)
    own = dataclasses.replace(cfg, gait=dataclasses.replace(cfg.gait, lift_height=start.lift_height))
    gaits = {"learned path": (cfg, None, offsets), "cycloid (its lift)": (matched, None, None),
             "the trot's own path": (own, start, None)}
    hardware = HARDWARE_LIKE if args.robot == "hardware" else None
    print(f"{args.path} at {path.speed:g} m/s, {args.robot} robot; electrical J per joint type "
          f"({' / '.join(JOINT_TYPES)}), stance RMS N·m")
    for name, (gait_cfg, trajectory, shift) in gaits.items():
        for kp_f, kd_f in args.gains:
            pid = gait_cfg.pid
            walked = dataclasses.replace(gait_cfg, pid=dataclasses.replace(
                pid, kp=tuple(g * kp_f for g in pid.kp), kd=tuple(g * kd_f for g in pid.kd)))
            r = walk_terms(walked, trajectory, shift, hardware)
            joules = lambda v: " / ".join(f"{x:.0f}" for x in v)  # noqa: E731
            torques = lambda v: " / ".join(f"{x:.2f}" for x in v)  # noqa: E731
            t = r["stance_rms_Nm"]
            print(f"{name:20s} kp {kp_f:g}× kd {kd_f:g}×: {r['electrical_J_per_m']:.1f} J/m"
                  f"{' FELL' if r['fell'] else ''} | stance {joules(r['stance_J'])} swing {joules(r['swing_J'])} | "
                  f"τ {torques(t['torque'])}, kp·e {torques(t['kp_e'])}, kd·ė {torques(t['kd_e_rate'])}, "
                  f"ff {torques(t['feedforward'])}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
