"""evaluate.py end to end on a reduced budget, and the consistency of what it writes (Table 5, Eq. 12, Fig. 10)."""
import csv
import json
import math

import numpy as np
import pytest

import evaluate
from cyberdog import config as C
from cyberdog.analysis import compare as cmp
from cyberdog.analysis import table5 as t5
from conftest import commanded, learned_set
from cyberdog.core.learned_set import LearnedSetError
from cyberdog.core.trajectories import CompositeCycloid, SampledTrajectory
from plots.figure10 import last_cycles_window
from cyberdog.evaluation import learned as learned_module

FIGURES = ("figure4_baseline_trajectories", "figure6_reward_curves", "figure7_learned_trajectory",
           "figure10_power", "figure13_energy_vs_speed")
# 2 s walks: a short speed ramp and a stiff speed integral make every walk reach 1.0 m/s ± 5 % in 2 s
FAST = ["--set", "controller.speed_ramp_time=0.3", "controller.speed_gain=6.0"]


def learned_file(path, lift=0.1):
    """A stand-in for an extracted trajectory: the composite cycloid sampled at 100 phases, seed 0."""
    phase = np.arange(100) / 100
    pos, _ = CompositeCycloid().position_velocity(phase, 0.2, lift, 0.2, 0.2)
    t = SampledTrajectory.from_points(phase, pos[:, 0], pos[:, 1], 0.2, lift,
                                      {"seed": 0, "policy": "synthetic", "period_s": 0.4})
    return t.save(path)


def metrics_file(path):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["stage", "episode", "stage_episode", "score"])
        for stage in (1, 2):
            for ep in range(1, 41):
                w.writerow([stage, ep + 40 * (stage - 1), ep, -50 + ep + np.sin(ep)])
    return path


@pytest.fixture(scope="module")
def reduced_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("evaluate")
    out = tmp / "out"
    argv = ["--learned", str(learned_file(tmp / "learned.json")), "--metrics", str(metrics_file(tmp / "m.csv")),
            "--speeds", "1.0", "--duration", "2.0", "--prototype-distance", "1.0", "--prototype-modes", "ideal",
            "--workers", "2", "--out", str(out), *FAST]
    assert evaluate.main(argv) == 0
    return out


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_reduced_run_writes_table5_figures_and_prototype(reduced_run):
    out = reduced_run
    for stem in ("table5", "comparison", "prototype"):
        for ext in ("csv", "json", "md"):
            assert (out / f"{stem}.{ext}").stat().st_size > 0, f"{stem}.{ext}"
    for stem in FIGURES:
        assert (out / f"{stem}.png").stat().st_size > 1000 and (out / f"{stem}.pdf").exists(), stem
    assert (out / "power_traces.npz").exists() and (out / "learned" / "seed0.json").exists()
    md = (out / "table5.md").read_text()
    assert "Decrement D_t" in md and "Composite cycloid (H = 0.150 m)" in md and "H = 0.100 m" in md
    proto = json.loads((out / "prototype.json").read_text())
    # the shipped shape searched for the battery walks beside the common trajectories as a reference row
    assert {r["trajectory"] for r in proto} == {"learned", "cycloid", "straight", "searched"}
    from cyberdog.evaluation.cli import DEFAULT_PROTOTYPE_RUN_UP
    assert DEFAULT_PROTOTYPE_RUN_UP > 0 and all(r["run_up_s"] == DEFAULT_PROTOTYPE_RUN_UP for r in proto)


def test_table5_decrement_is_eq12_on_its_own_energies(reduced_run):
    rows = read_csv(reduced_run / "table5.csv")
    assert {r["set"] for r in rows} == {"paper", "same_lift"}
    checked = 0
    for r in rows:
        if r["row"] != "learned":
            continue
        base = [b for b in rows if b["set"] == r["set"] and b["speed_mps"] == r["speed_mps"]
                and b["row"] in ("cycloid", "straight")]
        assert len(base) == 2
        lift = 0.15 if r["set"] == "paper" else float(r["lift_height_m"])
        assert all(abs(float(b["lift_height_m"]) - lift) < 1e-4 for b in base)
        valid = [float(b["energy_kJ"]) for b in base if b["valid"] == "True"]
        if r["valid"] == "True" and valid:
            e_min = min(valid)
            assert float(r["D_t_pct"]) == pytest.approx(100 * (e_min - float(r["energy_kJ"])) / e_min, rel=1e-9)
            checked += 1
        else:
            assert math.isnan(float(r["D_t_pct"]))
    assert checked == 2  # both sets: every 2 s walk reached the speed with FAST


