"""The prototype run at several joint-PD stiffnesses (`evaluate.py stiffness`): the scaling reaches the PD of
every walk kind, a walk that falls is reported in its row, and the policy walks the same robots as its path."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cyberdog import config as C
from conftest import commanded, learned_set
from cyberdog.analysis import prototype as proto
from cyberdog.analysis import stiffness as st
from cyberdog.core import pid as pid_module
from cyberdog.core.trajectories import SampledTrajectory

ROOT = Path(__file__).resolve().parents[1]
BATTERY_ACTOR = ROOT / "results/battery/policy/seed0/stage2_actor.pt"  # a foot-mode policy trained with seed 0


def test_a_stiffer_pd_scales_kp_and_keeps_the_damping_ratio():
    pid = C.PIDConfig(kp=(60.0, 50.0, 40.0), ki=(1.0, 0.0, 0.0), kd=(2.0, 1.0, 4.0))
    stiff = pid.stiffness_scaled(1.44)
    assert stiff.kp == pytest.approx((86.4, 72.0, 57.6)) and stiff.ki == pytest.approx((1.44, 0.0, 0.0))
    assert stiff.kd == pytest.approx((2.4, 1.2, 4.8))  # × √1.44
    for kp0, kd0, kp1, kd1 in zip(pid.kp, pid.kd, stiff.kp, stiff.kd):  # ζ ∝ kd / √kp unchanged
        assert kd1 / math.sqrt(kp1) == pytest.approx(kd0 / math.sqrt(kp0))
    assert pid.stiffness_scaled(1.0) == pid
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="PD stiffness"):
            pid.stiffness_scaled(bad)


def test_the_stiffness_reaches_the_drivers_pd_in_every_walk_kind(monkeypatch):
    """Learned path, common trajectory, searched shape and the policy closed loop: every joint PD built for the
    walks of a 1.4x run has kp = 1.4 × 60 and kd = √1.4 × 2 (the hardware-like robot's drawn PD factors are 1)."""
    built = []
    original = pid_module.JointPID.__init__

    def recording(self, kp, ki, kd, *args, **kwargs):
        original(self, kp, ki, kd, *args, **kwargs)
        built.append((np.array(self.kp), np.array(self.kd)))
    monkeypatch.setattr(pid_module.JointPID, "__init__", recording)
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0)])
    searched = SampledTrajectory.load(ROOT / "results/searched_shapes/optimized_trajectory_H0.095.json")
    rows = proto.run_prototype({"cycloid": None, "searched": searched}, speeds=(1.0,), distance_m=0.3,
                               modes=("hardware",), learned=learned, draws=1, run_up_s=0.0, workers=1,
                               log=lambda *_: None, policies={"seed0": str(BATTERY_ACTOR)}, pd_scale=1.4)
    assert sorted(r["trajectory"] for r in rows) == ["cycloid", "learned", "policy", "searched"]
    assert all(r["pd_scale"] == 1.4 for r in rows)
    assert len(built) >= 4  # one walker (at least) per walk
    for kp, kd in built:
        assert kp == pytest.approx(np.full(12, 84.0)) and kd == pytest.approx(np.full(12, 2.0 * math.sqrt(1.4)))


def test_the_policy_walks_the_same_robots_as_its_replayed_path():
    """Draw by draw, the closed-loop row and the path's row are the same hardware-like robot (mass draw) over the
    same protocol (run-up left out, the distance reached)."""
    from cyberdog.core.learned_set import LearnedSet, learned_files

    learned = LearnedSet.load(learned_files([ROOT / "results/battery/paths/seed0_1mps.json"]))
    rows = proto.run_prototype({}, speeds=(1.0,), distance_m=1.0, modes=("hardware",), learned=learned, draws=2,
                               run_up_s=1.0, workers=1, log=lambda *_: None, policies={"seed0": str(BATTERY_ACTOR)})
    by = {(r["trajectory"], r["draw"]): r for r in rows}
    assert set(by) == {("learned", 0), ("learned", 1), ("policy", 0), ("policy", 1)}
    for d in (0, 1):
        assert by["policy", d]["mass_scale"] == by["learned", d]["mass_scale"]
        assert by["policy", d]["run_up_s"] == by["learned", d]["run_up_s"] == 1.0
        for kind in ("policy", "learned"):
            assert by[kind, d]["reached"] and 1.0 <= by[kind, d]["distance_m"] < 1.1  # measured after the run-up
    assert by["policy", 0]["mass_scale"] != by["policy", 1]["mass_scale"]
    assert math.isnan(by["policy", 0]["lift_height_m"])  # a policy's lift is not an input


