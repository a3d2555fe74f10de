"""A run killed with SIGKILL continues from its last complete checkpoint with exactly the
losses and parameters of an uninterrupted run (loader position included), ignoring a
checkpoint that was still being written; a checkpoint also restores onto another mesh."""

import shutil
import signal
import time
from pathlib import Path

import numpy as np
import pytest

import train_runs

SAVED = train_runs.SAVE_EVERY  # the checkpoint the killed run leaves
STEPS = train_runs.STEPS


def _wait_for(condition, proc, what: str, timeout_s: float = train_runs.TIMEOUT_S) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        if proc.poll() is not None:
            raise AssertionError(f"run exited ({proc.returncode}) before {what}")
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.2)


@pytest.mark.slow
def test_killed_run_resumes_exactly(reference_run: Path, tmp_path: Path) -> None:
    run = tmp_path / "run"
    # The run trains one step past its checkpoint (that step is lost with the process) and waits.
    proc = train_runs.start(run, devices=1, pause_after=SAVED + 1)
    checkpoints = run / "checkpoints"
    _wait_for(lambda: (run / "paused").exists() and (checkpoints / str(SAVED)).is_dir(), proc,
              f"step {SAVED + 1} and the finished checkpoint {SAVED}")
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(timeout=60) == -signal.SIGKILL

    # What a kill in the middle of an asynchronous save leaves: orbax's temporary directory,
    # incomplete (here the next checkpoint's, with its parameter arrays missing).
    partial = checkpoints / f"{SAVED + 1}.orbax-checkpoint-tmp"
    shutil.copytree(checkpoints / str(SAVED), partial)
    shutil.rmtree(partial / "state")

    train_runs.finish(train_runs.cli_train(run, devices=1), run)
    assert f"resumed from step {SAVED}" in next(run.parent.glob(f"{run.name}.cli.log")).read_text()

    got, want = train_runs.losses(run), train_runs.losses(reference_run)
    assert sorted(got) == list(range(1, STEPS + 1))
    assert len(got[SAVED + 1]) == 2  # logged before the kill and again after the resume
    for step, values in got.items():
        assert values == [want[step][-1]] * len(values), f"step {step}: {values} vs {want[step]}"
    assert train_runs.saved_loader_positions(run, STEPS) == {"processes": [{"step": STEPS, "seed": 0}]}
    ours, theirs = train_runs.hf_params(run), train_runs.hf_params(reference_run)
    for name, value in ours.items():
        np.testing.assert_array_equal(value, theirs[name], err_msg=name)


@pytest.mark.slow
def test_checkpoint_restores_onto_another_mesh(reference_run: Path, tmp_path: Path) -> None:
    """Saved on one device, continued on fsdp=2 x tensor=2 over four."""
    run = tmp_path / "run"
    shutil.copytree(reference_run / "checkpoints" / str(SAVED), run / "checkpoints" / str(SAVED))
    train_runs.train(run, devices=4, overrides=("mesh.fsdp=2", "mesh.tensor=2"))

    assert sorted(train_runs.losses(run)) == list(range(SAVED + 1, STEPS + 1))
    train_runs.assert_same_run(run, reference_run, range(SAVED + 1, STEPS + 1))
    layout = train_runs.checkpoint_layout(run, STEPS)
    assert {mesh for mesh, _ in layout.values()} == {(1, 2, 2)}
    assert any(set(spec) == {"fsdp", "tensor"} for _, spec in layout.values())
