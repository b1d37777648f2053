"""The parts `evaluate.py` is made of: the comparison walks (Section 4.1), the prototype experiment (Section
4.2), the figures and the video. Each writes its results into `out` and prints its table."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cyberdog import config as C
from cyberdog.analysis import compare as cmp
from cyberdog.analysis import table5 as t5
from cyberdog.analysis.report import markdown_table, write_rows
from cyberdog.core.learned_set import LearnedSet
from cyberdog.evaluation.options import UsageError

FIGURES = ("figure4", "figure6", "figure7", "figure10", "figure13")


def run_compare(cfg: C.WalkConfig, learned: LearnedSet, speeds: list[float], duration: float, same_lift: bool,
                workers: int | None, out: Path, log=print, reference=None, brief: bool = False,
                skip_missing: bool = False) -> tuple[list, list, dict]:
    """Comparison walks → comparison.*, table5.*, walks.json, power_traces.npz; returns (rows, walks, power).
    reference: the direct search's shape (a SampledTrajectory) for the matched-lift table's reference row.
    skip_missing: a seed without a path at a speed walks nothing there, and is named.
    brief: print a progress line per quarter of the walks and the headline's main rows only (the full tables
    are in the files)."""
    for p in learned.paths():
        if p.period is not None and abs(p.period - cfg.gait.period) > 1e-9:
            log(f"warning: {p.label} was recorded with a {p.period} s gait period; the baselines walk "
                f"{cfg.gait.period} s")
    if reference is not None:
        lifts = [p.lift_height for p in learned.paths()]
        gap = abs(reference.lift_height - sum(lifts) / len(lifts))
        log(f"reference row: the direct search's best shape, searched at H = {reference.lift_height:.3f} m"
            + (f" ({1e3 * gap:.1f} mm from the learned paths' mean lift height: compare with care)"
               if gap > 2e-3 else ""))
    if skip_missing:
        _log_skipped("comparison", learned, speeds, log)
    jobs = cmp.comparison_jobs(cfg, learned, speeds, duration, same_lift=same_lift, reference=reference,
                               skip_missing=skip_missing)
    log(f"comparison: {len(jobs)} walks of {duration:g} s")
    walks = cmp.run_jobs(jobs, workers, log, every_walk=not brief)
    power = {w["walk_id"]: w.pop("power_W") for w in walks}
    rows = cmp.comparison_rows(walks, cfg.gait.lift_height)
    means = cmp.seed_means(rows)
    write_rows(rows, out, "comparison")
    (out / "comparison.md").write_text(markdown_table(rows, cmp.COLUMNS) + "\n")
    write_rows(t5.table5_rows(rows), out, "table5")
    # every walk of the paper's set, per seed (the matched-lift walks, one baseline pair per seed and lift
    # height, are in comparison.md; the summaries above average them)
    table5 = t5.table5_markdown([r for r in rows if r["set"] == "paper"], means)
    summary = t5.summary_rows(rows)
    write_rows(summary, out, "table5_summary")
    headline = "\n\n".join(
        f"{title}\n\n{t5.summary_markdown(summary, set_name)}"
        for set_name, title in (("same_lift", "Matched conditions: the baselines at the learned path's own lift "
                                              "height, same step length and period (the headline)"),
                                ("paper", "The paper's protocol: the baselines at H = "
                                          f"{cfg.gait.lift_height:g} m"))
        if t5.summary_markdown(summary, set_name))
    (out / "table5.md").write_text("Table 5: energy consumption of the foot trajectories at each speed\n\n"
                                   + headline + "\n\nEvery walk of the paper's protocol (E in kJ over the walk; the "
                                   "matched-lift walks are in comparison.md)\n\n" + table5 + "\n")
    if len(learned) > 1:
        write_rows(means, out, "learned_mean_ci")
    (out / "walks.json").write_text(json.dumps(walks, indent=1))
    np.savez_compressed(out / "power_traces.npz", **{f"walk_{i}": p for i, p in power.items()})
    if brief:
        _print_brief_table5(summary, cfg.gait.lift_height)
        return rows, walks, power
    print("\nTable 5: energy consumption of the foot trajectories over the walk\n")
    print(headline)
    print("\nEvery walk of the paper's protocol (E in kJ over the walk; matched-lift walks: comparison.md)\n")
    print(table5)
    print("\nAll walks (energy per 100 m, cost of transport, mean speed over the last half):\n")
    print(markdown_table(rows, cmp.COLUMNS))
    return rows, walks, power


def _print_brief_table5(summary: list[dict], paper_lift: float) -> None:
    """The main job's Table 5: the matched-lift summary's main rows, and the paper's protocol in one line."""
    matched = t5.summary_markdown(summary, "same_lift", brief=True)
    paper = [r for r in summary if r["set"] == "paper"]
    print("\nTable 5 at matched lift (mean ± 95 % CI over seeds; in full: table5.md):\n")
    print(matched or t5.summary_markdown(summary, "paper", brief=True))
    if matched and paper:
        print(f"\nThe paper's protocol (baselines at H = {paper_lift:g} m): D_t on E "
              + " / ".join(f"{r['D_t_pct_mean']:.1f} %" for r in paper)
              + " at " + " / ".join(f"{r['speed_command_mps']:g}" for r in paper) + " m/s")