def test_a_policy_without_a_learned_path_of_its_seed_is_refused_before_walking():
    learned = learned_set(seed3=[commanded(1.0, -0.01, 3)])
    with pytest.raises(ValueError, match="no learned path of the same label"):
        proto.run_prototype(speeds=(1.0,), distance_m=0.3, learned=learned, policies={"seed0": "x.pt"},
                            log=lambda *_: None)


def row(trajectory: str, seed: str, scale: float, battery_pct: float, **kw) -> dict:
    """A synthetic 20 m hardware walk at PD stiffness `scale` using `battery_pct` of the pack."""
    return {"trajectory": trajectory, "seed": seed, "draw": 0, "speed_mps": 1.0, "robot": "hardware",
            "pd_scale": scale, "reached": True, "fell": False, "mean_speed_mps": 1.0, "distance_m": 20.0,
            "battery_used_pct": battery_pct, "energy_J": 2000.0, "electrical_energy_J": 7000.0,
            "electrical_cost_of_transport": 2.5, "range_full_charge_m": 20.0 * 95 / battery_pct, **kw}


def test_each_stiffness_is_its_own_comparison_and_a_fall_is_reported_in_its_row(tmp_path):
    rows = []
    for scale, learned_s1 in ((1.0, 0.8), (1.4, 0.5)):
        rows += [row("learned", "s0", scale, 0.9), row("cycloid", "s0", scale, 1.0 * scale),
                 row("straight", "s0", scale, 1.2), row("cycloid", "s1", scale, 1.0), row("straight", "s1", scale, 1.1)]
        rows.append(row("learned", "s1", scale, learned_s1, **({"fell": True, "reached": False, "distance_m": 4.0}
                                                               if scale == 1.4 else {})))
    table = {(r["trajectory"], r["pd_scale"]): r for r in st.stiffness_table(rows)}
    # at 1.0x: 10 % and 20 %; at 1.4x: s0 against the straight line (1.2 < 1.4), s1's walk fell: not counted
    assert table["learned", 1.0]["battery_saving_pct_mean"] == pytest.approx(15.0)
    assert table["learned", 1.4]["battery_saving_pct_mean"] == pytest.approx(25.0)
    stiff = table["learned", 1.4]
    assert (stiff["walks"], stiff["counted"], stiff["fell"]) == (2, 1, 1)
    assert (table["learned", 1.0]["counted"], table["learned", 1.0]["fell"]) == (2, 0)
    assert math.isnan(stiff["battery_saving_stood_pct_mean"]), "the walk that did not count fell: nothing to add"
    md = st.write_stiffness(rows, tmp_path)
    line = next(x for x in md.splitlines() if x.startswith("| learned | 1.4x"))
    assert "1 of 2 did not count, 1 fell" in line and "25.0 %" in line and "did not fall" not in line
    assert "did not count" not in next(x for x in md.splitlines() if x.startswith("| learned | 1x"))
    assert (tmp_path / "stiffness.json").is_file() and (tmp_path / "stiffness_walks.json").is_file()
    assert "re-solved" not in md  # said only where the commands were re-solved
    assert "command re-solved for that PD" in st.write_stiffness([{**r, "pd_matched": r["pd_scale"] != 1.0}
                                                                  for r in rows], tmp_path / "matched")


