"""Two processes on one machine (one CPU device each, gloo collectives) train the tiny job
together through `jax3dc train` and match the one-process run of the same global batch."""

from pathlib import Path

import numpy as np
import pytest

import train_runs


@pytest.mark.slow
def test_two_processes_train_together(reference_run: Path, tmp_path: Path) -> None:
    run = tmp_path / "run"
    port = train_runs.free_port()
    procs = [train_runs.cli_train(run, devices=1, log=f"process{i}", env={
        "JAX_COORDINATOR_ADDRESS": f"localhost:{port}", "JAX_NUM_PROCESSES": "2", "JAX_PROCESS_ID": str(i)})
        for i in range(2)]
    rcs = [p.wait(timeout=train_runs.TIMEOUT_S) for p in procs]
    logs = [next(run.parent.glob(f"{run.name}.process{i}.log")).read_text() for i in range(2)]

    got, want = train_runs.losses(run), train_runs.losses(reference_run)
    assert sorted(got) == list(range(1, train_runs.STEPS + 1)), logs[0][-3000:]
    for step, values in got.items():
        np.testing.assert_allclose(values, want[step][-1], rtol=1e-5, err_msg=f"loss of step {step}")
    # Every process's loader position is in the checkpoint; the state matches the one-process run.
    positions = train_runs.saved_loader_positions(run, train_runs.STEPS)["processes"]
    assert positions == [{"step": train_runs.STEPS, "seed": 0}] * 2
    layout = train_runs.checkpoint_layout(run, train_runs.STEPS)
    assert {mesh for mesh, _ in layout.values()} == {(1, 2, 1)}
    ours, theirs = (train_runs.checkpoint_state(r, train_runs.STEPS) for r in (run, reference_run))
    for path, value in ours.items():
        np.testing.assert_allclose(value, theirs[path], rtol=1e-4, atol=1e-6, err_msg=path)

    # The HF export gathers each tensor from both processes; process 0 alone writes it.
    assert rcs == [0, 0], "\n".join(log[-3000:] for log in logs)
    train_runs.assert_same_run(run, reference_run, range(1, train_runs.STEPS + 1))
