#!/usr/bin/env python
"""Do a torque policy's four feet move alike? Per foot, the cheapest in-band cycle of one 1.0 m/s rollout of
each shipped torque seed's stage-2 actor: its swing share, x range, lift and speed (the quantities a measured
path is made of, `cyberdog.analysis.extract_measured`).

    python notebook/tools/torque_feet.py 0 1 3     # seeds; about 5 s a seed
"""
from __future__ import annotations

import sys
from pathlib import Path

from cyberdog.analysis.extract import ExtractionError
from cyberdog.analysis.extract_measured import extract_from_rollout
from cyberdog.config import LEG_NAMES
from cyberdog.rl.rollout import load_actor, rollout

POLICY = Path("results/torque/policy")

for seed in sys.argv[1:] or ["0", "1", "2", "3", "4"]:
    actor = load_actor(POLICY / f"seed{seed}" / "stage2_actor.pt")
    r = rollout(actor, speed=1.0, duration=10.0, seed=0)
    for leg in LEG_NAMES:
        try:
            p = extract_from_rollout(r, actor.config.env, leg=leg).trajectory.provenance
        except ExtractionError as err:
            print(f"seed {seed} {leg}: {err}")
            continue
        print(f"seed {seed} {leg}: swing share {p['measured_swing_share']:.2f}, "
              f"x range {p['measured_x_range_m']:.3f} m, lift {p['measured_lift_height_m']:.3f} m, "
              f"cycle {p['cycle_index']} at {p['cycle_speed_mps']:.3f} m/s ({p['cycles_in_band']} cycles in the band)")