def test_power_traces_integrate_to_the_tables_energy(reduced_run):
    walks = json.loads((reduced_run / "walks.json").read_text())
    assert {w["trajectory"] for w in walks} >= {"learned", "cycloid", "straight"}
    table = read_csv(reduced_run / "table5.csv")
    with np.load(reduced_run / "power_traces.npz") as z:
        for w in walks:
            p = z[f"walk_{w['walk_id']}"]
            assert len(p) == round(w["duration_s"] / w["controller_dt_s"])
            assert p.sum() * w["controller_dt_s"] == pytest.approx(w["energy_J"], rel=1e-9)
            e_table = [float(r["energy_kJ"]) for r in table
                       if r["row"] == w["trajectory"] and abs(float(r["lift_height_m"]) - w["lift_height_m"]) < 1e-9]
            assert e_table and all(e == pytest.approx(w["energy_J"] / 1e3, rel=1e-9) for e in e_table)
            window = p[last_cycles_window(len(p), w["controller_dt_s"], w["period_s"])]
            assert len(window) == round(2 * w["period_s"] / w["controller_dt_s"])  # Figure 10's two cycles


def test_figures_redraw_from_a_saved_folder(reduced_run, tmp_path):
    out = tmp_path / "figs"
    assert evaluate.main(["figures", "--from", str(reduced_run), "--out", str(out), "--metrics",
                          str(metrics_file(tmp_path / "m.csv"))]) == 0
    for stem in FIGURES:
        assert (out / f"{stem}.png").exists(), stem


