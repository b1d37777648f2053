"""The command line of `evaluate.py`: one sub-parser per sub-command, each with only the options it uses.

Options shared by several sub-commands are declared once, in parent parsers. This module imports neither
the simulator nor numpy, so that `evaluate.py SUB --help` answers at once; values are checked here, before
any long work starts, with one-line errors naming the option.
"""
from __future__ import annotations

import argparse
import difflib
import math
import sys
from pathlib import Path

from cyberdog.config import LEG_NAMES, add_override_option
from cyberdog.config.paper import (PAPER_DISTANCE_M, PAPER_SPEEDS, PAPER_WALK_DURATION, PROTOTYPE_DISTANCE_M,
                                   PROTOTYPE_DRAWS, PROTOTYPE_RUN_UP_S, SPEED_BAND)
from cyberdog.evaluation import check, pd_match

# Literal copies of library constants whose modules import the simulator or numpy (a test keeps them equal):
BASELINE_CHOICES = ("cycloid", "straight")  # cyberdog.analysis.baselines.BASELINES
CYCLE_CHOICES = ("mean", "cheapest")  # cyberdog.analysis.extract.CYCLE_CHOICES
# the prototype run's defaults are the library's (cyberdog.config.paper): one set for the CLI and run_prototype
DEFAULT_PROTOTYPE_DISTANCE, DEFAULT_PROTOTYPE_DRAWS, DEFAULT_PROTOTYPE_RUN_UP = (PROTOTYPE_DISTANCE_M, PROTOTYPE_DRAWS,
                                                                            PROTOTYPE_RUN_UP_S)
DEFAULT_COMMAND = "all"
DEFAULT_CANDIDATES = 1  # paths that replay, per speed, of which extraction keeps the cheapest on the check robots
# extract's settings a preset may choose (its `extract:`), with their defaults here; an option given on the command
# line wins over the preset's
EXTRACT_DEFAULTS = {"cycle": "mean", "rollout_duration": 10.0, "replay_attempts": 3, "candidates": DEFAULT_CANDIDATES,
                    "replay_check": True}


class UsageError(Exception):
    """Bad or missing input, reported in one line before any long work starts."""


DESCRIPTION = """\
Evaluate foot trajectories on the simulated CyberDog (paper Sections 3 and 4).

Without a sub-command, `all` runs. `evaluate.py SUB --help` lists the options of one sub-command.

Outputs go to --out (default runs/evaluate-<time>/), never over inputs; a folder that already holds results is
refused unless --force (which first removes the files earlier runs recorded in its outputs.json); every file a
run writes is listed at the end and recorded in outputs.json; the last line names the folder.
"""

COMMANDS = {  # name: (one line for the list of sub-commands, the paragraph of its own --help)
    "all": ("compare + prototype + figures (+ --video) on the learned trajectories (the default)",
            "compare, prototype and figures (+ a video with --video) on the learned trajectories (default: "
            "Table 5 on results/table5/paths/, the paper preset's commanded paths, one per seed and speed; the "
            "prototype on results/battery/paths/, the battery recipe's; --learned "
            "FILE|DIR... (both), or --policies/--sweep to extract them first). Writes table5.md, "
            "table5_summary.*, table5.*, comparison.*, "
            "learned_mean_ci.* (several seeds), walks.json, power_traces.npz, prototype.*, prototype_gaps.*, "
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
                  "learned path's battery saving. Writes prototype.*, prototype_summary.* and prototype_gaps.*."),
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
              "a GIF (or MP4) of the trot with one trajectory (--video-trajectory, --video-speed)."),
    "check": (check.LINE, check.PARAGRAPH),
    "pd-match": (pd_match.LINE, pd_match.PARAGRAPH),
}


# ---- value checks: argparse turns ArgumentTypeError into "evaluate.py SUB: error: argument --x: ..." --------

def _number(text: str, kind, ok, allowed: str):
    try:
        value = kind(text)
    except ValueError:
        value = None
    if value is None or not ok(value):
        raise argparse.ArgumentTypeError(f"must be {allowed}, got {text!r}")
    return value


def positive(text: str) -> float:
    return _number(text, float, lambda v: math.isfinite(v) and v > 0, "a number > 0")


def positive_int(text: str) -> int:
    return _number(text, int, lambda v: v >= 1, "a whole number >= 1")


