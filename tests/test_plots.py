"""The figures: drawn from saved results only, never importing the simulator or torch; the README's PNGs are
redrawn by their documented command from the shipped inputs; the figure faults that were fixed stay fixed."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.image import imread

import plots
from cyberdog import config as C
from cyberdog.config.paper import SPEED_BAND, speed_within_band
from conftest import commanded
from cyberdog.metrics_csv import read_rows, read_stages, run_name
from plots import figure6, figure7, figure10, figure13, results
from plots.learning_curves import NUMBER_COLUMNS, read_curves
from plots.shipped import README_FIGURES, SHIPPED_INPUTS, SHIPPED_PNG, export_inputs
from plots.style import COLORS, FADED_ALPHA

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = ("torch", "torchrl", "pybullet", "pybullet_data", "cyberdog.sim", "cyberdog.rl", "cyberdog.envs",
             "cyberdog.analysis.compare", "cyberdog.analysis.walk")
README_COMMAND = "python -m plots --from results/figures_input --out plots/png --readme"  # as in the README


# ---- a small results folder, shaped like what evaluate.py writes ----------------------------------------------
def fake_results(folder: Path, seed: int = 0) -> Path:
    """Two speeds; learned (two seeds), cycloid and straight walks of 2.3 s at 1 kHz with random power."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True)
    C.save(C.WalkConfig(), folder / "config.yaml")
    walks, power = [], {}
    for v in (1.0, 1.2):
        for key, s, lift in (("learned", "seed0", 0.09), ("learned", "seed1", 0.092), ("cycloid", None, 0.15),
                             ("straight", None, 0.15), ("cycloid", None, 0.09)):
            i = len(walks)
            power[i] = rng.uniform(0, 300, 2300)  # W; 2.3 s: the last whole cycles end at 2.0 s
            walks.append({"walk_id": i, "trajectory": key, "label": key, "seed": s, "lift_height_m": lift,
                          "speed_command_mps": v, "period_s": 0.4, "controller_dt_s": 0.001, "fell": False,
                          "speed_ok": True, "valid": True, "duration_s": 2.3,
                          "energy_kJ": float(power[i].sum()) * 1e-6, "set": "paper" if lift > 0.1 or s else
                          "same_lift"})
    (folder / "walks.json").write_text(json.dumps(walks))
    (folder / "comparison.json").write_text(json.dumps(walks))
    np.savez_compressed(folder / "power_traces.npz", **{f"walk_{i}": p for i, p in power.items()})
    proto = [{"trajectory": t, "speed_mps": v, "robot": r, "fell": False, "reached": True,
              "mean_speed_mps": v * rng.uniform(0.9, 1.1), "distance_m": 20.0, "battery_used_pct": rng.uniform(1, 2)}
             for t in ("learned", "cycloid", "straight") for v in (1.0, 1.2) for r in ("ideal", "hardware")]
    (folder / "prototype.json").write_text(json.dumps(proto))
    for s in (0, 1):
        for v in (1.0, 1.2):
            commanded(v, -0.005 * (s + 1), s).save(folder / "learned" / f"seed{s}_{v:g}mps.json")
    return folder


def pixels(path: Path) -> np.ndarray:
    return imread(path)[..., :3]  # RGB in [0, 1]


# ---- layers ------------------------------------------------------------------------------------------------------
def test_plots_import_and_draw_without_the_simulator_or_torch(tmp_path):
    """Import every plots module and draw every figure from the shipped inputs in a fresh interpreter, then
    look at what was imported."""
    code = f"""
import importlib, json, pkgutil, sys
import plots
for m in pkgutil.iter_modules(plots.__path__):
    importlib.import_module("plots." + m.name)
paths = plots.draw_all({str(SHIPPED_INPUTS)!r}, {str(tmp_path)!r},
                       metrics=[{str(ROOT / "results/table5/policy/seed0/metrics.csv")!r}])
print(json.dumps({{"paths": [str(p) for p in paths], "modules": sorted(sys.modules)}}))
"""
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    loaded = [m for m in out["modules"] if any(m == f or m.startswith(f + ".") for f in FORBIDDEN)]
    assert loaded == []
    drawn = {Path(p).name for p in out["paths"]}
    for stem in ("figure4_baseline_trajectories", "figure6_reward_curves", "figure7_learned_trajectory",
                 "figure10_power", "figure13_energy_vs_speed", "walk_strip"):
        assert {f"{stem}.png", f"{stem}.pdf"} <= drawn