def test_missing_learned_trajectory_is_a_clear_error(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(learned_module, "DEFAULT_LEARNED", tmp_path / "results" / "table5" / "paths")
    assert evaluate.main(["--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "results/table5/paths does not exist" in err and "extract --sweep" in err
    assert not (tmp_path / "o").exists()  # nothing started
    assert evaluate.main(["compare", "--learned", str(tmp_path / "nope.json"), "--out", str(tmp_path / "o")]) == 2
    assert evaluate.main(["extract", "--out", str(tmp_path / "o")]) == 2
    assert "--policy" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        evaluate.main(["compare", "--speeds", "-1"])


def test_video_writes_a_gif(tmp_path):
    from PIL import Image

    assert evaluate.main(["video", "--video-trajectory", "cycloid", "--video-duration", "0.3",
                          "--out", str(tmp_path)]) == 0
    gif = tmp_path / "trot_cycloid_1mps.gif"
    with Image.open(gif) as im:
        assert im.n_frames >= 5 and im.size == (480, 360)


def walk_row(walk_id, trajectory, energy, lift, valid=True, seed=""):
    return {"walk_id": walk_id, "trajectory": trajectory, "label": trajectory, "seed": seed,
            "lift_height_m": lift, "speed_command_mps": 1.0, "energy_J": energy, "energy_kJ": energy / 1e3,
            "energy_per_100m_kJ": energy / 100, "valid": valid, "fell": False, "speed_ok": valid,
            "status": "ok" if valid else "speed miss", "mean_speed_mps": 1.0, "duration_s": 10.0,
            "electrical_energy_J": 3.5 * energy, "positive_work_J": 0.5 * energy, "foot_slip_mm_per_cycle": 10.0}


def test_decrement_uses_the_cheaper_valid_baseline_of_the_same_set():
    walks = [walk_row(0, "learned", 900.0, 0.1, seed="s0"), walk_row(1, "learned", 1200.0, 0.1, seed="s1"),
             walk_row(2, "cycloid", 1000.0, 0.15), walk_row(3, "straight", 800.0, 0.15, valid=False),
             walk_row(4, "cycloid", 850.0, 0.1), walk_row(5, "straight", 950.0, 0.1)]
    rows = cmp.comparison_rows(walks, paper_lift=0.15)
    d = {(r["set"], r["seed"]): r["D_t_pct"] for r in rows if r["trajectory"] == "learned"}
    assert d[("paper", "s0")] == pytest.approx(10.0)  # the invalid straight walk (800 J) is not E_min
    assert d[("paper", "s1")] == pytest.approx(-20.0)
    assert d[("same_lift", "s0")] == pytest.approx(100 * (850 - 900) / 850)
    means = {m["set"]: m for m in cmp.seed_means(rows)}
    assert means["paper"]["n_valid"] == 2 and means["paper"]["D_t_pct_mean"] == pytest.approx(-5.0)
    assert means["paper"]["energy_kJ_ci95"] > 0
    md = t5.table5_markdown(rows, cmp.seed_means(rows))
    assert "mean ± 95 % CI over 2 seeds" in md and "(miss: 1.00 m/s)" in md


def test_table5_labels_a_seeds_row_with_each_walks_own_lift():
    """A seed whose paths differ in lift from speed to speed (commanded paths): the paper-protocol row, which holds
    all three, names the three lifts in the columns' order, not the first one."""
    walks = []
    for i, (v, lift) in enumerate(((1.0, 0.093), (1.2, 0.086), (1.4, 0.083))):
        for j, (traj, energy, h) in enumerate((("learned", 900.0, lift), ("cycloid", 1000.0, 0.15),
                                               ("straight", 1100.0, 0.15), ("cycloid", 1000.0, lift),
                                               ("straight", 1100.0, lift))):
            walks.append({**walk_row(10 * i + j, traj, energy, h, seed="seed0" if traj == "learned" else ""),
                          "speed_command_mps": v})
    md = t5.table5_markdown(cmp.comparison_rows(walks, paper_lift=0.15))
    labels = [line.split("|")[1].strip() for line in md.splitlines() if line.startswith("| Learned trajectory")]
    assert "Learned trajectory (H = 0.093 / 0.086 / 0.083 m) [seed0]" in labels
    assert {"Learned trajectory (H = 0.093 m) [seed0]", "Learned trajectory (H = 0.086 m) [seed0]",
            "Learned trajectory (H = 0.083 m) [seed0]"} <= set(labels)  # the matched-lift groups: one each


def test_commanded_paths_walk_only_at_their_speed_with_baselines_at_their_own_lift():
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.2, -0.02, 0)])
    jobs = cmp.comparison_jobs(C.WalkConfig(), learned, speeds=(1.0, 1.2))
    mine = [j for j in jobs if j.trajectory == "learned"]
    assert [(j.speed, round(j.lift_height, 3)) for j in mine] == [(1.0, 0.09), (1.2, 0.08)]
    assert all(j.cfg.gait.lift_height == 0.10 and j.cfg.gait.trajectory == "cycloid" for j in mine)
    assert all(j.foot_offsets is j.learned.path.offsets and j.foot_trajectory is None for j in mine)
    base_lifts = {(j.speed, round(j.lift_height, 3)) for j in jobs if j.trajectory == "cycloid"}
    assert base_lifts == {(1.0, 0.15), (1.0, 0.09), (1.2, 0.15), (1.2, 0.08)}
    with pytest.raises(LearnedSetError, match="seed0 has no learned path at 1.4 m/s"):  # never a table without it
        cmp.comparison_jobs(C.WalkConfig(), learned, speeds=(1.0, 1.4))
    # --skip-missing-paths: a seed without a path at a speed walks nothing there; a speed no seed has is refused
    two = learned_set(seed0=[commanded(1.0, -0.01, 0)], seed1=[commanded(1.0, -0.01, 0), commanded(1.2, -0.02, 0)])
    jobs = cmp.comparison_jobs(C.WalkConfig(), two, speeds=(1.0, 1.2), skip_missing=True)
    assert sorted((j.seed, j.speed) for j in jobs if j.trajectory == "learned") == [
        ("seed0", 1.0), ("seed1", 1.0), ("seed1", 1.2)]
    with pytest.raises(LearnedSetError, match="1.4 m/s"):
        cmp.comparison_jobs(C.WalkConfig(), two, speeds=(1.4,), skip_missing=True)


