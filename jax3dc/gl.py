"""The OpenGL backend MuJoCo renders with, chosen before anything imports mujoco.

MuJoCo reads MUJOCO_GL once, at its first import, and otherwise defaults to GLFW, which fails on a
machine without a display at the first render. The `jax3dc` command imports modules that import
mujoco (the physics checks) long before it renders, so both the command and the renderer call
:func:`configure_gl` before their first ``import mujoco``.
"""

from __future__ import annotations

import os

HEADLESS_GL = "egl"  # Mesa's software EGL on a CPU machine, the driver's EGL on a GPU


def configure_gl() -> str:
    """MUJOCO_GL: the caller's choice, else headless EGL."""
    return os.environ.setdefault("MUJOCO_GL", HEADLESS_GL)