# ---- the README's figures ---------------------------------------------------------------------------------------
def test_readme_figures_regenerate_from_the_shipped_inputs(tmp_path):
    args = README_COMMAND.split()[1:]
    args[args.index("plots/png")] = str(tmp_path)
    proc = subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    shipped = sorted(SHIPPED_PNG.glob("*.png"))
    assert len(shipped) == len(README_FIGURES)
    assert sorted(p.name for p in tmp_path.iterdir()) == [p.name for p in shipped]  # PNG only
    for path in shipped:
        assert path.stat().st_size < 250_000, path.name  # small enough to commit (Figure 10: two rows of traces)
        new, old = pixels(tmp_path / path.name), pixels(path)
        assert new.shape == old.shape, path.name
        # the same figure: anti-aliasing may differ between matplotlib builds, a changed figure does not pass
        # (drawing Figure 10's learned trace under the others changes 2.7 % of its pixels, mean 0.009)
        diff = np.abs(new - old)
        assert diff.mean() < 0.002 and (diff.max(axis=-1) > 0.1).mean() < 0.005, path.name


def test_exported_inputs_draw_the_same_figures_as_the_full_folder(tmp_path):
    full = fake_results(tmp_path / "full")
    export_inputs(full, tmp_path / "small")
    a = plots.draw_all(full, tmp_path / "a", only=README_FIGURES, pdf=False)
    b = plots.draw_all(tmp_path / "small", tmp_path / "b", only=README_FIGURES, pdf=False)
    assert [p.name for p in a] == [p.name for p in b] and len(a) == 3
    for pa, pb in zip(a, b):
        assert np.array_equal(pixels(pa), pixels(pb)), pa.name
    with np.load(tmp_path / "small" / "power_traces.npz") as z:
        assert z.files and all(len(z[k]) == 800 for k in z.files)  # two 0.4 s cycles at 1 kHz, nothing more
    with pytest.raises(ValueError, match="drawn from"):
        export_inputs(full, full)


# ---- figure faults ----------------------------------------------------------------------------------------------
def figure10_of(folder: Path):
    walks = json.loads((folder / "walks.json").read_text())
    with np.load(folder / "power_traces.npz") as z:
        power = {int(k.split("_")[1]): z[k] for k in z.files}
    return figure10.draw(walks, power)


def traces(ax) -> list:
    return [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]  # not the gait period boundary


def test_figure10_draws_the_learned_trace_on_top(tmp_path):
    fig = figure10_of(fake_results(tmp_path / "r"))
    assert len(fig.axes) == 4
    top_row, bottom_row = fig.axes[:2], fig.axes[2:]  # two speeds: (a), (b) above, (c), (d) below
    for ax in fig.axes:
        top = max(traces(ax), key=lambda ln: ln.get_zorder())
        assert top is traces(ax)[-1] and top.get_color() == COLORS["learned"]
    for ax in top_row:  # the learned path and the cycloid at its lift height (the headline pair), nothing else
        assert [ln.get_label().split(",")[0] for ln in traces(ax)] == ["cycloid (matched)", "learned (RL) [seed0]"]
    for ax in bottom_row:  # the cycloid at the paper's H; the straight line was walked at the paper's H only
        styles = {ln.get_label().split(",")[0]: ln.get_linestyle() for ln in traces(ax)}
        assert styles == {"cycloid (paper)": ":", "straight (paper)": ":", "learned (RL) [seed0]": "-"}


def test_figure10_shows_learned_and_cycloid_on_their_own_scale_and_labels_every_line():
    """From the shipped inputs: the straight line's ~1.5 kW spikes are on another axis than the learned path and
    the cycloid, whose axis reaches less than twice their highest power; every line, the gait period boundary
    included, has an entry in the legend under its column."""
    fig = figure10_of(SHIPPED_INPUTS)
    n = len(fig.axes) // 2
    # the top row shares its axis: it reaches less than twice the highest power of the pairs it shows
    row_highest = max(float(np.max(ln.get_ydata())) for ax in fig.axes[:n] for ln in traces(ax))
    for col in range(n):
        top, bottom = fig.axes[col], fig.axes[n + col]
        pair = traces(top)
        assert {ln.get_color() for ln in pair} == {COLORS["learned"], COLORS["cycloid"]}
        highest = max(float(np.max(ln.get_ydata())) for ln in pair)
        assert top.get_ylim()[1] < 2 * row_highest, (top.get_ylim(), row_highest)
        assert max(float(np.max(ln.get_ydata())) for ln in traces(bottom)) > 2 * highest  # the spikes: below
        legend = [t.get_text() for t in bottom.get_legend().get_texts()]
        for ax in (top, bottom):
            for ln in ax.get_lines():
                assert ln.get_label() in legend or ln.get_label() == "_boundary", ln.get_label()
        assert any(lab.startswith("gait period boundary (T = 0.4 s)") for lab in legend)


