"""Puts the repository root on sys.path so tests import the packages without installing, and picks
headless EGL for MuJoCo before any test module imports it (the renderer needs it chosen first;
collection imports every module, so one that imports mujoco early would fix the backend to GLFW),
and keeps the session's convex pieces and compiled XLA programs in its own folders, never the user's
~/.cache (the tests and the commands they start in subprocesses share them; a test that counts
decompositions points the pieces elsewhere). With JAX_COMPILATION_CACHE_DIR set after collection,
an in-process `jax3dc train` leaves this process's persistent cache off (the environment wins, and
JAX read its settings at import): the suite's own compiles are not written to disk, where one
serialisation crashed a run, while commands started in subprocesses cache in the session's folder."""

import faulthandler
import os
import sys

import pytest
from _pytest.faulthandler import fault_handler_stderr_fd_key

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.hookimpl(trylast=True)  # after pytest's own faulthandler plugin has opened its stderr copy
def pytest_configure(config: pytest.Config) -> None:
    """A native crash prints the crashing thread alone: with every thread's stack the CI log's tail
    held only idle pool workers and cut the one frame that names the test."""
    if fault_handler_stderr_fd_key in config.stash:
        faulthandler.enable(file=config.stash[fault_handler_stderr_fd_key], all_threads=False)


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
