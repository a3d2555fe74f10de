"""Puts the repository root on sys.path so tests import the packages without installing, and picks
headless EGL for MuJoCo before any test module imports it (the renderer needs it chosen first;
collection imports every module, so one that imports mujoco early would fix the backend to GLFW),
and keeps the session's convex pieces in its own folder, never the user's ~/.cache (the tests and the
commands they start in subprocesses share it; a test that counts decompositions points it elsewhere)."""

import os
import sys

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(autouse=True, scope="session")
def _session_piece_cache(tmp_path_factory: pytest.TempPathFactory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("JAX3DC_PIECE_CACHE", str(tmp_path_factory.mktemp("convex_pieces")))
        yield