def test_figure13_draws_the_matched_baselines_beside_the_papers_protocol(tmp_path):
    rows = json.loads((fake_results(tmp_path / "r") / "comparison.json").read_text())
    _, groups, styles = figure13.simulation_groups(rows)
    matched = [k for k in groups if "matched lift" in k]
    paper = [k for k in groups if "paper's protocol" in k]
    assert len(matched) == 1 and matched[0].startswith("cycloid") and len(paper) == 2
    assert styles[matched[0]][1] is None and all(styles[k][1] == "//" for k in paper)  # paper: hatched
    _, paper_only, _ = figure13.simulation_groups([r for r in rows if r["set"] == "paper"])
    assert not any("matched" in k for k in paper_only)


def test_figure7_matches_the_baselines_at_table5s_lift_height(tmp_path):
    """Figure 7's solid baselines stand at the lift height Table 5 matches (a commanded path's mean over its
    legs), and each learned entry names it beside the LF leg's own peak."""
    learned = results.load_results(fake_results(tmp_path / "r")).learned
    first = next(iter(learned.values()))
    own = first.provenance["own_lift_height_m"]
    fig = figure7.draw(learned)
    labels = [ln.get_label() for ln in fig.axes[0].get_lines()]
    assert any(lab.startswith("composite cycloid") and f"H = {own:.3f} m (matched" in lab for lab in labels)
    assert any(f"H = {own:.3f} m" in lab for lab in labels if "learned" in lab)


def test_figure13_marks_every_prototype_walk_off_the_speed_band_and_says_it_scales(tmp_path):
    rows = json.loads((fake_results(tmp_path / "r") / "comparison.json").read_text())
    proto = [{"trajectory": "straight", "speed_mps": 1.0, "robot": r, "fell": False, "reached": True,
              "mean_speed_mps": v, "distance_m": 20.0, "battery_used_pct": 1.0}
             for r, v in (("ideal", 1.0), ("hardware", 1.0 - 2 * SPEED_BAND))]  # the second walked too slowly
    fig = figure13.draw(rows, proto)
    assert len(fig.axes) == 3  # (a), then (b) the ideal and (c) the hardware-like robot
    for ax, row in zip(fig.axes[1:], proto):
        assert row["robot"] in ax.get_title()
        (bar,) = [p for p in ax.patches if p.get_height() > 0]
        counts = speed_within_band(row["mean_speed_mps"], row["speed_mps"])
        assert (bar.get_alpha() or 1.0) == (1.0 if counts else FADED_ALPHA) and not bar.get_hatch()
        crosses = [ln for ln in ax.get_lines() if ln.get_marker() == figure13.MISS_MARKER]
        assert len(crosses) == (0 if counts else 1)
        assert [t.get_text() for t in ax.texts] == ([] if counts else ["1/1"])
        assert "20 m walks" in ax.get_title() and "100 m" in ax.get_title()
    assert not all(figure13.prototype_counts(r) for r in proto)


def shipped_figure13():
    rows = json.loads((SHIPPED_INPUTS / "comparison.json").read_text())
    return rows, figure13.draw(rows, json.loads((SHIPPED_INPUTS / "prototype.json").read_text()))


