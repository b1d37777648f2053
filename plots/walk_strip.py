"""The picture at the top of the README: the robot trotting at 1.0 m/s with the learned battery gait (above)
and with the composite cycloid at the same lift height (below), five frames over the last whole gait period,
and beside them the foot paths the two walks command, where they differ.

Rendering runs physics, so `evaluate.py video` renders the walks (PyBullet's TinyRenderer, headless, the
camera following the body, a frame every 0.04 s); this module only picks frames out of the two GIFs it
writes, crops them, saves them as the strip's input and draws the strip. The shipped picture is made by:

    .venv/bin/python evaluate.py video --learned results/battery/paths --video-speed 1.0 \\
        --video-duration 3 --out runs/walk_strip/learned --force
    .venv/bin/python evaluate.py video --config runs/walk_strip/learned/config.yaml \\
        --video-trajectory cycloid --set gait.lift_height=0.0989 --video-speed 1.0 \\
        --video-duration 3 --out runs/walk_strip/cycloid --force
    .venv/bin/python -m plots.walk_strip runs/walk_strip/learned runs/walk_strip/cycloid \\
        --save-inputs results/figures_input --out plots/png

The learned row walks seed 0's commanded path as the tables walk it, each foot on its own path; the cycloid
walks under the learned run's config.yaml (the trot controller the battery paths were recorded under) at that
path's own lift height, 0.0989 m (its four feet's mean peak, the H the prototype run matches the common
trajectories at); each row's label gives the H its run walked, and the title the robot (config.yaml's hardware
section; a row's label where the rows differ). The last command writes `results/figures_input/walk_strip.npz` (the
cropped frames, their times, the rows' labels, lifts, robots and foot paths) and `plots/png/walk_strip.png`;
`python -m plots --from results/figures_input --out plots/png --readme` redraws the PNG from the saved frames.
Where the folder also holds the prototype run's walks (`prototype.json`), each row's label adds the battery that
path and that cycloid used there (per 100 m, the same seed's hardware-like robots).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from cyberdog import config as C
from cyberdog.analysis.prototype_summary import METRICS, walk_counts
from cyberdog.analysis.robot_words import robot_name
from cyberdog.core.commanded_path import LEG_NAMES
from cyberdog.core.learned_set import LearnedSet
from cyberdog.core.trajectories import make_trajectory
from plots.figure4 import cycle_path
from plots.style import COLORS, NAMES, save_figure, styled

STEM = "walk_strip"
INPUT_NAME = "walk_strip.npz"  # in a figures-input folder (results/figures_input/)
FRAMES = 5  # per row, evenly over one gait period
CROP = (110, 100, 430, 360)  # px (left, top, right, bottom) of evaluate.py's 480 x 360 frame: the robot, no text
TILE_PX = 160  # px: each frame's width in the strip (the saved frames are scaled to it)
PATH_POINTS = 200  # per foot path drawn
PANEL_PX = 300  # px: the foot paths' panel width
LIFT_TOLERANCE_M = 5e-4  # a common trajectory's lift matches a learned path's (rows of prototype.json) within this
VIDEO_NAME = re.compile(r"^trot_(?P<name>.+)_(?P<speed>[0-9.]+)mps\.gif$")  # as `evaluate.py video` names it


@dataclass
class StripInput:
    """The strip's saved input: per row (walk) the same frame times, the row's label, what it walked (trajectory,
    the seed of the learned path it walks or matches, lift, robot) and the four feet's commanded x–z paths."""

    frames: np.ndarray  # uint8 (rows, frames, height, width, 3)
    times_s: np.ndarray  # s since the walk started, one per column (the same in every row)
    labels: list[str]  # per row
    speed_mps: float
    period_s: float  # the gait period the columns span
    trajectories: list[str]  # per row: "learned", "cycloid", ... (prototype.json's `trajectory`)
    seeds: list[str]  # per row: the learned path's seed ("seed0"), a common trajectory's at its lift, else ""
    lifts_m: np.ndarray  # (rows,) m: the H each row walked (a learned path's own)
    feet_xz: np.ndarray  # (rows, 4, PATH_POINTS, 2) m: LF, RF, LH, RH's commanded path, contact level z = 0
    robots: list[str]  # per row: the robot walked ("ideal robot", "hardware-like robot (latency 5 ms)")

    def save(self, folder: str | Path) -> Path:
        path = Path(folder) / INPUT_NAME
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, frames=self.frames, times_s=self.times_s, labels=np.array(self.labels),
                            speed_mps=self.speed_mps, period_s=self.period_s,
                            trajectories=np.array(self.trajectories), seeds=np.array(self.seeds),
                            lifts_m=self.lifts_m, feet_xz=self.feet_xz, robots=np.array(self.robots))
        return path

    @classmethod
    def load(cls, path: str | Path) -> "StripInput":
        """The input saved at `path`; a file without every field is a ValueError naming the command that re-makes
        it from the video runs."""
        with np.load(path, allow_pickle=False) as z:
            missing = [f.name for f in dataclasses.fields(cls) if f.name not in z.files]
            if missing:
                raise ValueError(f"{path} has no {', '.join(missing)} (another format of the strip's input): re-make "
                                 f"it from the video runs with python -m plots.walk_strip RUN... --save-inputs "
                                 f"{Path(path).parent} --out DIR (plots/walk_strip.py's docstring has the commands)")
            strings = {name: [str(s) for s in z[name]] for name in ("labels", "trajectories", "seeds", "robots")}
            return cls(frames=z["frames"], times_s=z["times_s"], speed_mps=float(z["speed_mps"]),
                       period_s=float(z["period_s"]), lifts_m=z["lifts_m"], feet_xz=z["feet_xz"], **strings)


