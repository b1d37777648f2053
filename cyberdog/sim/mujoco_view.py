"""Offscreen pictures of a MuJoCo world (`MujocoRobot.render`), headless included.

MuJoCo picks its OpenGL backend once, when first imported (MUJOCO_GL; GLFW by default, which needs a display),
and other packages may import it first (torchrl does). On a Linux machine without a display the view makes its own
EGL context instead (`mujoco.egl`), unless MUJOCO_GL names another backend; elsewhere it uses the one MuJoCo chose.
A context that cannot start is a RuntimeError naming MUJOCO_GL.
"""
from __future__ import annotations

import os
import sys

import mujoco
import numpy as np


def _start(model: mujoco.MjModel, width: int, height: int) -> tuple:
    """(a current OpenGL context for `width` × `height` offscreen pictures (module docstring), MuJoCo's drawing
    context on it)."""
    chosen = os.environ.get("MUJOCO_GL", "").strip().lower()
    gl = None
    try:
        if sys.platform.startswith("linux") and not os.environ.get("DISPLAY") and chosen in ("", "egl"):
            from mujoco.egl import GLContext
        else:
            GLContext = mujoco.GLContext
        gl = GLContext(width, height)
        gl.make_current()
        return gl, mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
    except Exception as err:  # no OpenGL here: name the setting that chooses one
        if gl is not None:
            gl.free()
        raise RuntimeError(f"MuJoCo's offscreen renderer cannot start here (MUJOCO_GL={chosen!r}, DISPLAY="
                           f"{os.environ.get('DISPLAY', '')!r}): {err}. Headless it needs EGL (libEGL) or "
                           f"OSMesa: set MUJOCO_GL=egl or osmesa before anything imports mujoco") from err


class MujocoView:
    """Draws `model`'s world into `width` × `height` RGB pictures from a free camera."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int):
        vis = model.vis.global_
        if not (0 < width <= vis.offwidth and 0 < height <= vis.offheight):
            raise ValueError(f"render size must be within {vis.offwidth} × {vis.offheight}, got {width} × {height}")
        self.model, self.size = model, (width, height)
        self._gl, self._context = _start(model, width, height)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._scene = mujoco.MjvScene(model, maxgeom=1000)
        self._option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, width, height)

    def draw(self, data: mujoco.MjData, camera: mujoco.MjvCamera) -> np.ndarray:
        """(height, width, 3) uint8 RGB of `data`'s state (its kinematics computed) seen from `camera`."""
        self._gl.make_current()
        mujoco.mjv_updateScene(self.model, data, self._option, None, camera, mujoco.mjtCatBit.mjCAT_ALL,
                               self._scene)
        mujoco.mjr_render(self._rect, self._scene, self._context)
        width, height = self.size
        rgb = np.empty((height, width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(rgb, None, self._rect, self._context)
        return np.flipud(rgb).copy()  # OpenGL's rows run bottom-up

    def close(self) -> None:
        self._context.free()
        self._gl.free()