def run_prototype_part(cfg: C.WalkConfig, learned: LearnedSet, speeds: list[float], distance_m: float,
                       modes: list[str], workers: int | None, out: Path, log=print, brief: bool = False,
                       draws: int = 1, reference=None, run_up_s: float = 0.0, policies: dict | None = None,
                       hardware: C.HardwareConfig = C.HARDWARE_LIKE, skip_missing: bool = False,
                       pd_matched_from: C.PIDConfig | None = None) -> list[dict]:
    """Section 4.2 in simulation, at scale: every learned seed's paths and both common trajectories at their
    lift heights, on the robots of `modes` (the ideal one; `draws` hardware-like ones) → prototype.*,
    prototype_summary.*.
    `reference`: a searched shape (SampledTrajectory) walked beside them as the row "searched", under the trot it
    was searched under.
    `run_up_s`: s walked from the stand before the measured `distance_m` (`run_prototype`).
    `policies`: {label: actor file}, the policies that walk beside their paths, closed loop (row "policy").
    `hardware`: the hardware-like robots' effects (each draw its own seed of them).
    `skip_missing`: a seed without a path at a speed walks nothing there (`run_prototype`), and is named.
    `pd_matched_from`: the PD the walks' commands are re-solved from, for `cfg.pid` (`run_prototype`).
    `brief`: a progress line per quarter of the walks and the summary's main numbers only."""
    from cyberdog.analysis.prototype import prototype_table, run_prototype, write_prototype
    from cyberdog.evaluation.recorded_trot import searched_controller
    from cyberdog.analysis.prototype_summary import REFERENCE, summary_rows

    trajectories = {"cycloid": None, "straight": None, **({REFERENCE: reference} if reference is not None else {})}
    policies = dict(policies or {})
    _log_prototype_walks(learned, speeds, distance_m, modes, len(trajectories), draws, run_up_s, policies,
                         skip_missing, searched=reference is not None, log=log)
    rows = run_prototype(trajectories, speeds=speeds, distance_m=distance_m, modes=modes, workers=workers,
                         base_cfg=cfg, log=log, every_walk=not brief, learned=learned, draws=draws,
                         run_up_s=run_up_s, policies=policies, hardware=hardware,
                         own_trot=searched_controller(reference, cfg.controller, log), skip_missing=skip_missing,
                         pd_matched_from=pd_matched_from)
    write_prototype(rows, out)
    if not brief:
        print(f"\nPrototype experiment (Section 4.2) in simulation: {distance_m:g} m walks after a {run_up_s:g} s "
              f"run-up (paper: 100 m from a stand)\n")
        print(prototype_table(rows))
        return rows
    print(f"\nPrototype run, {len(learned)} seeds x {draws} hardware-like robots (battery % per 100 m, Eq. 13, "
          f"mean ± 95 % CI across seeds; {distance_m:g} m walks after a {run_up_s:g} s run-up; in full: "
          f"prototype.md):")
    _print_prototype_summary(summary_rows(rows), modes, [*(["policy"] if policies else []), *trajectories],
                             speeds, searched=reference is not None)
    return rows


def _log_skipped(part: str, learned: LearnedSet, speeds: list[float], log) -> list[tuple[str, float]]:
    """Name the (label, speed) pairs without a learned path, which `part` does not walk (--skip-missing-paths);
    returns them."""
    missing = [(label, v) for v in speeds for label in learned.labels if not learned.has(label, v)]
    if missing:
        log(f"{part}: no learned path, so no walk, for " + ", ".join(f"{label} at {v:g} m/s" for label, v in missing)
            + ": those speeds' rows are over the other seeds")
    return missing