def test_a_slow_walk_left_out_of_the_saving_is_also_counted_beside_it(tmp_path):
    """A walk off the band does not count, but the row also gives the saving over every walk that did not fall
    (its battery per metre as walked), so that a slow, costly walk cannot vanish from the table."""
    rows = []
    for seed, learned_slow in (("s0", 0.8), ("s1", 1.4)):  # s1's second walk is slow and costs 40 % more
        rows += [row("cycloid", seed, 1.4, 1.0), row("straight", seed, 1.4, 1.2), row("learned", seed, 1.4, 0.8)]
        slow = row("learned", seed, 1.4, learned_slow, mean_speed_mps=0.9 if seed == "s1" else 1.0)
        rows += [{**r, "draw": 1} for r in (row("cycloid", seed, 1.4, 1.0), row("straight", seed, 1.4, 1.2), slow)]
    learned = next(r for r in st.stiffness_table(rows) if r["trajectory"] == "learned")
    assert (learned["walks"], learned["counted"], learned["fell"]) == (4, 3, 0)
    assert learned["battery_saving_pct_mean"] == pytest.approx(20.0)  # every counted walk saves 20 %
    # counted too: s0 20 %, s1 (20 % − 40 %) / 2 = −10 %, so the mean over the two seeds is 5 %
    assert learned["battery_saving_stood_pct_mean"] == pytest.approx(5.0)
    line = next(x for x in st.write_stiffness(rows, tmp_path).splitlines() if x.startswith("| learned"))
    assert "20.0 % ± 0.0 (1 of 4 did not count, 0 fell; counting every walk that did not fall: 5.0 % ± " in line


def test_each_seed_has_its_own_saving_and_says_why_a_walk_did_not_count(tmp_path):
    """The per-seed table: a seed's saving at one stiffness is its own (not the mean over seeds), its walks that
    did not count say why (fell, off the band at their speed), and with the searched shape walked each seed
    has a row against it."""
    rows = [row("cycloid", "s0", 1.4, 1.0), row("straight", "s0", 1.4, 1.2), row("searched", "s0", 1.4, 0.95),
            row("learned", "s0", 1.4, 0.8),
            row("cycloid", "s1", 1.4, 1.0), row("straight", "s1", 1.4, 1.1), row("searched", "s1", 1.4, 0.95),
            row("learned", "s1", 1.4, 0.5, mean_speed_mps=0.9)]  # off the ±5 % band of 1.0 m/s
    fell = row("learned", "s1", 1.4, 0.5, fell=True, reached=False, distance_m=4.0)
    fell["draw"] = 1
    rows.append(fell)
    table = {(r["trajectory"], r["seed"]): r for r in st.seed_table(rows)}
    assert set(table) == {("learned", "s0"), ("learned", "s1"), ("learned against the searched shape", "s0"),
                          ("learned against the searched shape", "s1")}  # no row for the common or searched ones
    assert table["learned", "s0"]["1 m/s"] == "20.0 %"
    assert table["learned against the searched shape", "s0"]["1 m/s"] == f"+{100 * (1 - 0.8 / 0.95):.1f} %"
    assert table["learned", "s1"]["1 m/s"] == "– (off the band at 0.90 m/s; fell)"
    md = st.write_stiffness(rows, tmp_path)
    assert "| 1.4x | learned | s1 | – (off the band at 0.90 m/s; fell) |" in md
    assert (tmp_path / "stiffness_seeds.csv").is_file()


def test_a_row_whose_walks_ran_the_speed_loop_at_its_bound_says_so(tmp_path):
    """The speed loop is averaged over every walk of a row, the one that fell behind included, and a row at its
    bound for LOOP_NOTE_PCT % of the time or more says how long; rows without the fields (older files) do not."""
    rows = [row("cycloid", "s0", 1.4, 1.0, speed_loop_pct=-4.0, speed_loop_at_limit_pct=0.0),
            row("straight", "s0", 1.4, 1.2, speed_loop_pct=-3.0, speed_loop_at_limit_pct=0.0),
            row("learned", "s0", 1.4, 0.9, speed_loop_pct=28.0, speed_loop_at_limit_pct=60.0),
            row("learned", "s0", 1.4, 0.9, speed_loop_pct=30.0, speed_loop_at_limit_pct=90.0, mean_speed_mps=1.3)]
    rows[-1]["draw"] = 1
    table = {r["trajectory"]: r for r in st.stiffness_table(rows)}
    assert table["learned"]["speed_loop_pct"] == pytest.approx(29.0)  # the slow walk, not counted, is in it
    assert table["learned"]["speed_loop_at_limit_pct"] == pytest.approx(75.0)
    assert table["cycloid"]["speed_loop_pct"] == pytest.approx(-4.0)
    md = st.write_stiffness(rows, tmp_path)
    assert "speed loop at its bound 75 % of the time" in next(x for x in md.splitlines() if x.startswith("| learned"))
    assert "speed loop" not in next(x for x in md.splitlines() if x.startswith("| cycloid"))
    old = [{k: v for k, v in r.items() if not k.startswith("speed_loop")} for r in rows]
    assert "speed loop" not in st.write_stiffness(old, tmp_path / "old")
    assert math.isnan(st.stiffness_table(old)[0]["speed_loop_pct"])


