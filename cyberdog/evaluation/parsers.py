"""The options of each `evaluate.py` sub-command: one function per sub-command adds them to its parser, from the
blocks several share (`options`) and its own; `check`, `pd-match`, `stance-force`, `export` and `pick` keep theirs
beside their commands. `COMMANDS` lists every sub-command with its help and that function, in the order
`evaluate.py --help` lists them.
"""
from __future__ import annotations

from pathlib import Path

from cyberdog.evaluation import check, export, pd_match, pick, stance_force
from cyberdog.evaluation.options import (BASELINE_CHOICES, add_duration_option, add_extract_workers_option,
                                         add_extraction_options, add_learned_option, add_metrics_option,
                                         add_output_options, add_prototype_options, add_speed_options,
                                         add_video_options, add_workers_option, non_negative, positive)

HELP = {  # name: (one line for the list of sub-commands, the paragraph of its own --help)
    "all": ("compare + prototype + figures (+ --video) on the learned trajectories (the default)",
            "compare, prototype and figures (+ a video with --video) on the learned trajectories (default: "
            "Table 5 on results/table5/paths/, the paper preset's commanded paths, one per seed and speed; the "
            "prototype on results/battery/paths/, the battery recipe's; --learned "
            "FILE|DIR... (both), or --policies/--sweep to extract them first). Writes table5.md, "
            "table5_summary.*, table5.*, comparison.*, "
            "learned_mean_ci.* (several seeds), walks.json, power_traces.npz, prototype.*, prototype_gaps.* (both "
            "robots), "
            "figure{4,6,7,10,13}_*.{png,pdf} and learned/<label>.json (the trajectories used)."),
    "baselines": ("walk the composite cycloid and the straight line at each speed",
                  "walk --duration s at each of --speeds with the composite cycloid and straight-line "
                  "trajectories and print speed, drift, posture, energy (Eq. 7), energy per 100 m, CoT, peak "
                  "torque and joint speed. Writes baselines.{csv,json,md}."),
    "extract": ("roll out trained stage-2 policies and save their learned foot paths",
                "roll out trained stage-2 policies (--policy/--policies PATH, --sweep DIR) at each speed (a "
                "policy trained over a speed range: each of --speeds) and save the learned path "
                "(learned/<label>_<v>mps.json) and every cycle (learned/<label>_<v>mps_cycles.csv): the "
                "commanded foot path (trot path + the policy's per-leg shift, mean of the settled cycles within "
                "±5 % of the command) for foot-mode policies, or with --path measured the paper's way (the "
                "measured foot path of the cheapest cycle). Also draws Figure 7."),
    "compare": ("Section 4.1: Table 5, D_t (Eq. 12), Figures 10 and 13",
                "replay the learned, cycloid and straight-line trajectories with the IK + PID trot for "
                "--duration s at each speed; Table 5 (the headline: baselines at the learned path's own lift "
                "height; and the paper's protocol: baselines at 0.15 m), D_t by Eq. (12) on Eq. (7) and on the "
                "electrical energy, positive work and foot slip, and as a reference row the direct search's shape at "
                "the same lift (--reference); Figures 10 and 13."),
    "prototype": ("Section 4.2 in simulation: battery use and range",
                  "every learned seed's paths (default results/battery/paths/, the battery "
                  "recipe's, where shipped) and the common trajectories at their lift, walks of "
                  "--prototype-distance m (default "
                  "20; the paper's 100) on the ideal robot and on --prototype-draws hardware-like robots: battery "
                  "use (Eq. 13), range, energy per 100 m, cost of transport, mean ± 95 % CI across seeds, the "
                  "learned path's battery saving. Writes prototype.*, prototype_summary.* and, where both robots "
                  "walked, prototype_gaps.*."),
    "stiffness": ("the prototype run at several joint-PD stiffnesses: does the saving survive the gains?",
                  "the prototype run's walks (hardware-like robots by default) with every walk's joint PD scaled "
                  "by each of --pd-scales (kp x s, kd x sqrt(s), the damping ratio kept): the learned paths, the "
                  "common trajectories at their lift, the searched shape and, with --closed-loop, the policies "
                  "themselves; the battery saving against the cheaper common trajectory at each stiffness, mean "
                  "± 95 % CI across seeds, falls counted. Writes stiffness.{csv,json,md}, each seed's saving in "
                  "stiffness_seeds.{csv,json,md}, and stiffness_walks.json."),
    "figures": ("redraw Figures 4, 6, 7, 10, 13 from saved results",
                "Figures 4, 6, 7, 10 and 13 from saved results (--from DIR: a folder written by `all` or "
                "`compare`); by default they are written beside those results."),
    "video": ("a GIF (or MP4) of the trot with one trajectory",
              "a GIF (or MP4) of the trot with one trajectory (--video-trajectory, --video-speed) on the ideal or "
              "the hardware-like robot (--video-robot; --set hardware.* sets the latter), named in every frame "
              "with its PD gains."),
    "check": (check.LINE, check.PARAGRAPH),
    "pd-match": (pd_match.LINE, pd_match.PARAGRAPH),
    "stance-force": (stance_force.LINE, stance_force.PARAGRAPH),
    "export": (export.LINE, export.PARAGRAPH),
    "pick": (pick.LINE, pick.PARAGRAPH),
}