def test_figure13_each_mark_means_one_thing():
    """The shipped figure, one learned walk at 1.4 m/s marked as off the speed band: a hatch is used by one legend
    entry and only on the paper's-protocol bars of (a); a bar with walks that fell or left the speed band
    carries the ×, which has its own legend entry."""
    rows = json.loads((SHIPPED_INPUTS / "comparison.json").read_text())
    off = next(i for i, r in enumerate(rows) if r["set"] == "paper" and r["trajectory"] == "learned"
               and r["speed_command_mps"] == 1.4)
    rows[off] = dict(rows[off], valid=False, speed_ok=False, status="speed miss")
    fig = figure13.draw(rows, json.loads((SHIPPED_INPUTS / "prototype.json").read_text()))
    legend = fig.legends[0]
    hatches: dict[str, list[str]] = {}
    for handle, text in zip(legend.legend_handles, legend.get_texts()):
        if getattr(handle, "get_hatch", lambda: None)():
            hatches.setdefault(handle.get_hatch(), []).append(text.get_text())
    assert list(hatches) == [figure13.PAPER_HATCH] and len(hatches[figure13.PAPER_HATCH]) == 1
    assert "the paper's protocol" in hatches[figure13.PAPER_HATCH][0]
    paper = {(r["trajectory"], r["speed_command_mps"]) for r in rows
             if r["set"] == "paper" and r["trajectory"] in ("cycloid", "straight")}
    hatched = [p for p in fig.axes[0].patches if p.get_hatch()]
    assert len(hatched) == len(paper) and {p.get_hatch() for p in hatched} == {figure13.PAPER_HATCH}
    assert not any(p.get_hatch() for ax in fig.axes[1:] for p in ax.patches)
    missed = {r["speed_command_mps"] for r in rows if r["set"] == "paper" and not r["valid"]}
    crosses = [ln for ln in fig.axes[0].get_lines() if ln.get_marker() == figure13.MISS_MARKER]
    assert missed == {1.4} and len(crosses) == 1  # the learned bar at 1.4 m/s: 1 of 5 seeds off the band
    labels = [t.get_text() for t in legend.get_texts()]
    assert sum(lab.startswith("× k/n") for lab in labels) == 1
    assert not any("cross-hatched" in t for t in (fig.get_suptitle(), *labels))


def test_figure13s_legend_stays_under_the_panels():
    """Drawn from the shipped inputs (the README's figure): the one legend lies below every panel and its axis
    labels."""
    _, fig = shipped_figure13()
    renderer = FigureCanvasAgg(fig).get_renderer()
    legend = fig.legends[0].get_window_extent(renderer)
    for ax in fig.axes:
        assert legend.y1 < ax.get_tightbbox(renderer).y0, (legend, ax.get_title())


def write_metrics(folder: Path, episodes: dict[int, int]) -> Path:
    folder.mkdir(parents=True)
    lines = ["stage,stage_episode,score"] + [f"{s},{e},{np.sin(e)}" for s, n in episodes.items()
                                              for e in range(1, n + 1)]
    (folder / "metrics.csv").write_text("\n".join(lines) + "\n")
    return folder / "metrics.csv"


def test_figure6_names_its_run_and_labels_the_raw_scores(tmp_path):
    run = tmp_path / "policy_of_this_test"
    fig = figure6.draw([write_metrics(run, {1: 39, 2: 39})])
    assert run.name in fig.get_suptitle()
    for ax in fig.axes:
        raw = [ln for ln in ax.get_lines() if ln.get_alpha() == 0.25]
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert raw and raw[0].get_label() in legend


def test_figure6_names_the_run_by_recipe_and_smooths_both_stages_alike(tmp_path):
    """The shipped run's folders (table5/policy/seed0) give "table5, seed 0"; a short stage 1 and a long stage 2
    (37 and 400 episodes, as the shipped run) are smoothed over the same number of episodes, said in the legend."""
    path = write_metrics(tmp_path / "table5" / "policy" / "seed0", {1: 37, 2: 400})
    fig = figure6.draw([path])
    assert "table5, seed 0" in fig.get_suptitle() and "seed0" not in fig.get_suptitle()
    means = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_alpha() is None]
    assert len(means) == 2
    assert {ln.get_label() for ln in means} == {f"moving mean of {figure6.WINDOW_EPISODES} episodes"}
    w = figure6.WINDOW_EPISODES
    for ln in means:
        raw = [r for r in ln.axes.get_lines() if r.get_alpha() == 0.25][0].get_ydata()
        assert np.allclose(ln.get_ydata()[w - 1:], np.convolve(raw, np.ones(w) / w, mode="valid"))
    assert run_name(tmp_path / "runs" / "table5" / "seed5" / "stage2" / "metrics.csv") == "table5, seed 5 (stage2)"
    assert run_name(tmp_path / "quick_seed3" / "metrics.csv") == "quick, seed 3"