def non_negative(text: str) -> float:
    return _number(text, float, lambda v: math.isfinite(v) and v >= 0, "a number >= 0")


def share(text: str) -> float:
    return _number(text, float, lambda v: 0 < v < 1, "a number in (0, 1)")


def at_least_one(text: str) -> int:
    return _number(text, int, lambda v: v >= 1, "a whole number >= 1")


# ---- parent parsers: each group of options declared once ----------------------------------------------------

def _parent() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(add_help=False)


def _output_options() -> argparse.ArgumentParser:
    p = _parent()
    g = p.add_argument_group("walk config and output folder")
    g.add_argument("--config", type=Path, default=None,
                   help="YAML walk config (WalkConfig sections: robot, actuator, sim, gait, pid, controller, "
                        "energy); default: the built-in defaults (paper lift height 0.15 m)")
    add_override_option(g, "gait.lift_height=0.1 --set gait.straight_shape=trapezoid",
                        "; hardware.FIELD sets the hardware-like robot of the prototype and stiffness walks, as "
                        "training's env.hardware (HardwareConfig: friction, latency_s, joint_angle_noise_std, "
                        "joint_velocity_noise_std, estimated_velocity, imu_noise, mass_uncertainty, ...), e.g. "
                        "--set hardware.latency_s=0.005")
    g.add_argument("--no-recorded-trot", action="store_true",
                   help="walk under the config's trot controller even where the learned paths (or the policies "
                        "extracted) were recorded under another; by default every trajectory of a comparison walks "
                        "under the trot its learned paths were recorded under, unless --set controller.* or a "
                        "--config controller section chooses one")
    g.add_argument("--out", type=Path, default=None, help="output folder (default runs/evaluate-<time>)")
    g.add_argument("--force", action="store_true",
                   help="write into an --out folder that already holds results: the files earlier evaluate.py runs "
                        "recorded there (outputs.json) are removed first; without --force such a folder is refused")
    return p


def _speed_options(check=positive) -> argparse.ArgumentParser:
    p = _parent()
    p.add_argument("--speeds", type=check, nargs="+", default=list(PAPER_SPEEDS),
                   help="commanded speeds in m/s (default " + " ".join(f"{v:g}" for v in PAPER_SPEEDS) + ")")
    return p


def _duration_option() -> argparse.ArgumentParser:
    p = _parent()
    p.add_argument("--duration", type=positive, default=PAPER_WALK_DURATION,
                   help=f"s per walk (default {PAPER_WALK_DURATION:g}, the paper's)")
    return p


def _extract_workers_option() -> argparse.ArgumentParser:
    p = _parent()
    p.add_argument("--workers", dest="extract_workers", type=at_least_one, default=1, metavar="N",
                   help="extraction jobs (one per policy and speed) run at once in worker processes (default 1: "
                        "in turn, stopping at the first that fails; with more, every job runs, each path is saved "
                        "as its job ends, and the failures are reported together)")
    return p


def _workers_option() -> argparse.ArgumentParser:
    p = _parent()
    p.add_argument("--workers", type=at_least_one, default=None, help="parallel walk processes (default: CPU count)")
    return p


def _learned_option() -> argparse.ArgumentParser:
    p = _parent()
    p.add_argument("--learned", type=Path, nargs="+", default=None, metavar="FILE",
                   help="extracted trajectories (JSON/CSV files, or folders of JSON files): commanded paths (one "
                        "per seed and speed) or sampled x-z paths (one per seed, rescaled to every speed); "
                        "default results/table5/paths/ (the paper's Eq. 7 preset), and for the prototype run "
                        "results/battery/paths/ (the battery recipe) where it is shipped")
    return p


