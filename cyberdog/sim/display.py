"""Can PyBullet's GUI open a window here? Asked before connecting: PyBullet's GUI connection calls the C
`exit()` when it cannot open an X display (no exception, the interpreter just ends), so `Robot(gui=True)` checks
first and falls back to a DIRECT connection with a warning."""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys


def display_problem() -> str | None:
    """Why PyBullet's GUI cannot open a window here (None if it can): checked before connecting, because a
    failed GUI connection ends the process instead of raising."""
    if sys.platform in ("darwin", "win32"):
        return None
    display = os.environ.get("DISPLAY")
    if not display:
        if os.environ.get("WAYLAND_DISPLAY"):
            return ("WAYLAND_DISPLAY is set but DISPLAY is not (PyBullet's window is an X11 window; XWayland "
                    "provides DISPLAY)")
        return "neither DISPLAY nor WAYLAND_DISPLAY is set (a headless machine)"
    try:
        x11 = ctypes.CDLL(ctypes.util.find_library("X11") or "libX11.so.6")
    except OSError:
        return f"DISPLAY={display} is set but libX11 cannot be loaded"
    x11.XOpenDisplay.restype, x11.XOpenDisplay.argtypes = ctypes.c_void_p, [ctypes.c_char_p]
    handle = x11.XOpenDisplay(display.encode())
    if not handle:
        return f"cannot connect to the X server of DISPLAY={display}"
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    x11.XCloseDisplay(handle)
    return None