def test_the_prototype_walks_a_seed_without_a_path_at_a_speed_nowhere_at_that_speed_when_asked():
    """An extraction that found no path for one seed at one speed: by default the prototype refuses (the CLI names
    the seed and speed and the option); with skip_missing that seed walks nothing at that speed, neither its path
    nor the common trajectories, and the other seeds walk as they would have."""
    from cyberdog.analysis import prototype as pr
    from cyberdog.evaluation.commands import UsageError

    full = learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.4, -0.01, 0)],
                       seed1=[commanded(1.0, -0.02, 1), commanded(1.4, -0.02, 1)])
    partial = learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.4, -0.01, 0)],
                          seed1=[commanded(1.0, -0.02, 1)])
    args = dict(trajectories={"cycloid": None, "straight": None}, speeds=(1.0, 1.4), distance_m=1.0,
                modes=("hardware",), hardware=C.HARDWARE_LIKE, draws=1, run_up_s=0.0, policies=None)
    with pytest.raises(LearnedSetError, match="seed1 has no learned path at 1.4 m/s"):
        pr._checked_inputs(learned=partial, **args)
    pr._checked_inputs(learned=partial, skip_missing=True, **args)
    with pytest.raises(LearnedSetError, match="no learned path at 1.4 m/s"):
        pr._checked_inputs(learned=learned_set(seed1=[commanded(1.0, -0.02, 1)]), skip_missing=True, **args)

    def jobs(learned):
        return [(j.trajectory_name, j.seed, j.speed, round(j.lift_height or 0.0, 3))
                for j in pr._walk_jobs(args["trajectories"], args["speeds"], C.WalkConfig(), [("hardware", 0)],
                                       C.HARDWARE_LIKE, 1.0, 0.0, learned, None, {}, 1.0, None, {},
                                       skip_missing=True)]
    walked = jobs(partial)
    assert {(name, v) for name, seed, v, _ in walked if seed == "seed1"} == {
        ("learned", 1.0), ("cycloid", 1.0), ("straight", 1.0)}
    assert [j for j in jobs(full) if j[1] == "seed0"] == [j for j in walked if j[1] == "seed0"]
    assert [j for j in jobs(full) if j[1] == "seed1" and j[2] == 1.0] == [j for j in walked if j[1] == "seed1"]
    with pytest.raises(UsageError, match=r"seed1 at 1.4\).*--skip-missing-paths"):
        learned_module.check_speeds_covered(partial, [1.0, 1.4], skip_missing=False)
    learned_module.check_speeds_covered(partial, [1.0, 1.4], skip_missing=True)


def test_the_prototype_re_commands_every_walk_for_a_users_gains_when_asked(monkeypatch):
    """`run_prototype(pd_matched_from=the default PD)` under a config with kd doubled: the learned path and the
    common trajectories alike walk with their command re-solved from the default PD to kd 4 (like for like),
    each under kd 4; without it none is; with pd_scale or pd_matched as well it is refused."""
    from cyberdog.analysis import prototype as pr

    captured = []
    monkeypatch.setattr(pr, "map_in_processes", lambda run, jobs, *a, **k: captured.extend(jobs) or [])
    monkeypatch.setattr(pr, "add_gaps", lambda rows: rows)
    user = C.replace(C.WalkConfig(), pid=C.replace(C.PIDConfig(), kd=(4.0, 4.0, 4.0)))
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0)])
    kwargs = dict(speeds=(1.0,), distance_m=1.0, modes=("hardware",), draws=1, base_cfg=user, learned=learned)
    pr.run_prototype(pd_matched_from=C.PIDConfig(), **kwargs)
    assert {j.trajectory_name for j in captured} == {"learned", "cycloid", "straight"}
    assert all(j.pd_matched_from == C.PIDConfig() and j.cfg.pid.kd == (4.0, 4.0, 4.0) for j in captured)
    captured.clear()
    pr.run_prototype(**kwargs)
    assert captured and all(j.pd_matched_from is None for j in captured)
    with pytest.raises(ValueError, match="pd_matched_from"):
        pr.run_prototype(pd_matched_from=C.PIDConfig(), pd_scale=2.0, **kwargs)


def two_seeds_at_their_own_lift() -> list[dict]:
    """Two learned walks at 1.0 m/s (H = 0.09 and 0.08 m), the baselines at each of those lifts and at 0.15 m."""
    return [walk_row(0, "learned", 900.0, 0.09, seed="s0"), walk_row(1, "learned", 800.0, 0.08, seed="s1"),
            walk_row(2, "cycloid", 1000.0, 0.09), walk_row(3, "straight", 1100.0, 0.09),
            walk_row(4, "cycloid", 1000.0, 0.08), walk_row(5, "straight", 700.0, 0.08),
            walk_row(6, "cycloid", 1600.0, 0.15), walk_row(7, "straight", 2000.0, 0.15)]