def read_gif(path: str | Path) -> tuple[list[np.ndarray], np.ndarray]:
    """The frames of a GIF as RGB arrays and the time (s) each is shown from (its frame durations summed)."""
    from PIL import Image, ImageSequence

    frames, times, t = [], [], 0.0
    with Image.open(path) as im:
        for f in ImageSequence.Iterator(im):
            frames.append(np.asarray(f.convert("RGB")))
            times.append(t)
            t += f.info.get("duration", 40) / 1000.0
    return frames, np.asarray(times)


def learned_recipe(folder: Path) -> str:
    """The recipe of the learned paths a video run walked: "battery" for --learned results/battery/paths."""
    record = folder / "outputs.json"
    argv = json.loads(record.read_text())["runs"][-1]["argv"] if record.is_file() else []
    if "--learned" not in argv[:-1]:
        return ""
    src = Path(argv[argv.index("--learned") + 1])
    return src.parent.name if src.name == "paths" else src.stem


@dataclass
class VideoRun:
    """What an `evaluate.py video` run folder walked (`video_run`)."""

    gif: Path
    label: str
    speed_mps: float
    period_s: float  # the gait period walked
    trajectory: str  # "learned" or the common trajectory's name
    seed: str  # the learned path's ("seed0"), "" for a common trajectory
    lift_m: float  # the H walked (a learned path's own: a commanded path's four feet's mean peak)
    feet_xz: np.ndarray  # (4, PATH_POINTS, 2) m: each foot's commanded x–z path over one gait cycle
    robot: str  # the robot walked (`robot_name` of config.yaml's hardware section)


def video_run(folder: str | Path) -> VideoRun:
    """What an `evaluate.py video` run folder walked, from what it saved: the GIF's name (trajectory, seed,
    speed), config.yaml (the robot; the gait of a common trajectory or a measured path, a common trajectory's H)
    and learned/ (the learned path, its H and its feet; a commanded path's own gait)."""
    folder = Path(folder)
    gifs = [p for p in sorted(folder.glob("trot_*.gif")) if VIDEO_NAME.match(p.name)]
    if len(gifs) != 1:
        raise ValueError(f"{folder} should hold one GIF written by `evaluate.py video`, found {len(gifs)}")
    m = VIDEO_NAME.match(gifs[0].name)
    name, speed = m["name"], float(m["speed"])
    walked = C.load_walked(folder / "config.yaml")
    gait = walked.walk.gait
    if name.startswith("learned_"):
        seed = name.removeprefix("learned_")
        path = LearnedSet.load([folder / "learned"]).at(speed)[seed]
        gait = path.path.gait if path.commanded else gait  # a commanded path walks its own gait
        feet = [path.path.as_sampled(leg) for leg in LEG_NAMES] if path.commanded else [path.figure_path()] * 4
        xz = [cycle_path(f, f.step_length, f.lift_height, gait.swing_time, gait.stance_time, PATH_POINTS)[1]
              for f in feet]
        recipe = learned_recipe(folder)
        label = f"{NAMES['learned']}, {recipe + ' recipe, ' if recipe else ''}{seed.replace('seed', 'seed ')}"
        trajectory, lift = "learned", path.lift_height
    else:
        seed, trajectory, lift, label = "", name, gait.lift_height, NAMES.get(name, name)
        common = C.replace(gait, trajectory=name, speed=speed)
        xz = [cycle_path(make_trajectory(common), common.step_length, lift, gait.swing_time, gait.stance_time,
                         PATH_POINTS)[1]] * 4
    return VideoRun(gifs[0], f"{label}, H = {lift:.3f} m", speed, gait.period, trajectory, seed, lift,
                    np.stack(xz), robot_name(walked.hardware))


