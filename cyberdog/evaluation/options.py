"""What every part of `evaluate.py` may import: its usage error, the checks of option values, the defaults the
command line shares with the library, and the blocks of options several sub-commands take (each `add_*` adds one
block to a sub-command's parser). Imports neither the simulator nor numpy, so that `evaluate.py SUB --help`
answers at once; values are checked here, before any long work starts, with one-line errors naming the option.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from cyberdog.config import LEG_NAMES, add_override_option
from cyberdog.config.paper import (PAPER_DISTANCE_M, PAPER_SPEEDS, PAPER_WALK_DURATION, PROTOTYPE_DISTANCE_M,
                                   PROTOTYPE_DRAWS, PROTOTYPE_RUN_UP_S, SPEED_BAND)

# Literal copies of library constants whose modules import the simulator or numpy (a test keeps them equal):
BASELINE_CHOICES = ("cycloid", "straight")  # cyberdog.analysis.baselines.BASELINES
CYCLE_CHOICES = ("mean", "cheapest")  # cyberdog.analysis.extract.CYCLE_CHOICES
# the prototype run's defaults are the library's (cyberdog.config.paper): one set for the CLI and run_prototype
DEFAULT_PROTOTYPE_DISTANCE, DEFAULT_PROTOTYPE_DRAWS, DEFAULT_PROTOTYPE_RUN_UP = (PROTOTYPE_DISTANCE_M, PROTOTYPE_DRAWS,
                                                                            PROTOTYPE_RUN_UP_S)
DEFAULT_CANDIDATES = 1  # paths that replay, per speed, of which extraction keeps the cheapest on the check robots
# extract's settings a preset may choose (its `extract:`), with their defaults here; an option given on the command
# line wins over the preset's
EXTRACT_DEFAULTS = {"cycle": "mean", "rollout_duration": 10.0, "replay_attempts": 3, "candidates": DEFAULT_CANDIDATES,
                    "replay_check": True}


class UsageError(Exception):
    """Bad or missing input, reported in one line before any long work starts."""


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


# ---- blocks of options, each declared once --------------------------------------------------------------

def add_output_options(p) -> None:
    g = p.add_argument_group("walk config and output folder")
    g.add_argument("--config", type=Path, default=None,
                   help="YAML walk config, as an output's config.yaml holds it: WalkConfig sections (robot, "
                        "actuator, sim, gait, pid, controller, energy) and optionally hardware (read as training "
                        "reads env.hardware: over HardwareConfig(), every effect off); default: the built-in "
                        "defaults (paper lift height 0.15 m)")
    add_override_option(g, "gait.lift_height=0.1 --set gait.straight_shape=trapezoid",
                        "; hardware.FIELD sets a field (HardwareConfig: friction, latency_s, joint_angle_noise_std, "
                        "joint_velocity_noise_std, estimated_velocity, imu_noise, mass_uncertainty, seed, ...) of "
                        "the hardware-like robot of the walks that use one (prototype, stiffness, check's "
                        "hardware-like walks, video), laid over HARDWARE_LIKE, or over the --config file's hardware "
                        "section, e.g. --set hardware.latency_s=0.005; refused where no hardware-like robot walks "
                        "(there a --config file's hardware section is not used, and a note says so). The output's "
                        "config.yaml holds the walk config and the hardware section (null: the ideal robot only); "
                        "--config reads it back")
    g.add_argument("--no-recorded-trot", action="store_true",
                   help="walk under the config's trot controller even where the learned paths (or the policies "
                        "extracted) were recorded under another; by default every trajectory of a comparison walks "
                        "under the trot its learned paths were recorded under, unless --set controller.* or a "
                        "--config controller section chooses one")
    g.add_argument("--out", type=Path, default=None, help="output folder (default runs/evaluate-<time>)")
    g.add_argument("--force", action="store_true",
                   help="write into an --out folder that already holds results: the files previous evaluate.py runs "
                        "recorded there (outputs.json) are removed first; without --force such a folder is refused")


def add_speed_options(p, check=positive) -> None:
    p.add_argument("--speeds", type=check, nargs="+", default=list(PAPER_SPEEDS),
                   help="commanded speeds in m/s (default " + " ".join(f"{v:g}" for v in PAPER_SPEEDS) + ")")


def add_duration_option(p) -> None:
    p.add_argument("--duration", type=positive, default=PAPER_WALK_DURATION,
                   help=f"s per walk (default {PAPER_WALK_DURATION:g}, the paper's)")


def add_extract_workers_option(p) -> None:
    p.add_argument("--workers", dest="extract_workers", type=at_least_one, default=1, metavar="N",
                   help="extraction jobs (one per policy and speed) run at once in worker processes (default 1: "
                        "in turn, stopping at the first that fails; with more, every job runs, each path is saved "
                        "as its job ends, and the failures are reported together)")


def add_workers_option(p) -> None:
    p.add_argument("--workers", type=at_least_one, default=None, help="parallel walk processes (default: CPU count)")


def add_learned_option(p) -> None:
    p.add_argument("--learned", type=Path, nargs="+", default=None, metavar="FILE",
                   help="extracted trajectories (JSON/CSV files, or folders of JSON files): commanded paths (one "
                        "per seed and speed) or sampled x-z paths (one per seed, rescaled to every speed); "
                        "default results/table5/paths/ (the paper's Eq. 7 preset), and for the prototype run "
                        "results/battery/paths/ (the battery recipe) where it is shipped")


def add_extraction_options(p) -> None:
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
                   help="extraction rollouts (env seeds --rollout-seed, +1, ...) run per speed before giving up "
                        "(default 3)")
    g.add_argument("--candidates", type=positive_int, default=EXTRACT_DEFAULTS["candidates"], metavar="N",
                   help="commanded path: keep the first N candidates that replay (one per rollout) and extract "
                        "the one with the least electrical energy per metre on the replay check's hardware-like "
                        f"robots, which the prototype never walks (default {DEFAULT_CANDIDATES}: the first that "
                        "replays; the battery preset's shipped paths: 2, of up to 16 rollouts)")
    g.add_argument("--speed-tolerance", type=share, default=SPEED_BAND,
                   help=f"cycles within this share of the command qualify (default {SPEED_BAND:g})")
    g.add_argument("--leg", default="LF", choices=LEG_NAMES, help="measured path: the foot taken first, then the others")


def add_prototype_options(p) -> None:
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
    g.add_argument("--prototype-modes", nargs="+", default=["hardware"], choices=["ideal", "hardware"],
                   help="the robots the prototype walks: ideal (the paper's simulation) and hardware (friction, "
                        "latency, sensor noise, Kalman speed, mass draw: HARDWARE_LIKE) (default hardware; "
                        "'ideal hardware': both)")
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


def add_metrics_option(p) -> None:
    p.add_argument("--metrics", type=Path, nargs="+", default=None, metavar="CSV",
                   help="training logs for Figure 6 (default: the policies' metrics.csv, else "
                        "results/table5/policy/seed0/metrics.csv)")


def add_video_options(p) -> None:
    g = p.add_argument_group("video")
    g.add_argument("--video-trajectory", default="learned", choices=["learned", *BASELINE_CHOICES],
                   help="the foot trajectory the trot walks: the first learned path (its seed is named in the "
                        "frame and the file name) or a common one (default learned)")
    g.add_argument("--video-speed", type=positive, default=1.0, help="commanded speed, m/s (default 1.0)")
    g.add_argument("--video-duration", type=positive, default=4.0, help="s of simulated walking (default 4)")
    g.add_argument("--video-robot", default=None, choices=["ideal", "hardware"],
                   help="the robot the video walks: ideal (the paper's simulation) or hardware (the hardware-like "
                        "robot of --set hardware.*, HARDWARE_LIKE by default); default: hardware where hardware "
                        "settings are given (--set hardware.* or a --config file's hardware section), else ideal. "
                        "The frame names the robot and its PD gains")
    g.add_argument("--video-format", default="gif", choices=["gif", "mp4"],
                   help="gif (Pillow, always available) or mp4 (needs imageio[ffmpeg] or ffmpeg; default gif)")