def test_summary_pairs_each_learned_walk_with_the_baselines_at_its_own_lift():
    walks = two_seeds_at_their_own_lift()
    rows = cmp.comparison_rows(walks, paper_lift=0.15)
    summary = {r["set"]: r for r in t5.summary_rows(rows)}
    matched, paper = summary["same_lift"], summary["paper"]
    assert matched["n_valid"] == 2 and matched["D_t_pct_mean"] == pytest.approx((10.0 - 100 * 100 / 700) / 2)
    assert matched["cycloid_energy_kJ_mean"] == pytest.approx(1.0)  # one matched cycloid walk per seed
    assert matched["straight_energy_kJ_mean"] == pytest.approx(0.9)
    assert paper["D_t_pct_mean"] == pytest.approx((100 * 700 / 1600 + 100 * 800 / 1600) / 2)
    assert paper["cycloid_energy_kJ_mean"] == pytest.approx(1.6)
    assert paper["D_t_electrical_pct_mean"] == pytest.approx(paper["D_t_pct_mean"])  # electrical = 3.5 × E here
    md = t5.summary_markdown(list(summary.values()), "same_lift")
    assert "2 of 2" in md and "D_t on the electrical energy" in md


def test_the_reference_shape_is_a_row_of_the_matched_table_but_not_a_baseline():
    walks = two_seeds_at_their_own_lift()
    plain = cmp.comparison_rows(walks, paper_lift=0.15)
    rows = cmp.comparison_rows(walks + [walk_row(8, cmp.REFERENCE, 600.0, 0.085)], paper_lift=0.15)
    learned = [r for r in rows if r["trajectory"] == "learned"]
    assert [r["D_t_pct"] for r in learned] == [r["D_t_pct"] for r in plain if r["trajectory"] == "learned"]
    d_ref = {(r["set"], r["seed"]): r["D_ref_pct"] for r in learned}
    assert d_ref[("same_lift", "s0")] == pytest.approx(-50.0) and d_ref[("same_lift", "s1")] == pytest.approx(
        100 * (600 - 800) / 600)
    assert math.isnan(d_ref[("paper", "s0")])  # the reference walks at the learned lift only
    assert [r["set"] for r in rows if r["trajectory"] == cmp.REFERENCE] == ["same_lift"]
    summary = {r["set"]: r for r in t5.summary_rows(rows)}
    assert summary["same_lift"][f"{cmp.REFERENCE}_energy_kJ_mean"] == pytest.approx(0.6)
    assert summary["same_lift"]["D_ref_pct_mean"] == pytest.approx((-50.0 + 100 * (600 - 800) / 600) / 2)
    assert f"{cmp.REFERENCE}_energy_kJ_mean" not in summary["paper"]
    md = t5.summary_markdown(list(summary.values()), "same_lift")
    assert "searched shape (H = 0.085 m, reference)" in md and "learned against the searched shape" in md
    # a reference walk that failed is shown, and no D_ref comes of it
    failed = cmp.comparison_rows(walks + [walk_row(8, cmp.REFERENCE, 600.0, 0.085, valid=False)], paper_lift=0.15)
    learned_rows = [r for r in failed if r["trajectory"] == "learned"]
    assert learned_rows and all(math.isnan(r["D_ref_pct"]) for r in learned_rows)
    assert any(r["trajectory"] == cmp.REFERENCE for r in failed)


