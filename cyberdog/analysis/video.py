"""A video of the scripted trot with a chosen foot trajectory, rendered headless (PyBullet TinyRenderer).

The walk is the same trot controller as `cyberdog.analysis.walk.walk`, on the ideal robot (true state feedback)
or on a hardware-like one (`HardwareConfig`); every `1 / fps` s of simulated time the camera that follows the
body (`Robot.render`) takes a frame, with the trajectory, speed, time, the energy so far and the robot walked
(ideal or hardware-like, the settings that differ from HARDWARE_LIKE's, the PD gains) written on it. GIF is
written with Pillow (no ffmpeg needed); MP4 needs `imageio` with its ffmpeg plugin, or matplotlib with an `ffmpeg`
binary on the PATH.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from cyberdog.analysis.robot_words import robot_words
from cyberdog.config import HardwareConfig, WalkConfig
from cyberdog.control.trot import TrotController
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.trajectories import FootTrajectory
from cyberdog.loop.walker import Walker

FORMATS = (".gif", ".mp4")


def render_walk(cfg: WalkConfig, trajectory: FootTrajectory | None = None, duration: float = 4.0,
                fps: int = 25, width: int = 480, height: int = 360, label: str = "",
                hardware: HardwareConfig | None = None, foot_offsets: FootOffsetPath | None = None,
                lift_height: float | None = None) -> list[np.ndarray]:
    """Frames (height, width, 3) uint8 of a `duration` s trot at `cfg.gait.speed` on the robot of `hardware`
    (None: the ideal robot); stops early on a fall. foot_offsets: a learned path's shift of each foot target
    (as `cyberdog.analysis.walk.walk` takes it); lift_height: m, the H written on the frames (default: the
    gait's)."""
    if not duration > 0:
        raise ValueError(f"video duration must be > 0 s, got {duration!r}")
    if not 1 <= fps <= 100:
        raise ValueError(f"fps must be in [1, 100], got {fps!r}")
    from PIL import Image, ImageDraw

    dt = cfg.sim.controller_dt
    every = max(1, int(round(1.0 / (fps * dt))))
    ctrl = TrotController(cfg, trajectory, foot_offsets)
    lift = cfg.gait.lift_height if lift_height is None else lift_height
    robot = robot_words(hardware, cfg.pid)
    frames = []
    with Walker(cfg, ctrl, hardware=hardware) as walker:
        start = walker.start
        for k in range(int(round(duration / dt))):
            walker.step()
            s, fell = walker.state, walker.fallen()
            if k % every == 0 or fell:
                energy = walker.energy()  # Eq. (7) so far
                img = Image.fromarray(walker.robot.render(width, height, distance=1.0, yaw_deg=60.0,
                                                          pitch_deg=-15.0))
                text = (f"{label or ctrl.trajectory.name}  v_cmd = {ctrl.speed:.1f} m/s  H = "
                        f"{lift:.3f} m\nt = {k * dt:5.2f} s  x = {s.base_position[0] - start[0]:5.2f} m"
                        f"  E = {energy:6.1f} J (Eq. 7)" + ("  FELL" if fell else "") + f"\n{robot}")
                ImageDraw.Draw(img).multiline_text((8, 6), text, fill=(0, 0, 0))
                frames.append(np.asarray(img))
            if fell:
                break
    return frames


def mp4_writer_problem() -> str | None:
    """Why an MP4 cannot be written here (None if it can): checked before any frame is rendered."""
    import importlib.util

    if importlib.util.find_spec("imageio") and importlib.util.find_spec("imageio_ffmpeg"):
        return None
    if shutil.which("ffmpeg") is not None:
        return None
    return ("MP4 needs imageio with its ffmpeg plugin (pip install 'imageio[ffmpeg]') or an ffmpeg binary on the "
            "PATH, and neither is here; write a GIF instead (--video-format gif, the default)")


def write_video(frames: list[np.ndarray], path: str | Path, fps: int = 25) -> Path:
    """Write frames as GIF (Pillow) or MP4 (imageio-ffmpeg, else matplotlib + ffmpeg), by the suffix."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"video file must end in one of {FORMATS}, got {path.name!r}")
    if not frames:
        raise ValueError("no frames to write")
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() == ".gif":
        from PIL import Image

        images = [Image.fromarray(f) for f in frames]
        images[0].save(path, save_all=True, append_images=images[1:], duration=int(round(1000 / fps)), loop=0)
        return path
    try:
        import imageio.v2 as imageio  # optional

        imageio.mimwrite(path, frames, fps=fps)
        return path
    except ImportError:
        pass
    if shutil.which("ffmpeg") is None:
        raise RuntimeError("MP4 needs imageio[ffmpeg] or an ffmpeg binary on the PATH; write a .gif instead")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FFMpegWriter

    h, w = frames[0].shape[:2]
    fig = plt.figure(figsize=(w / 100, h / 100), dpi=100)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.axis("off")
    im = ax.imshow(frames[0])
    writer = FFMpegWriter(fps=fps)
    with writer.saving(fig, str(path), dpi=100):
        for f in frames:
            im.set_data(f)
            writer.grab_frame()
    plt.close(fig)
    return path


def record_video(cfg: WalkConfig, trajectory: FootTrajectory | None, path: str | Path, duration: float = 4.0,
                 fps: int = 25, width: int = 480, height: int = 360, label: str = "",
                 hardware: HardwareConfig | None = None, foot_offsets: FootOffsetPath | None = None,
                 lift_height: float | None = None) -> Path:
    """Render a trot (`render_walk`, on the robot of `hardware`, the feet shifted by `foot_offsets`) and write
    it to `path` (.gif or .mp4); returns the path."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"video file must end in one of {FORMATS}, got {path.name!r}")
    frames = render_walk(cfg, trajectory, duration, fps, width, height, label, hardware, foot_offsets, lift_height)
    return write_video(frames, path, fps)


__all__ = ["FORMATS", "record_video", "render_walk", "write_video"]
