"""Puts the repository root on sys.path so tests import the packages without installing, and picks
headless EGL for MuJoCo before any test module imports it (the renderer needs it chosen first;
collection imports every module, so one that imports mujoco early would fix the backend to GLFW),
and keeps the session's convex pieces and compiled XLA programs in its own folders, never the user's
~/.cache (the tests and the commands they start in subprocesses share them; a test that counts
decompositions points the pieces elsewhere). With JAX_COMPILATION_CACHE_DIR set after collection,
an in-process `jax3dc train` leaves this process's persistent cache off (the environment wins, and
JAX read its settings at import): the suite's own compiles are not written to disk, where one
serialisation crashed a run, while commands started in subprocesses cache in the session's folder."""

import os
import sys

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def pytest_runtest_logstart(nodeid: str, location: tuple) -> None:
    """Writes the test about to run to the file JAX3DC_LAST_TEST names, where set: after a native
    crash .ci/run prints it (the -q log shows only dots)."""
    if path := os.environ.get("JAX3DC_LAST_TEST"):
        with open(path, "w") as f:
            f.write(nodeid + "\n")


@pytest.fixture(autouse=True, scope="session")
def _session_piece_cache(tmp_path_factory: pytest.TempPathFactory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("JAX3DC_PIECE_CACHE", str(tmp_path_factory.mktemp("convex_pieces")))
        mp.setenv("JAX_COMPILATION_CACHE_DIR", str(tmp_path_factory.mktemp("xla_cache")))
        yield