def test_bad_scales_are_refused():
    for bad in ([], [0.0], [1.0, 1.0], [float("nan")]):
        with pytest.raises(ValueError, match="PD stiffness scales"):
            st.check_scales(bad)


def test_the_readme_robustness_table_gives_each_stiffness_its_saving_its_falls_and_its_slow_walks():
    from cyberdog.analysis.readme_tables import stiffness_markdown
    rows = []
    for scale, learned_s1 in ((0.7, 0.8), (1.4, 0.5)):
        rows += [row("learned", "s0", scale, 0.9), row("cycloid", "s0", scale, 1.0), row("straight", "s0", scale, 1.2),
                 row("policy", "s0", scale, 0.7), row("cycloid", "s1", scale, 1.0), row("straight", "s1", scale, 1.1),
                 row("learned", "s1", scale, learned_s1, **({"fell": True, "reached": False, "distance_m": 4.0}
                                                           if scale == 1.4 else {}))]
    rows.append(row("learned", "s2", 1.4, 0.1, mean_speed_mps=0.9))  # 10 % slow: off the band, not a fall
    rows += [row("cycloid", "s2", 1.4, 1.0), row("straight", "s2", 1.4, 1.1)]
    lines = stiffness_markdown(rows).splitlines()
    soft = next(x for x in lines if x.startswith("| **replayed learned path, PD 0.7×**"))
    stiff = next(x for x in lines if x.startswith("| **replayed learned path, PD 1.4×**"))
    assert "**15.0 % ± " in soft and "fell" not in soft and "band" not in soft  # 10 % and 20 %
    # s0 alone counts (its 90 % saving left out for s2, which walked slow); s1's fall and s2's slow walk reported,
    # and the saving with the slow walk counted: s0's 10 % and s2's 90 % (s1 fell: never counted)
    assert "**10.0 % (1 fell, 1 off the ±5 % band, of 3; with it: 50.0 % ± " in stiff
    assert any(x.startswith("| the policy, closed loop, PD 1.4× | 30.0 %") for x in lines)


def test_the_readme_robustness_table_puts_the_re_commanded_paths_beside_the_plain_ones():
    """The walks of a --pd-matched run give rows of their own, at every stiffness but 1× (where nothing is
    re-solved), each against the common trajectories of that same run."""
    from cyberdog.analysis.readme_tables import stiffness_markdown

    def run(learned_battery):
        return [r for scale in (0.7, 1.0, 1.4) for r in (
            row("learned", "s0", scale, learned_battery[scale]), row("cycloid", "s0", scale, 1.0 * scale),
            row("straight", "s0", scale, 2.0))]
    plain = run({0.7: 0.8, 1.0: 0.8, 1.4: 1.4})  # at 1.4x the plain path saves nothing against a 1.4 cycloid
    matched = run({0.7: 0.56, 1.0: 0.8, 1.4: 1.12})  # re-commanded: 20 % at every stiffness
    lines = stiffness_markdown(plain, matched=matched).splitlines()
    labels = [x.split(" | ")[0] for x in lines[2:]]
    assert labels == ["| **replayed learned path, PD 0.7×**", "| **replayed learned path, PD 1×**",
                      "| **replayed learned path, PD 1.4×**",
                      "| **replayed learned path re-commanded for the PD, PD 0.7×**",
                      "| **replayed learned path re-commanded for the PD, PD 1.4×**"]
    assert "**0.0 %**" in lines[4] and all("**20.0 %**" in x for x in lines[5:7])
    assert stiffness_markdown(plain) == "\n".join(lines[:5])  # without them, the table as before