def pick(times: list[np.ndarray], period: float, n: int = FRAMES) -> list[np.ndarray]:
    """Per video, the indices of `n` frames evenly spread over the last whole gait period every video has."""
    last = min(np.floor((t[-1] + 1e-9) / period) * period for t in times)  # end of the last whole period shown
    if last < period:
        raise ValueError(f"the videos are shorter than one gait period ({period:g} s)")
    wanted = last - period + np.arange(n) * period / n
    return [np.array([int(np.argmin(np.abs(t - w))) for w in wanted]) for t in times]


def crop(frame: np.ndarray, width: int = TILE_PX) -> np.ndarray:
    """The robot's part of a frame (`CROP`, without the text line), scaled to `width` px."""
    from PIL import Image

    img = Image.fromarray(frame).crop(CROP)
    return np.asarray(img.resize((width, round(img.height * width / img.width)), Image.LANCZOS))


def extract(folders: list[str | Path], n: int = FRAMES) -> StripInput:
    """The strip's input from `evaluate.py video` run folders (one row each, in order). A common trajectory
    walked at a learned row's lift is that row's seed's matched trajectory (its seed, for the prototype's rows)."""
    runs = [video_run(f) for f in folders]
    speeds, periods = {r.speed_mps for r in runs}, {r.period_s for r in runs}
    if len(speeds) != 1 or len(periods) != 1:
        raise ValueError(f"the videos differ in speed {sorted(speeds)} or gait period {sorted(periods)}")
    videos = [read_gif(r.gif) for r in runs]
    period = periods.pop()
    picks = pick([t for _, t in videos], period, n)
    frames = np.stack([[crop(f[i]) for i in idx] for (f, _), idx in zip(videos, picks)])
    learned = [r for r in runs if r.trajectory == "learned"]
    seeds = [r.seed or next((q.seed for q in learned if abs(q.lift_m - r.lift_m) <= LIFT_TOLERANCE_M), "")
             for r in runs]
    return StripInput(frames=frames, times_s=videos[0][1][picks[0]], labels=[r.label for r in runs],
                      speed_mps=speeds.pop(), period_s=period, trajectories=[r.trajectory for r in runs],
                      seeds=seeds, lifts_m=np.array([r.lift_m for r in runs]),
                      feet_xz=np.stack([r.feet_xz for r in runs]), robots=[r.robot for r in runs])


def prototype_battery(strip: StripInput, walks: list[dict]) -> list[float | None]:
    """Per row, battery % per 100 m of the prototype run's walks (`walks`, prototype.json's rows) of the same
    trajectory, seed, speed and lift on the hardware-like robots at the default PD, averaged over the draws that
    count; None where none does."""
    out = []
    for trajectory, seed, lift in zip(strip.trajectories, strip.seeds, strip.lifts_m):
        used = [METRICS["battery_pct_per_100m"](w) for w in walks
                if w["trajectory"] == trajectory and str(w.get("seed", "")) == seed and seed
                and w.get("robot") == "hardware" and w.get("pd_scale", 1.0) == 1.0 and not w.get("pd_matched")
                and abs(w["speed_mps"] - strip.speed_mps) < 1e-9
                and abs(w["lift_height_m"] - lift) <= LIFT_TOLERANCE_M and walk_counts(w)]
        out.append(sum(used) / len(used) if used else None)
    return out