def _extraction_options() -> argparse.ArgumentParser:
    p = _parent()
    g = p.add_argument_group("extraction from trained policies")
    g.add_argument("--policies", "--policy", dest="policies", type=Path, nargs="+", default=None, metavar="PATH",
                   help="stage-2 actor files or training run folders: extract their trajectories first")
    g.add_argument("--sweep", type=Path, default=None, metavar="DIR",
                   help="a folder of training runs (one per seed): extract each run's trajectory first")
    g.add_argument("--policy-speed", type=positive, default=None,
                   help="m/s commanded in the extraction rollout (default: each of --speeds for a policy trained "
                        "over a speed range, else the policy's training speed)")
    g.add_argument("--path", dest="path_kind", default="auto", choices=("auto", "commanded", "measured"),
                   help="'commanded' (the foot targets the policy commanded: trot path + its per-leg shift), "
                        "'measured' (the paper's: forward kinematics of the joint angles, one leg), or 'auto' "
                        "(default): commanded for foot-mode policies, else measured")
    g.add_argument("--cycle", default=EXTRACT_DEFAULTS["cycle"], choices=CYCLE_CHOICES,
                   help="commanded path: average the settled in-band cycles (default) or take the cheapest")
    g.add_argument("--rollout-duration", type=positive, default=EXTRACT_DEFAULTS["rollout_duration"],
                   help="s of each extraction rollout (default 10)")
    g.add_argument("--rollout-seed", type=int, default=0, help="env seed of the extraction rollout")
    g.add_argument("--no-replay-check", dest="replay_check", action="store_false",
                   default=EXTRACT_DEFAULTS["replay_check"],
                   help="keep a path without replaying it first (as --sweep of a recipe whose extract: says "
                        "replay_check: false does, configs/table5.yaml's). By default a commanded path that falls or "
                        "misses the speed in a 10 s and a 100 m replay on the ideal robot, in 100 m walks on six "
                        "hardware-like robots with the PD at 1, 0.7 and 1.4x, or in the prototype's 20 m walk on "
                        "eight more at each of 0.7 and 1.4x, none of them a prototype robot, is rejected for the "
                        "next candidate (the other --cycle choice, then the rollout of the next env seed); a measured "
                        "path must walk Table 5's 10 s at every speed (else the next cheapest cycle, then rollout)")
    g.add_argument("--replay-attempts", type=positive_int, default=EXTRACT_DEFAULTS["replay_attempts"], metavar="N",
                   help="extraction rollouts (env seeds --rollout-seed, +1, ...) tried per speed before giving up "
                        "(default 3)")
    g.add_argument("--candidates", type=positive_int, default=EXTRACT_DEFAULTS["candidates"], metavar="N",
                   help="commanded path: keep the first N candidates that replay (one per rollout) and extract "
                        "the one with the least electrical energy per metre on the replay check's hardware-like "
                        f"robots, which the prototype never walks (default {DEFAULT_CANDIDATES}: the first that "
                        "replays; the battery preset's shipped paths: 2, of up to 16 rollouts)")
    g.add_argument("--speed-tolerance", type=share, default=SPEED_BAND,
                   help=f"cycles within this share of the command qualify (default {SPEED_BAND:g})")
    g.add_argument("--leg", default="LF", choices=LEG_NAMES, help="measured path: the foot tried first, then others")
    return p


def _prototype_options() -> argparse.ArgumentParser:
    p = _parent()
    g = p.add_argument_group("prototype experiment (Section 4.2)")
    g.add_argument("--prototype-distance", type=positive, default=DEFAULT_PROTOTYPE_DISTANCE,
                   help=f"m per walk (default {DEFAULT_PROTOTYPE_DISTANCE:g}, so that the default run stays under "
                        f"5 min on 2 cores; the paper's is {PAPER_DISTANCE_M:g}: about 5x the time). Battery use "
                        "and range are also reported per 100 m")
    g.add_argument("--prototype-run-up", type=non_negative, default=DEFAULT_PROTOTYPE_RUN_UP, metavar="S",
                   help=f"s each walk walks from its stand before the measured distance starts (default "
                        f"{DEFAULT_PROTOTYPE_RUN_UP:g}: the speed ramp, over which a learned path blends in, and the "
                        f"speed's settling); its battery use is left out, as a start-up is of a range on a full "
                        f"charge. 0 = "
                        f"the paper's walk from a stand, whose start-up weighs 5x more in a 20 m walk than in 100 m")
    g.add_argument("--prototype-modes", nargs="+", default=["ideal", "hardware"], choices=["ideal", "hardware"],
                   help="the robots the prototype walks: ideal (the paper's simulation) and hardware (friction, "
                        "latency, sensor noise, Kalman speed, mass draw: HARDWARE_LIKE) (default both; for stiffness, "
                        "hardware)")
    g.add_argument("--prototype-draws", type=positive_int, default=DEFAULT_PROTOTYPE_DRAWS, metavar="N",
                   help=f"hardware-like robots (each its own mass draw and sensor noise) every learned seed's path "
                        f"and the common trajectories at its lift walk on (default {DEFAULT_PROTOTYPE_DRAWS}); every "
                        f"learned seed walks, and the tables give mean ± 95 %% CI across seeds")
    g.add_argument("--prototype-reference", type=Path, default=None, metavar="FILE",
                   help="a shape saved by tools/optimize_trajectory.py walked beside the common trajectories at each "
                        "learned path's lift as the reference row \"searched\", under the trot it was searched under "
                        "(default results/searched_shapes/optimized_trajectory_H0.085_electrical_hardware.json: "
                        "searched for the battery on the hardware-like robot, the cheapest such shape under any "
                        "shipped trot)")
    g.add_argument("--no-prototype-reference", action="store_true", help="no reference row in the prototype run")
    g.add_argument("--closed-loop", type=Path, nargs="+", default=None, metavar="ACTOR",
                   help="stage-2 actor files whose policies walk the same protocol themselves, closed loop, as the "
                        "row \"policy\" (each beside the learned path of its seed: seed<N>, from its config)")
    return p


