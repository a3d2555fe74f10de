"""`jax3dc train` without a data source stops with one line naming `--set data=`, writing nothing."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from train.config import NO_DATA, ConfigError, TrainConfig

ROOT = Path(__file__).resolve().parents[2]


def test_cli_without_data_exits_1_with_one_line_and_writes_nothing(tmp_path):
    out = tmp_path / "run"
    env = dict(os.environ, PYTHONPATH=str(ROOT), JAX_PLATFORMS="cpu")
    # cwd=tmp_path: a default output_dir (runs/train) would land here too
    proc = subprocess.run([sys.executable, "-m", "jax3dc.cli", "train", "--init", "tiny", "--output-dir", str(out),
                           "--steps", "1"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1, proc.stderr[-2000:]
    assert proc.stderr.strip().splitlines() == [f"jax3dc train: error: {NO_DATA}"]
    assert "--set data=" in proc.stderr and "--set data=synthetic" in proc.stderr
    assert proc.stdout == ""
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_run_without_data_raises_before_making_output_dir(tmp_path):
    from train.loop import run

    out = tmp_path / "run"
    with pytest.raises(ConfigError, match="--set data="):
        run(TrainConfig(init="tiny", output_dir=str(out), steps=1, warmup_steps=0))
    assert not out.exists()