def _log_prototype_walks(learned: LearnedSet, speeds: list[float], distance_m: float, modes: list[str],
                         n_trajectories: int, draws: int, run_up_s: float, policies: dict, skip_missing: bool,
                         searched: bool, log) -> None:
    """The prototype run's plan in one line (how many walks of what, `n_trajectories` beside each learned path),
    after the seeds and speeds it skips."""
    robots = sum(draws if m == "hardware" else 1 for m in modes)
    missing = _log_skipped("prototype", learned, speeds, log) if skip_missing else []
    pairs = len(learned) * len(speeds) - len(missing)
    log(f"prototype: {(pairs * (n_trajectories + 1) + len(policies) * len(speeds)) * robots} walks of "
        f"{distance_m:g} m "
        f"{f'after a {run_up_s:g} s run-up ' if run_up_s > 0 else 'from a stand '}"
        f"({len(learned)} learned seeds, each with the common trajectories"
        f"{' and the searched shape' if searched else ''} at its lift "
        f"height{f', {len(policies)} policies closed loop' if policies else ''}; "
        f"{draws} hardware-like robot{'s' * (draws > 1)})")


def _print_prototype_summary(summary: list[dict], modes: list[str], others: list[str], speeds: list[float],
                             searched: bool) -> None:
    """Per robot, the battery per 100 m of the learned paths and of `others` (rows) at each speed, and the learned
    paths' saving."""
    for mode in modes:
        cells = [f"{name} " + " / ".join(f"{r['battery_pct_per_100m_mean']:.2f}" for r in summary
                                         if r["trajectory"] == name and r["robot"] == mode)
                 for name in ("learned", *others)]
        print(f"  {mode:8s} " + "   ".join(cells) + f"  at {' / '.join(f'{v:g}' for v in speeds)} m/s")
        saving = [r for r in summary if r["trajectory"] == "learned" and r["robot"] == mode]
        print(f"  {'':8s} learned saves " + " / ".join(
            f"{r['battery_saving_pct_mean']:.1f} ± {r['battery_saving_pct_ci95']:.1f} %" for r in saving)
              + " of the battery against the cheaper common trajectory at its lift"
              + ("; against the searched shape " + " / ".join(
                  f"{r['battery_vs_searched_pct_mean']:.1f} %" for r in saving) if searched else "")
              + "".join(f"; {r['walks'] - r['counted']} learned walk(s) at {r['speed_mps']:g} m/s did not count "
                        f"({r['fell']} fell)" for r in saving if r["counted"] < r["walks"]))


def run_figures(draw, results_dir: Path, out: Path | None = None, *, metrics: dict | None = None, learned=None,
                only=None, log=print) -> list[Path]:
    """The figures of `only` (default: all) that the results saved in `results_dir` have inputs for, drawn into
    `out` (default: beside the results) by `draw(results_dir, out, metrics, only, learned=...)`: the checkout's
    `plots.draw_all`, which `evaluate.py` passes in (from the saved files only, never running physics). Without
    it (the package run on its own) the results are written and the figures left to `python -m plots`."""
    if draw is None:
        log(f"figures: not drawn here (no figure code given); from a checkout: python -m plots --from {results_dir}")
        return []
    try:
        return draw(results_dir, out or results_dir, metrics, only, learned=learned)
    except (OSError, ValueError) as err:  # a missing or unreadable input file: the user's to fix
        raise UsageError(f"figures: {err}") from None


def run_video(cfg: C.WalkConfig, learned: LearnedSet | None, args, out: Path) -> Path:
    """A GIF/MP4 of the trot with --video-trajectory at --video-speed, on the robot of --video-robot (the
    hardware-like one: `args.hardware`, as --set hardware.* and --config make it)."""
    from cyberdog.analysis.robot_words import robot_words
    from cyberdog.analysis.video import record_video
    from cyberdog.evaluation.walked_robot import video_robot

    name = label = args.video_trajectory
    traj = offsets = None
    lift = cfg.gait.lift_height
    vcfg = cmp.walk_config(cfg, name, args.video_speed, lift)
    if name == "learned":  # walked as the tables walk it: a commanded path moves each foot on its own path
        seed, learned_path = next(iter(learned.at(args.video_speed).items()))
        vcfg, traj, offsets = learned_path.walk_args(cfg, args.video_speed)
        lift = learned_path.lift_height  # its own, the H the tables match (a commanded path's: its feet's mean peak)
        label = f"learned, {seed}"  # which of the learned paths the video walks
        name = f"learned_{seed}"
    hardware = args.hardware if video_robot(args) == "hardware" else None
    path = out / f"trot_{name}_{args.video_speed:g}mps.{args.video_format}"
    print(f"video: the trot with the {label} trajectory at {args.video_speed:g} m/s, {args.video_duration:g} s, "
          f"on the {robot_words(hardware, vcfg.pid)}")
    return record_video(vcfg, traj, path, args.video_duration, label=label, hardware=hardware,
                        foot_offsets=offsets, lift_height=lift)


__all__ = ["FIGURES", "run_compare", "run_figures", "run_prototype_part", "run_video"]