# ---- metrics.csv ------------------------------------------------------------------------------------------------
def test_metrics_reader_reads_what_the_logger_writes_and_drops_a_cut_last_line(tmp_path):
    from cyberdog.rl.logger import COLUMNS, EpisodeLogger

    log = EpisodeLogger(tmp_path, tensorboard=False)
    written = [{"stage": s, "episode": i, "stage_episode": i, "env_steps": 400 * i, "length": 400,
                "score": float(i) * s, "actor_loss": float("nan")} for s in (1, 2) for i in range(1, 6)]
    for row in written:
        log.log(row)
    log.close()
    with open(tmp_path / "metrics.csv", "a") as f:
        f.write("2,99,99,4")  # a write cut short: no newline
    stages = read_stages(tmp_path / "metrics.csv")
    assert sorted(stages) == [1, 2] and set(stages[1]) == set(COLUMNS)
    for s in (1, 2):
        mine = [r for r in written if r["stage"] == s]
        assert np.array_equal(stages[s]["score"], [r["score"] for r in mine])
        assert np.isnan(stages[s]["actor_loss"]).all() and np.isnan(stages[s]["energy_J"]).all()  # nan and ""
    assert len(read_rows(tmp_path / "metrics.csv")) == len(written)


def test_metrics_reader_skips_damaged_lines_and_missing_files(tmp_path):
    path = tmp_path / "metrics.csv"
    path.write_text("stage,score\n1,3.5\nx,2\n1,4.5,extra\n2\n2,7\n")
    stages = read_stages(path)
    assert {s: list(c["score"]) for s, c in stages.items()} == {1: [3.5], 2: [7.0]}
    assert read_stages(tmp_path / "none.csv") == {} and read_rows(tmp_path / "none.csv") == []


def test_learning_curves_read_back_what_the_csv_holds(tmp_path):
    rng = np.random.default_rng(1)
    data = {1: rng.normal(size=(5, len(NUMBER_COLUMNS))), 2: rng.normal(size=(3, len(NUMBER_COLUMNS)))}
    lines = ["stage," + ",".join(NUMBER_COLUMNS)]
    lines += [f"{s}," + ",".join(repr(float(x)) for x in row) for s, rows in data.items() for row in rows]
    (tmp_path / "learning_curves.csv").write_text("\n".join(lines) + "\n")
    curves = read_curves(tmp_path / "learning_curves.csv")
    for s, rows in data.items():
        for j, col in enumerate(NUMBER_COLUMNS):
            assert np.array_equal(curves[s][col], rows[:, j])
    paths = plots.draw_all(tmp_path, tmp_path / "out", only=["learning_curves"], pdf=False)
    assert [p.name for p in paths] == ["learning_curves.png"]


# ---- the command line ---------------------------------------------------------------------------------------------
def test_command_line_refuses_bad_input(tmp_path, capsys):
    from plots.__main__ import main

    with pytest.raises(SystemExit):
        main(["--from", str(tmp_path / "missing"), "--out", str(tmp_path / "o")])
    assert main(["--from", str(tmp_path), "--out", str(tmp_path / "o"), "--metrics", str(tmp_path / "m.csv")]) == 2
    assert "m.csv does not exist" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--from", str(tmp_path), "--out", str(tmp_path / "o"), "--only", "5"])


def test_exported_inputs_keep_the_searched_shapes_rows(tmp_path):
    """Table 5's row against the direct search's shape is made from the shipped comparison.json: the export keeps
    the reference rows beside Figure 13's."""
    full = fake_results(tmp_path / "full")
    rows = json.loads((full / "comparison.json").read_text())
    searched = {**rows[0], "trajectory": "searched", "label": "searched", "walk_id": 10_000}
    (full / "comparison.json").write_text(json.dumps(rows + [searched]))
    export_inputs(full, tmp_path / "small")
    exported = json.loads((tmp_path / "small" / "comparison.json").read_text())
    assert sum(r["trajectory"] == "searched" for r in exported) == 1
    assert len(exported) == len(rows) + 1


def test_figure10_takes_the_first_seed_that_walked_at_each_speed():
    """A seed without a path at a speed (compare --skip-missing-paths) gives way there to the next seed, whose
    matched baselines come with it."""
    def w(i, traj, seed, v, lift):
        return {"walk_id": i, "trajectory": traj, "seed": seed, "speed_command_mps": v, "lift_height_m": lift}
    walks = [w(0, "learned", "seed23", 1.2, 0.088), w(1, "learned", "seed24", 1.0, 0.092),
             w(2, "learned", "seed24", 1.2, 0.087), w(3, "cycloid", "", 1.0, 0.092), w(4, "cycloid", "", 1.2, 0.088),
             w(5, "cycloid", "", 1.2, 0.087)]
    chosen = figure10.chosen_walks(walks)
    assert chosen[1.0]["learned"]["seed"] == "seed24" and chosen[1.0]["cycloid"]["walk_id"] == 3
    assert chosen[1.2]["learned"]["seed"] == "seed23" and chosen[1.2]["cycloid"]["walk_id"] == 4
