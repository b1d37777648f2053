#!/usr/bin/env python3
"""Can a torque held over the agent step walk the CyberDog at all? The trot controller as a torque policy.

The paper's agent chooses the 12 joint torques every Ts = 25 ms and they are held in between (Table 3). Before
training one, this asks what the best-known torque law does under that constraint: the trot controller
(trajectory + IK + PD + feedforward) evaluated once per agent step at the state then read, its torque held over
the step, exactly what `CyberDog-v0` applies in torque mode with the trot prior at weight 1 and a zero action.
Swept over the agent step Ts and the motor drivers' damping c (−c·q̇ at every 2.5 ms controller period,
`EnvConfig.joint_damping`, motor torque that Eq. 7 books), at the commanded speeds, one 10 s walk each from the
stand on the ideal robot. Printed and written to --out (held_trot.md, held_trot.json).

    python notebook/tools/held_trot_study.py --out runs/held_trot
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from cyberdog.analysis.parallel import map_in_processes, progress_log
from cyberdog.analysis.report import json_safe, markdown_table


def held_walk(job: tuple) -> dict:
    """One walk: (Ts s, damping N·m·s/rad, speed m/s, duration s) → a row."""
    from cyberdog import config as C
    from cyberdog.envs.cyberdog_env import CyberDogEnv

    control_dt, damping, speed, duration = job
    t0 = time.perf_counter()
    env = CyberDogEnv(C.EnvConfig(action_mode="torque", control_dt=control_dt, joint_damping=damping,
                                  prior_weight=1.0, target_speed=speed, episode_time=duration), reward="stage1")
    env.reset(seed=0)
    speeds, energy, fell = [], 0.0, False
    for _ in range(int(round(duration / control_dt))):
        _, _, fell, _, info = env.step(np.zeros(12))
        speeds.append(info["forward_speed"])
        energy += info["step_energy_J"]
        if fell:
            break
    walked = env.t
    env.close()
    half = speeds[len(speeds) // 2:]
    return {"Ts_ms": 1e3 * control_dt, "damping_Nms_per_rad": damping, "speed_command_mps": speed,
            "fell": fell, "walked_s": walked, "mean_speed_mps": float(np.mean(half)) if not fell else float("nan"),
            "energy_J": energy, "wall_s": time.perf_counter() - t0}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ts-ms", type=float, nargs="+", default=[5.0, 10.0, 25.0], help="agent steps Ts (ms)")
    p.add_argument("--damping", type=float, nargs="+", default=[0.0, 2.0, 3.0], help="drivers' damping (N·m·s/rad)")
    p.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.4], help="m/s")
    p.add_argument("--duration", type=float, default=10.0, help="s per walk (default 10)")
    p.add_argument("--workers", type=int, default=None, help="processes (default: the CPUs)")
    p.add_argument("--out", type=Path, required=True, help="folder for held_trot.md and held_trot.json")
    args = p.parse_args(argv)
    if any(t < 2.5 or abs(t / 2.5 - round(t / 2.5)) > 1e-9 for t in args.ts_ms):
        p.error(f"--ts-ms must be whole multiples of the 2.5 ms controller period, got {args.ts_ms}")
    if any(c < 0 for c in args.damping) or any(v <= 0 for v in args.speeds) or args.duration <= 0:
        p.error("--damping must be >= 0, --speeds and --duration > 0")
    jobs = [(t / 1e3, c, v, args.duration) for t in args.ts_ms for c in args.damping for v in args.speeds]
    print(f"{len(jobs)} walks of {args.duration:g} s: the trot's torque held over Ts", flush=True)

    def line(r: dict) -> str:
        return (f"Ts {r['Ts_ms']:g} ms, c {r['damping_Nms_per_rad']:g}, {r['speed_command_mps']:g} m/s: "
                f"{'fell at %.2f s' % r['walked_s'] if r['fell'] else '%.3f m/s' % r['mean_speed_mps']}")

    rows = map_in_processes(held_walk, jobs, args.workers, on_result=progress_log(len(jobs), line))
    md = markdown_table([{k: v for k, v in r.items() if k != "wall_s"} for r in rows])
    print(md)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "held_trot.md").write_text(md + "\n")
    (args.out / "held_trot.json").write_text(json.dumps(json_safe(rows), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
