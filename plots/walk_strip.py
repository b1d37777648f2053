"""The picture at the top of the README: the robot trotting at 1.0 m/s with the learned battery gait (above)
and with the composite cycloid at the same lift height (below), five frames over the last whole gait period.

Rendering runs physics, so `evaluate.py video` renders the walks (PyBullet's TinyRenderer, headless, the
camera following the body, a frame every 0.04 s); this module only picks frames out of the two GIFs it
writes, crops them, saves them as the strip's input and draws the strip. The shipped picture is made by:

    .venv/bin/python evaluate.py video --learned results/battery/paths --video-speed 1.0 \\
        --video-duration 3 --out runs/walk_strip/learned --force
    .venv/bin/python evaluate.py video --config runs/walk_strip/learned/config.yaml \\
        --video-trajectory cycloid --set gait.lift_height=0.110 --video-speed 1.0 \\
        --video-duration 3 --out runs/walk_strip/cycloid --force
    .venv/bin/python -m plots.walk_strip runs/walk_strip/learned runs/walk_strip/cycloid \\
        --save-inputs results/figures_input --out plots/png

The cycloid walks under the learned run's config.yaml (the trot controller the battery paths were recorded
under) at the learned path's lift height, 0.110 m: the LF leg's peak of seed 0's path, which the video
replays on all four legs; each row's label gives the H its run walked. The last command writes
`results/figures_input/walk_strip.npz` (the cropped frames, their times and the rows' labels) and
`plots/png/walk_strip.png`; `python -m plots --from results/figures_input --out plots/png --readme` redraws the
PNG from the saved frames.
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from cyberdog import config as C
from cyberdog.core.learned_set import LearnedSet
from plots.style import NAMES, save_figure, styled

STEM = "walk_strip"
INPUT_NAME = "walk_strip.npz"  # in a figures-input folder (results/figures_input/)
FRAMES = 5  # per row, evenly over one gait period
CROP = (110, 100, 430, 360)  # px (left, top, right, bottom) of evaluate.py's 480 x 360 frame: the robot, no text
TILE_PX = 180  # px: each frame's width in the strip (the saved frames are scaled to it)
VIDEO_NAME = re.compile(r"^trot_(?P<name>.+)_(?P<speed>[0-9.]+)mps\.gif$")  # as `evaluate.py video` names it


@dataclass
class StripInput:
    """The strip's saved input: per row (walk) the same frame times, and the row's label."""

    frames: np.ndarray  # uint8 (rows, frames, height, width, 3)
    times_s: np.ndarray  # s since the walk started, one per column (the same in every row)
    labels: list[str]  # per row
    speed_mps: float
    period_s: float  # the gait period the columns span

    def save(self, folder: str | Path) -> Path:
        path = Path(folder) / INPUT_NAME
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, frames=self.frames, times_s=self.times_s, labels=np.array(self.labels),
                            speed_mps=self.speed_mps, period_s=self.period_s)
        return path

    @classmethod
    def load(cls, path: str | Path) -> "StripInput":
        with np.load(path, allow_pickle=False) as z:
            return cls(frames=z["frames"], times_s=z["times_s"], labels=[str(s) for s in z["labels"]],
                       speed_mps=float(z["speed_mps"]), period_s=float(z["period_s"]))


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


def video_run(folder: str | Path) -> tuple[Path, str, float, float]:
    """(GIF, row label, speed m/s, gait period s) of an `evaluate.py video` run folder, from what it saved: the
    GIF's name (trajectory, seed, speed), config.yaml (period; a baseline's H) and learned/ (a learned H)."""
    folder = Path(folder)
    gifs = [p for p in sorted(folder.glob("trot_*.gif")) if VIDEO_NAME.match(p.name)]
    if len(gifs) != 1:
        raise ValueError(f"{folder} should hold one GIF written by `evaluate.py video`, found {len(gifs)}")
    m = VIDEO_NAME.match(gifs[0].name)
    name, speed = m["name"], float(m["speed"])
    gait = C.load_walked(folder / "config.yaml").walk.gait
    if name.startswith("learned_"):
        seed = name.removeprefix("learned_")
        lift = LearnedSet.load([folder / "learned"]).at(speed)[seed].figure_path().lift_height
        recipe = learned_recipe(folder)
        label = f"{NAMES['learned']}, {recipe + ' recipe, ' if recipe else ''}{seed.replace('seed', 'seed ')}"
    else:
        lift, label = gait.lift_height, NAMES.get(name, name)
    return gifs[0], f"{label}, H = {lift:.3f} m", speed, gait.period


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
    """The strip's input from `evaluate.py video` run folders (one row each, in order)."""
    runs = [video_run(f) for f in folders]
    speeds, periods = {r[2] for r in runs}, {r[3] for r in runs}
    if len(speeds) != 1 or len(periods) != 1:
        raise ValueError(f"the videos differ in speed {sorted(speeds)} or gait period {sorted(periods)}")
    videos = [read_gif(r[0]) for r in runs]
    period = periods.pop()
    picks = pick([t for _, t in videos], period, n)
    frames = np.stack([[crop(f[i]) for i in idx] for (f, _), idx in zip(videos, picks)])
    return StripInput(frames=frames, times_s=videos[0][1][picks[0]], labels=[r[1] for r in runs],
                      speed_mps=speeds.pop(), period_s=period)


@styled
def draw(strip: StripInput, dpi: int = 80) -> Figure:
    """One row per walk (its label above it), one column per frame (its time at the top); each frame drawn at
    its own pixel size at `dpi`, the layout laid out in pixels."""
    rows, cols, h, w, _ = strip.frames.shape
    gap, title, head, label = (round(pt * dpi / 72) for pt in (3, 17, 12, 13))  # pt → px: the text scales
    width, height = cols * w + (cols - 1) * gap, title + head + rows * (label + h + gap)
    fig = Figure(figsize=(width / dpi, height / dpi))
    fig.text(0.5, 1 - 4 / height, f"The trot at {strip.speed_mps:g} m/s over one gait period (T = "
             f"{strip.period_s:g} s), simulated in PyBullet", ha="center", va="top", fontsize=10)
    for c, t in enumerate(strip.times_s):
        fig.text((c * (w + gap) + w / 2) / width, 1 - (title + 2) / height, f"t = {t:.2f} s", ha="center",
                 va="top", fontsize=8)
    for r, (row, text) in enumerate(zip(strip.frames, strip.labels)):
        top = title + head + r * (label + h + gap)  # px from the figure's top
        fig.text(2 / width, 1 - (top + 2) / height, text, ha="left", va="top", fontsize=9)
        for c, frame in enumerate(row):
            ax = fig.add_axes(((c * (w + gap)) / width, 1 - (top + label + h) / height, w / width, h / height))
            ax.imshow(frame, interpolation="none")
            ax.set_axis_off()
    return fig


def walk_strip(input_dir: str | Path, out_dir: str | Path, dpi: int = 80, pdf: bool = True) -> list[Path]:
    """Draw the strip from `input_dir`'s walk_strip.npz into `out_dir` (its frames at their own size at `dpi`)."""
    return save_figure(draw(StripInput.load(Path(input_dir) / INPUT_NAME), dpi), out_dir, STEM, dpi, pdf)


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


__all__ = ["CROP", "FRAMES", "INPUT_NAME", "STEM", "StripInput", "draw", "extract", "main", "pick", "read_gif",
           "video_run", "walk_strip"]

if __name__ == "__main__":
    sys.exit(main())
