"""Puts the repository root on sys.path so tests import the packages without installing, and picks
headless EGL for MuJoCo before any test module imports it (the renderer needs it chosen first;
collection imports every module, so one that imports mujoco early would fix the backend to GLFW)."""

import os
import sys

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
