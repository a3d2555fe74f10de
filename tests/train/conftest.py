"""The one-device reference run that the sharded, resumed and multi-process runs are compared with."""

from pathlib import Path

import pytest

import train_runs


@pytest.fixture(scope="session")
def compile_cache(tmp_path_factory) -> Path:
    """One XLA compilation cache for every training subprocess of the session."""
    train_runs.compile_cache = tmp_path_factory.mktemp("xla_cache")
    return train_runs.compile_cache


@pytest.fixture(scope="session")
def reference_run(tmp_path_factory, compile_cache: Path) -> Path:
    """The tiny job on one device, uninterrupted: losses, checkpoints 3 and 6, hf/ export."""
    return train_runs.train(tmp_path_factory.mktemp("reference") / "run", devices=1)