@styled
def draw(strip: StripInput, dpi: int = 80, battery: list[float | None] | None = None) -> Figure:
    """One row per walk (its label above it, with `battery`'s % per 100 m where given), one column per frame (its
    time at the top), each frame at its own pixel size at `dpi`; at the right, every row's commanded foot paths.
    The robot walked is named in the title where every row walked the same one, else in each row's label."""
    rows, cols, h, w, _ = strip.frames.shape
    gap, title, head, label = (round(pt * dpi / 72) for pt in (3, 17, 12, 13))  # pt → px: the text scales
    battery = battery or [None] * rows
    note = label if any(b is not None for b in battery) else 0  # a line saying where the battery comes from
    frames_w = cols * w + (cols - 1) * gap
    width, height = frames_w + 4 * gap + PANEL_PX, title + head + rows * (label + h + gap) + note
    fig = Figure(figsize=(width / dpi, height / dpi))
    one_robot = len(set(strip.robots)) == 1
    fig.text(0.5, 1 - 4 / height, f"The trot at {strip.speed_mps:g} m/s over one gait period (T = "
             f"{strip.period_s:g} s), simulated in PyBullet" + (f" ({strip.robots[0]})" if one_robot else ""),
             ha="center", va="top", fontsize=10)
    for c, t in enumerate(strip.times_s):
        fig.text((c * (w + gap) + w / 2) / width, 1 - (title + 2) / height, f"t = {t:.2f} s", ha="center",
                 va="top", fontsize=8)
    for r, (row, text, b, robot) in enumerate(zip(strip.frames, strip.labels, battery, strip.robots)):
        top = title + head + r * (label + h + gap)  # px from the figure's top
        text += ("" if one_robot else f", {robot}") + ("" if b is None else f"; battery {b:.2f} % per 100 m in "
                                                                             "the prototype run")
        fig.text(2 / width, 1 - (top + 2) / height, text, ha="left", va="top", fontsize=9)
        for c, frame in enumerate(row):
            ax = fig.add_axes(((c * (w + gap)) / width, 1 - (top + label + h) / height, w / width, h / height))
            ax.imshow(frame, interpolation="none")
            ax.set_axis_off()
    if note:
        fig.text(2 / width, note / height, "battery: the prototype run's walks of the same path and cycloid (same "
                 "seed, speed and H) on hardware-like robots, the mean of the draws", ha="left", va="top", fontsize=8)
    panel = (frames_w + 4 * gap + 34, note + 30, PANEL_PX - 40, rows * (label + h + gap) - 30)  # px: x, y, w, h
    feet_panel(fig.add_axes((panel[0] / width, panel[1] / height, panel[2] / width, panel[3] / height)), strip)
    return fig


def feet_panel(ax, strip: StripInput) -> None:
    """Each row's four feet's commanded x–z paths (cm; a common trajectory's four are one), in the row's colour."""
    for trajectory, seed, lift, feet in zip(strip.trajectories, strip.seeds, strip.lifts_m, strip.feet_xz):
        color = COLORS.get(trajectory, "black")
        name = NAMES.get(trajectory, trajectory) + (f", {seed.replace('seed', 'seed ')}" if trajectory == "learned"
                                                    and seed else "")
        alike = all(np.allclose(f, feet[0]) for f in feet)
        for k, f in enumerate(feet[:1] if alike else feet):
            ax.plot(100 * f[:, 0], 100 * f[:, 1], color=color, lw=2.0 if alike else 1.2, ls="--" if alike else "-",
                    label=None if k else f"{name}{'' if alike else ', its 4 feet'}, H = {lift:.3f} m")
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + 0.45 * (high - low))  # room for the legend above the paths
    ax.set_title("the feet's commanded paths", fontsize=9)
    ax.set_xlabel("x from the hip's neutral point (cm)", fontsize=8)
    ax.set_ylabel("z above the contact level (cm)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, loc="upper center", frameon=False)


def walk_strip(input_dir: str | Path, out_dir: str | Path, dpi: int = 80, pdf: bool = True) -> list[Path]:
    """Draw the strip from `input_dir`'s walk_strip.npz into `out_dir` (its frames at their own size at `dpi`),
    each row's battery from the prototype run's walks beside it (`prototype.json`) where it has them."""
    strip = StripInput.load(Path(input_dir) / INPUT_NAME)
    walks = Path(input_dir) / "prototype.json"
    battery = prototype_battery(strip, json.loads(walks.read_text())) if walks.is_file() else None
    return save_figure(draw(strip, dpi, battery), out_dir, STEM, dpi, pdf)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m plots.walk_strip", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", type=Path, nargs="+", metavar="RUN", help="`evaluate.py video` run folders, a row each")
    p.add_argument("--save-inputs", type=Path, required=True, metavar="DIR",
                   help=f"where the cropped frames go ({INPUT_NAME}; the README's: results/figures_input)")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="where walk_strip.png goes")
    p.add_argument("--frames", type=int, default=FRAMES, help=f"frames per row (default {FRAMES})")
    args = p.parse_args(argv)
    if args.frames < 1:
        p.error(f"--frames must be >= 1, got {args.frames}")
    try:
        saved = extract(args.runs, args.frames).save(args.save_inputs)
        paths = [saved, *walk_strip(args.save_inputs, args.out, pdf=False)]
    except (ValueError, OSError, KeyError) as err:
        print(f"python -m plots.walk_strip: error: {err}", file=sys.stderr)
        return 2
    print("wrote " + ", ".join(map(str, paths)))
    return 0


__all__ = ["CROP", "FRAMES", "INPUT_NAME", "STEM", "StripInput", "VideoRun", "draw", "extract", "feet_panel", "main",
           "pick", "prototype_battery", "read_gif", "video_run", "walk_strip"]

if __name__ == "__main__":
    sys.exit(main())
