"""The same tiny job on 8 simulated CPU devices with fsdp x tensor sharding gives the one-device
losses and parameters (float32 tolerance), with the frozen vision tower bit-identical."""

from pathlib import Path

import numpy as np
import pytest

import train_runs

MESHES = {
    "fsdp4_tensor2": (("mesh.data=1", "mesh.fsdp=4", "mesh.tensor=2"), (1, 4, 2)),
    "data2_fsdp2_tensor2": (("mesh.data=2", "mesh.fsdp=2", "mesh.tensor=2"), (2, 2, 2)),
}


@pytest.mark.slow
@pytest.mark.parametrize("mesh", list(MESHES))
def test_eight_device_mesh_matches_one_device(mesh: str, reference_run: Path, tmp_path: Path) -> None:
    overrides, shape = MESHES[mesh]
    run = train_runs.train(tmp_path / "run", devices=8, overrides=overrides)

    ref = train_runs.losses(reference_run)
    assert sorted(ref) == list(range(1, train_runs.STEPS + 1))
    # The job learns, so agreement to 1e-5 after it says the updates agree, not just the start.
    assert ref[train_runs.STEPS][-1] < ref[1][-1] - 0.1
    train_runs.assert_same_run(run, reference_run, range(1, train_runs.STEPS + 1))

    # The run was really laid out on the mesh: decoder weights split over fsdp AND tensor.
    layout = train_runs.checkpoint_layout(run, train_runs.STEPS)
    assert {mesh_shape for mesh_shape, _ in layout.values()} == {shape}
    kernels = [spec for path, (_, spec) in layout.items() if path.startswith("['params']") and "mlp" in path]
    assert kernels and all(set(spec) == {"fsdp", "tensor"} for spec in kernels), kernels

    # Optimiser moments too (they were updated sharded, element by element).
    ours, theirs = (train_runs.checkpoint_state(r, train_runs.STEPS) for r in (run, reference_run))
    assert ours.keys() == theirs.keys()
    for path, value in ours.items():
        np.testing.assert_allclose(value, theirs[path], rtol=1e-4, atol=1e-6, err_msg=path)