def _metrics_option() -> argparse.ArgumentParser:
    p = _parent()
    p.add_argument("--metrics", type=Path, nargs="+", default=None, metavar="CSV",
                   help="training logs for Figure 6 (default: the policies' metrics.csv, else "
                        "results/table5/policy/seed0/metrics.csv)")
    return p


def _video_options() -> argparse.ArgumentParser:
    p = _parent()
    g = p.add_argument_group("video")
    g.add_argument("--video-trajectory", default="learned", choices=["learned", *BASELINE_CHOICES],
                   help="the foot trajectory the trot walks: the first learned path (its seed is named in the "
                        "frame and the file name) or a common one (default learned)")
    g.add_argument("--video-speed", type=positive, default=1.0, help="commanded speed, m/s (default 1.0)")
    g.add_argument("--video-duration", type=positive, default=4.0, help="s of simulated walking (default 4)")
    g.add_argument("--video-format", default="gif", choices=["gif", "mp4"],
                   help="gif (Pillow, always available) or mp4 (needs imageio[ffmpeg] or ffmpeg; default gif)")
    return p


# ---- the parser ---------------------------------------------------------------------------------------------

class _Parser(argparse.ArgumentParser):
    """An unknown option that another sub-command takes is named with the sub-commands that take it."""

    known: dict[str, list[str]] = {}  # option string -> sub-commands that accept it, filled by build_parser

    def error(self, message):
        if message.startswith("unrecognized arguments:"):
            hints = [f"{opt} is an option of: {', '.join(self.known[opt])}"
                     for opt in message.split(":", 1)[1].split() if opt in self.known]
            if hints:
                message += " (" + "; ".join(hints) + ")"
        super().error(message)


