"""The OpenGL backend MuJoCo renders with, chosen before anything imports mujoco.

MuJoCo reads MUJOCO_GL once, at its first import, and otherwise defaults to GLFW, which fails on a
machine without a display at the first render. The `jax3dc` command imports modules that import
mujoco (the physics checks) long before it renders, so importing the package calls
:func:`configure_gl`, before any ``import mujoco`` of ours.

A headless backend is chosen only where its library is installed: ``import mujoco`` itself fails
under MUJOCO_GL=egl without libEGL (a GPU machine without the Mesa/GLVND packages), and the
physics checks, exports and training need no rendering at all.
"""

from __future__ import annotations

import os
from ctypes.util import find_library

HEADLESS_GL = (("egl", "EGL"), ("osmesa", "OSMesa"))  # (MUJOCO_GL, library), in order of preference


def configure_gl() -> str | None:
    """MUJOCO_GL: the caller's choice, else the first headless backend whose library the machine
    has, else unset (MuJoCo's GLFW default: rendering then needs a display)."""
    if "MUJOCO_GL" in os.environ:
        return os.environ["MUJOCO_GL"]
    for backend, library in HEADLESS_GL:
        if find_library(library):
            os.environ["MUJOCO_GL"] = backend
            return backend
    return None