def _same_lift_option(p) -> None:
    p.add_argument("--no-same-lift", action="store_true",
                   help="skip the control set of baselines at the learned trajectory's lift height")


def _reference_options(p) -> None:
    g = p.add_argument_group("reference row of the matched-lift table")
    g.add_argument("--reference", type=Path, default=None, metavar="FILE",
                   help="a shape saved by tools/optimize_trajectory.py, walked at each speed at its own lift "
                        "height (default results/searched_shapes/optimized_trajectory_H0.095.json)")
    g.add_argument("--no-reference", action="store_true", help="no reference row")


def all_options(p) -> None:
    for add in (add_output_options, add_speed_options, add_duration_option, add_workers_option, add_learned_option,
                add_extraction_options, add_prototype_options, add_metrics_option, add_video_options):
        add(p)
    _same_lift_option(p)
    p.add_argument("--no-prototype", action="store_true", help="skip the prototype experiment")
    p.add_argument("--video", action="store_true", help="also write a video")
    _reference_options(p)


def baselines_options(p) -> None:
    add_output_options(p)
    add_speed_options(p, non_negative)
    add_duration_option(p)
    p.add_argument("--trajectories", nargs="+", default=list(BASELINE_CHOICES), choices=BASELINE_CHOICES,
                   help="which common trajectories to walk")


def extract_options(p) -> None:
    for add in (add_output_options, add_speed_options, add_extraction_options, add_extract_workers_option):
        add(p)


def compare_options(p) -> None:
    for add in (add_output_options, add_speed_options, add_duration_option, add_workers_option, add_learned_option,
                add_extraction_options):
        add(p)
    _same_lift_option(p)
    _reference_options(p)
    _skip_missing_option(p)


def _skip_missing_option(p) -> None:
    p.add_argument("--skip-missing-paths", action="store_true",
                   help="walk each speed with the seeds that have a learned path there: a seed whose extraction "
                        "found none at a speed walks nothing at it, and that speed's rows are over the other seeds "
                        "(named in the log; default: every seed must have every speed)")


def _prototype_walk_options(p) -> None:
    """What the prototype and stiffness runs share: the learned paths (or policies) walked on the prototype's robots."""
    for add in (add_output_options, add_speed_options, add_workers_option, add_learned_option, add_extraction_options,
                add_prototype_options):
        add(p)


def prototype_options(p) -> None:
    _prototype_walk_options(p)
    _skip_missing_option(p)
    p.add_argument("--pd-matched-from-default", action="store_true",
                   help="with gains set by --set pid.kp=... pid.kd=...: every walk's command (the learned paths' and "
                        "the common trajectories' alike, not a policy's) is re-solved so that those gains execute "
                        "the motion the default PD executes, the PD the paths were recorded under (as `stiffness "
                        "--pd-matched` for a stiffness factor; default: each walks its command as it is)")


def stiffness_options(p) -> None:
    _prototype_walk_options(p)
    p.add_argument("--pd-scales", type=positive, nargs="+", default=[0.7, 1.0, 1.4], metavar="S",
                   help="joint-PD stiffness factors (default 0.7 1.0 1.4; the battery preset's training draws kp "
                        "0.6-1.6x and kd 0.7-1.3x)")
    p.add_argument("--pd-matched", action="store_true",
                   help="at each stiffness, walk every path and trajectory (not a policy) with its command re-solved "
                        "for that PD, so that it executes the motion it executes under the configured PD (recorded "
                        "on the ideal robot; cyberdog.analysis.pd_match_recording)")


def figures_options(p) -> None:
    for add in (add_output_options, add_metrics_option, add_learned_option):
        add(p)
    p.add_argument("--from", dest="from_dir", type=Path, default=None, metavar="DIR",
                   help="the results folder to draw from (default: --out)")


def video_options(p) -> None:
    for add in (add_output_options, add_learned_option, add_extraction_options, add_video_options):
        add(p)


def check_options(p) -> None:
    add_output_options(p)
    add_workers_option(p)
    check.add_options(p)


def pd_match_options(p) -> None:
    add_output_options(p)
    pd_match.add_options(p)


def stance_force_options(p) -> None:
    add_output_options(p)
    stance_force.add_options(p)


def export_options(p) -> None:
    add_output_options(p)
    export.add_options(p)


def pick_options(p) -> None:
    add_output_options(p)
    pick.add_options(p)


ADD_OPTIONS = {"all": all_options, "baselines": baselines_options, "extract": extract_options,
               "compare": compare_options, "prototype": prototype_options, "stiffness": stiffness_options,
               "figures": figures_options, "video": video_options, "check": check_options,
               "pd-match": pd_match_options, "stance-force": stance_force_options, "export": export_options,
               "pick": pick_options}
COMMANDS = {name: (line, paragraph, ADD_OPTIONS[name]) for name, (line, paragraph) in HELP.items()}