def build_parser() -> argparse.ArgumentParser:
    output, speeds, duration, workers = _output_options(), _speed_options(), _duration_option(), _workers_option()
    learned, extraction, prototype = _learned_option(), _extraction_options(), _prototype_options()
    metrics, video = _metrics_option(), _video_options()
    parents = {
        "all": [output, speeds, duration, workers, learned, extraction, prototype, metrics, video],
        "baselines": [output, _speed_options(non_negative), duration],
        "extract": [output, speeds, extraction, _extract_workers_option()],
        "compare": [output, speeds, duration, workers, learned, extraction],
        "prototype": [output, speeds, workers, learned, extraction, prototype],
        "stiffness": [output, speeds, workers, learned, extraction, prototype],
        "figures": [output, metrics, learned],
        "video": [output, learned, extraction, video],
        "check": [output, workers],
        "pd-match": [output],
    }
    top = _Parser(prog="evaluate.py", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    subs = top.add_subparsers(dest="command", metavar="SUB-COMMAND", parser_class=_Parser, required=True)
    sub = {}
    for name, (line, paragraph) in COMMANDS.items():
        sub[name] = subs.add_parser(name, parents=parents[name], help=line, description=f"{name}: {paragraph}")
    # the options only one sub-command has
    sub["all"].add_argument("--no-same-lift", action="store_true",
                            help="skip the control set of baselines at the learned trajectory's lift height")
    sub["all"].add_argument("--no-prototype", action="store_true", help="skip the prototype experiment")
    sub["all"].add_argument("--video", action="store_true", help="also write a video")
    sub["compare"].add_argument("--no-same-lift", action="store_true",
                                help="skip the control set of baselines at the learned trajectory's lift height")
    for name in ("all", "compare"):
        g = sub[name].add_argument_group("reference row of the matched-lift table")
        g.add_argument("--reference", type=Path, default=None, metavar="FILE",
                       help="a shape saved by tools/optimize_trajectory.py, walked at each speed at its own lift "
                            "height (default results/searched_shapes/optimized_trajectory_H0.095.json)")
        g.add_argument("--no-reference", action="store_true", help="no reference row")
    sub["prototype"].add_argument("--skip-missing-paths", action="store_true",
                                  help="walk each speed with the seeds that have a learned path there: a seed whose "
                                       "extraction found none at a speed walks nothing at it, and that speed's rows "
                                       "are over the other seeds (named in the log; default: every seed must have "
                                       "every speed)")
    sub["prototype"].add_argument("--pd-matched-from-default", action="store_true",
                                  help="with gains set by --set pid.kp=... pid.kd=...: every walk's command (the "
                                       "learned paths' and the common trajectories' alike, not a policy's) is "
                                       "re-solved so that those gains execute the motion the default PD executes, "
                                       "the PD the paths were recorded under (as `stiffness --pd-matched` for a "
                                       "stiffness factor; default: each walks its command as it is)")
    sub["stiffness"].add_argument("--pd-scales", type=positive, nargs="+", default=[0.7, 1.0, 1.4], metavar="S",
                                  help="joint-PD stiffness factors (default 0.7 1.0 1.4; the battery preset's training "
                                       "draws kp 0.6-1.6x and kd 0.7-1.3x)")
    sub["stiffness"].add_argument("--pd-matched", action="store_true",
                                  help="at each stiffness, walk every path and trajectory (not a policy) with its "
                                       "command re-solved for that PD, so that it executes the motion it executes "
                                       "under the configured PD (recorded on the ideal robot; "
                                       "cyberdog.analysis.pd_match_recording)")
    sub["stiffness"].set_defaults(prototype_modes=["hardware"])
    sub["baselines"].add_argument("--trajectories", nargs="+", default=list(BASELINE_CHOICES),
                                  choices=BASELINE_CHOICES, help="which common trajectories to walk")
    check.add_options(sub["check"])
    pd_match.add_options(sub["pd-match"])
    sub["figures"].add_argument("--from", dest="from_dir", type=Path, default=None, metavar="DIR",
                                help="the results folder to draw from (default: --out)")
    known: dict[str, list[str]] = {}
    for name, p in sub.items():
        for action in p._actions:
            for opt in action.option_strings:
                if opt not in ("-h", "--help"):
                    known.setdefault(opt, []).append(name)
    _Parser.known = known
    top.sub_commands = sub
    return top


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Parse `argv` (without the program name); no sub-command means `all`, as in `evaluate.py --out DIR`.
    An option the sub-command does not take ends the program (status 2) with a line naming the sub-commands
    that do take it."""
    argv = list(argv)
    if argv and not argv[0].startswith("-") and argv[0] not in COMMANDS:  # a word where a sub-command goes
        close = difflib.get_close_matches(argv[0], COMMANDS, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        print(f"evaluate.py: error: unknown sub-command '{argv[0]}' (one of {', '.join(COMMANDS)}){hint}",
              file=sys.stderr)
        raise SystemExit(2)
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help")):
        argv.insert(0, DEFAULT_COMMAND)
    top = build_parser()
    args, extras = top.parse_known_args(argv)
    if extras:  # reported by the sub-command's parser, with its own usage line
        top.sub_commands[args.command].error(f"unrecognized arguments: {' '.join(extras)}")
    return args


__all__ = ["BASELINE_CHOICES", "COMMANDS", "CYCLE_CHOICES", "DEFAULT_PROTOTYPE_DISTANCE", "DEFAULT_PROTOTYPE_DRAWS",
           "UsageError",
           "build_parser", "parse_args"]
