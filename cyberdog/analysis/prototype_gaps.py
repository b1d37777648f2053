"""The prototype run's comparisons between walks: each walk's ideal-vs-hardware gap (`add_gaps`) and, per
trajectory, seed and speed, the battery saving against the cheaper common trajectory on each robot (`gap_rows`,
Eq. 12 on battery % per metre). Plain rows in, rows out; the walks are `cyberdog.analysis.prototype`'s."""
from __future__ import annotations

from cyberdog.core import energy as en


def _per_m(row: dict, key: str) -> float:
    return row[key] / row["distance_m"] if row["distance_m"] > 0 else float("nan")


def add_gaps(rows: list[dict]) -> list[dict]:
    """Fill in each row's ideal-vs-hardware gaps (%, per metre, so the few mm past the goal do not count):
    `electrical_gap_pct` = 100·(E_el,hw − E_el,ideal)/E_el,ideal, `mechanical_gap_pct` likewise for Eq. (7),
    a hardware row against the ideal walk of its trajectory, seed and speed (an ideal row against draw 0);
    NaN where the row has no partner of the other robot. Returns the same rows."""
    index = {(r["trajectory"], r.get("seed", ""), r["speed_mps"], r["robot"], r.get("draw", 0)): r for r in rows}
    for r in rows:
        key = (r["trajectory"], r.get("seed", ""), r["speed_mps"])
        ideal = index.get((*key, "ideal", 0))
        hw = index.get((*key, "hardware", r.get("draw", 0) if r["robot"] == "hardware" else 0))
        for k, gap in (("electrical_energy_J", "electrical_gap_pct"), ("energy_J", "mechanical_gap_pct")):
            r[gap] = (100.0 * (_per_m(hw, k) / _per_m(ideal, k) - 1.0)
                      if ideal is not None and hw is not None else float("nan"))
    return rows


COMMON_TRAJECTORIES = ("cycloid", "straight")  # the reference of every reduction: the cheaper of these two


def gap_rows(rows: list[dict]) -> list[dict]:
    """Per trajectory, seed and speed: the ideal robot against the first hardware-like one (draw 0), and the
    Eq. (12) battery saving on each (the across-seed and across-draw means are in
    `cyberdog.analysis.prototype_summary`).

    Every reduction is against one reference, the cheaper common trajectory (`COMMON_TRAJECTORIES`) of the same
    seed and speed on the same robot (`reference_ideal`, `reference_hardware` name it): a searched or learned
    shape is never a baseline. `battery_reduction_ideal_pct` and `battery_reduction_hardware_pct` are Eq. (12)
    on battery % per metre on the two robots: one quantity, one reference, so `sim_to_real_gap_pp`, their
    difference, is a gap between the robots and nothing else (the paper's: 3 percentage points, between its
    simulation and its prototype). `eq7_reduction_ideal_pct` is Eq. (12) on the ideal robot's Eq. (7) energy
    per metre (Table 5's measure), against the same reference, for reading beside the paper's 12 %.
    """
    index = {(r["trajectory"], r.get("seed", ""), r["speed_mps"], r["robot"]): r for r in rows if not r.get("draw")}
    names = list(dict.fromkeys(r["trajectory"] for r in rows))
    seeds = list(dict.fromkeys(r.get("seed", "") for r in rows))
    speeds = list(dict.fromkeys(r["speed_mps"] for r in rows))

    def common(seed: str, v: float, robot: str, key: str) -> tuple[str | None, float]:
        """The cheaper common trajectory's name and per-metre value (of the same seed, else the seedless one)."""
        found = []
        for n in COMMON_TRAJECTORIES:
            row = index.get((n, seed, v, robot), index.get((n, "", v, robot)))
            if row is not None and _per_m(row, key) > 0:
                found.append((n, _per_m(row, key)))
        return min(found, key=lambda f: f[1]) if found else (None, float("nan"))

    def reduction(name: str, seed: str, v: float, robot: str, key: str) -> tuple[str | None, float]:
        own = index.get((name, seed, v, robot))
        ref, value = common(seed, v, robot, key)
        if own is None or ref is None:
            return ref, float("nan")
        return ref, 100.0 * en.energy_reduction(value, _per_m(own, key))

    out = []
    for seed in seeds:
        for name in names:
            for v in speeds:
                row = _gap_row(index, name, seed, v, reduction)
                if row is not None:
                    out.append(row)
    return out


def _gap_row(index: dict, name: str, seed: str, v: float, reduction) -> dict | None:
    ideal, hw = index.get((name, seed, v, "ideal")), index.get((name, seed, v, "hardware"))
    if ideal is None or hw is None:
        return None
    ref_ideal, d_ideal = reduction(name, seed, v, "ideal", "battery_used_pct")
    ref_hw, d_hw = reduction(name, seed, v, "hardware", "battery_used_pct")
    _, d_eq7 = reduction(name, seed, v, "ideal", "energy_J")
    return {"trajectory": name, "seed": seed, "speed_mps": v,
            "ideal_energy_kJ_per_100m": 0.1 * _per_m(ideal, "energy_J"),  # Eq. (7)
            "hardware_energy_kJ_per_100m": 0.1 * _per_m(hw, "energy_J"),
            "ideal_electrical_kJ_per_100m": 0.1 * _per_m(ideal, "electrical_energy_J"),
            "hardware_electrical_kJ_per_100m": 0.1 * _per_m(hw, "electrical_energy_J"),
            "ideal_battery_pct_per_100m": 100 * _per_m(ideal, "battery_used_pct"),
            "hardware_battery_pct_per_100m": 100 * _per_m(hw, "battery_used_pct"),
            "mechanical_gap_pct": hw["mechanical_gap_pct"], "electrical_gap_pct": hw["electrical_gap_pct"],
            "ideal_range_m": ideal["range_full_charge_m"], "hardware_range_m": hw["range_full_charge_m"],
            "reference_ideal": ref_ideal, "reference_hardware": ref_hw,
            "battery_reduction_ideal_pct": d_ideal, "battery_reduction_hardware_pct": d_hw,
            "sim_to_real_gap_pp": d_ideal - d_hw, "eq7_reduction_ideal_pct": d_eq7}
