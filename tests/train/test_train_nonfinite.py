"""A NaN loss (from a corrupt batch) stops the run with NonFiniteLossError naming the last good
checkpoint, saves nothing from the bad step, and leaves that checkpoint intact: the run
continues from it exactly as the uninterrupted run did."""

import re
from pathlib import Path

import numpy as np
import pytest

import train_runs

SAVED = train_runs.SAVE_EVERY
BAD = SAVED + 2  # one good step after the checkpoint, then the corrupt batch


@pytest.mark.slow
def test_nan_loss_stops_and_names_intact_last_good_checkpoint(reference_run: Path, tmp_path: Path) -> None:
    run = tmp_path / "run"
    train_runs.finish(train_runs.start(run, devices=1, nan_at=BAD), run, expect_rc=3)

    message = (run / "nonfinite.txt").read_text()
    assert re.search(rf"loss is nan at step {BAD}\b", message), message
    assert f"step {SAVED} in {run / 'checkpoints'}" in message, message
    assert sorted(p.name for p in (run / "checkpoints").iterdir()) == [str(SAVED)]
    assert not (run / "hf").exists()

    got, want = train_runs.losses(run), train_runs.losses(reference_run)
    assert sorted(got) == list(range(1, BAD))  # the bad step is not logged as a result
    # Intact: bit for bit the uninterrupted run's checkpoint (parameters, moments, step, RNG).
    ours, theirs = (train_runs.checkpoint_state(r, SAVED) for r in (run, reference_run))
    assert ours.keys() == theirs.keys()
    for path, value in ours.items():
        np.testing.assert_array_equal(value, theirs[path], err_msg=path)
    assert all(np.isfinite(v).all() for v in ours.values() if v.dtype.kind == "f")
    assert train_runs.saved_loader_positions(run, SAVED) == {"processes": [{"step": SAVED, "seed": 0}]}

    # And it restores: the same run, its data clean again, continues with the reference losses.
    train_runs.train(run, devices=1, log="resumed")
    assert f"resumed from step {SAVED}" in (run.parent / f"{run.name}.resumed.log").read_text()
    got = train_runs.losses(run)
    for step in range(SAVED + 1, train_runs.STEPS + 1):
        assert got[step][-1] == want[step][-1], f"step {step}: {got[step]} vs {want[step]}"
