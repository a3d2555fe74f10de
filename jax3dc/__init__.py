"""jax3dc: one image in, a structured, executable 3D object out (3DCoder in JAX)."""

from jax3dc.gl import configure_gl

# MuJoCo reads MUJOCO_GL at its first import; scripts that import the project's evaluation or data
# modules (which import mujoco) before the renderer would otherwise fix GLFW and fail headless
configure_gl()

__version__ = "0.1.0"