def test_the_reference_shape_walks_once_per_speed_at_its_own_lift():
    phase = np.arange(100) / 100
    pos, _ = CompositeCycloid().position_velocity(phase, 0.2, 0.095, 0.2, 0.2)
    ref = SampledTrajectory.from_points(phase, pos[:, 0], pos[:, 1], 0.2, 0.095, {})
    learned = learned_set(seed0=[commanded(1.0, -0.01, 0), commanded(1.2, -0.02, 0)])
    jobs = cmp.comparison_jobs(C.WalkConfig(), learned, speeds=(1.0, 1.2), reference=ref)
    mine = [j for j in jobs if j.trajectory == cmp.REFERENCE]
    assert [(j.speed, j.lift_height, j.cfg.gait.lift_height) for j in mine] == [(1.0, 0.095, 0.095),
                                                                                (1.2, 0.095, 0.095)]
    assert all(j.foot_trajectory is ref and j.learned is None for j in mine)
    assert not [j for j in cmp.comparison_jobs(C.WalkConfig(), learned, speeds=(1.0,), same_lift=False,
                                                reference=ref) if j.trajectory == cmp.REFERENCE]
    with pytest.raises(TypeError, match="foot trajectory"):
        cmp.comparison_jobs(C.WalkConfig(), learned, reference=commanded(1.0, -0.01, 0))


# ---- the command line: each sub-command has its own options and help ----------------------------------------
OWN_OPTIONS = {  # an option each sub-command takes, and one it must refuse
    "all": ("--no-prototype", "--trajectories"), "baselines": ("--trajectories", "--policies"),
    "extract": ("--rollout-duration", "--learned"), "compare": ("--no-same-lift", "--prototype-distance"),
    "prototype": ("--prototype-distance", "--duration"), "figures": ("--from", "--speeds"),
    "video": ("--video-speed", "--workers"),
}


def sub_command_help(sub, capsys) -> str:
    with pytest.raises(SystemExit) as exit_:
        evaluate.main([sub, "--help"])
    assert exit_.value.code == 0
    return capsys.readouterr().out


def test_each_sub_command_helps_with_its_own_options_only(capsys):
    texts = {sub: sub_command_help(sub, capsys) for sub in OWN_OPTIONS}
    assert len(set(texts.values())) == len(OWN_OPTIONS)  # seven different help texts
    for sub, (own, other) in OWN_OPTIONS.items():
        assert texts[sub].startswith(f"usage: evaluate.py {sub} ")
        assert own in texts[sub] and other not in texts[sub], sub
    top = sub_command_help("--help", capsys)  # the top-level help lists every sub-command
    assert top.startswith("usage: evaluate.py [-h] SUB-COMMAND") and all(f"    {sub} " in top for sub in OWN_OPTIONS)


@pytest.mark.parametrize("sub", sorted(OWN_OPTIONS))
def test_an_option_of_another_sub_command_is_refused_in_one_line(sub, capsys):
    own, other = OWN_OPTIONS[sub]
    with pytest.raises(SystemExit) as exit_:
        evaluate.main([sub, other, "1"])
    assert exit_.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith(f"evaluate.py {sub}: error: unrecognized arguments: {other}")
    assert "is an option of:" in last and sub not in last.split("is an option of:")[1].split(", ")


@pytest.mark.parametrize("argv, words", [
    (["compare", "--speeds", "-1"], ["--speeds", "> 0", "'-1'"]),
    (["baselines", "--duration", "abc"], ["--duration", "'abc'"]),
    (["all", "--workers", "0"], ["--workers", ">= 1"]),
    (["extract", "--speed-tolerance", "1.5"], ["--speed-tolerance", "(0, 1)"]),
    (["--video-format", "avi"], ["evaluate.py all: error", "--video-format"]),  # no sub-command: all
])
def test_bad_values_end_with_a_line_naming_the_option(argv, words, capsys):
    with pytest.raises(SystemExit) as exit_:
        evaluate.main(argv)
    assert exit_.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert all(w in last for w in words), last


def test_baselines_accept_a_standing_speed_that_the_others_refuse():
    from cyberdog.evaluation.cli import parse_args

    assert parse_args(["baselines", "--speeds", "0"]).speeds == [0.0]
    with pytest.raises(SystemExit):
        parse_args(["compare", "--speeds", "0"])


def test_the_command_line_copies_of_library_constants_match_the_library():
    from cyberdog.analysis import extract
    from cyberdog.analysis.baselines import BASELINES
    from cyberdog.config.paper import SPEED_BAND
    from cyberdog.evaluation import cli

    assert cli.BASELINE_CHOICES == tuple(BASELINES) and cli.CYCLE_CHOICES == tuple(extract.CYCLE_CHOICES)
    assert SPEED_BAND == extract.SPEED_TOLERANCE  # the default --speed-tolerance

