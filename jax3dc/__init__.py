"""jax3dc: one image in, a structured, executable 3D object out (3DCoder in JAX)."""

__version__ = "0.1.0"
