"""Tiny training runs in their own processes, and reading back what they left on disk.

Every run here is the same tiny job (the `tiny` preset, synthetic data with images, float32
compute, 6 steps, a checkpoint every 3) on a different number of devices, meshes or processes,
so their losses and parameters can be compared with one reference run.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = Path(__file__).with_name("train_process.py")
STEPS = 6
SAVE_EVERY = 3
TINY = ("init=tiny", "data=synthetic", "seq_len=32", "image_size=16", "batch_size=8", "grad_accum=2",
        f"steps={STEPS}", "warmup_steps=1", "lr=1e-2", "compute_dtype=float32", "log_every=1",
        f"save_every={SAVE_EVERY}", "eval_every=100", "eval_batches=1", "keep_last=5")
TIMEOUT_S = 600
_MULTIPROCESS_ENV = ("JAX_COORDINATOR_ADDRESS", "JAX_NUM_PROCESSES", "JAX_PROCESS_ID")
# XLA's persistent compilation cache shared by the runs of one test session (set by conftest):
# the one-device runs compile the same programs, and compiling is most of a tiny run's time.
compile_cache: Path | None = None


def _env(devices: int, extra: dict[str, str] | None = None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in _MULTIPROCESS_ENV}
    env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    env["PYTHONPATH"] = str(ROOT)
    if compile_cache is not None:
        env["JAX_COMPILATION_CACHE_DIR"] = str(compile_cache)
        env["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0"
    env.update(extra or {})
    return env


def start(out: Path, devices: int = 1, overrides: tuple[str, ...] = (), *, pause_after: int = 0,
          nan_at: int = 0, env: dict[str, str] | None = None, log: str = "run") -> subprocess.Popen:
    """Start train_process.py on `devices` simulated CPU devices; output goes to out/../<log>.log."""
    args = [sys.executable, str(SCRIPT), f"--devices={devices}", f"--pause-after={pause_after}",
            f"--nan-at={nan_at}", *TINY, f"output_dir={out}", *overrides]
    log_file = open(out.parent / f"{out.name}.{log}.log", "w")
    return subprocess.Popen(args, cwd=ROOT, env=_env(devices, env), stdout=log_file, stderr=subprocess.STDOUT)


def cli_train(out: Path, devices: int = 1, overrides: tuple[str, ...] = (),
              env: dict[str, str] | None = None, log: str = "cli") -> subprocess.Popen:
    """Start `python3 -m jax3dc.cli train` with the same settings as `start`."""
    sets = [a for item in (*TINY, f"output_dir={out}", *overrides) for a in ("--set", item)]
    log_file = open(out.parent / f"{out.name}.{log}.log", "w")
    return subprocess.Popen([sys.executable, "-m", "jax3dc.cli", "train", *sets], cwd=ROOT,
                            env=_env(devices, env), stdout=log_file, stderr=subprocess.STDOUT)


def finish(proc: subprocess.Popen, out: Path, expect_rc: int = 0) -> None:
    """Wait for `proc`; fail with its log's tail when it exits otherwise than expected."""
    rc = proc.wait(timeout=TIMEOUT_S)
    if rc != expect_rc:
        tails = "".join(f"--- {f.name}\n{f.read_text()[-3000:]}\n" for f in sorted(out.parent.glob(f"{out.name}.*.log")))
        raise AssertionError(f"run in {out} exited {rc}, expected {expect_rc}:\n{tails}")


def train(out: Path, devices: int = 1, overrides: tuple[str, ...] = (), **kw) -> Path:
    finish(start(out, devices, overrides, **kw), out)
    return out


def losses(run: Path) -> dict[int, list[float]]:
    """Training loss of each step, every time it was logged (a resumed run logs some twice)."""
    out: dict[int, list[float]] = {}
    for line in (run / "metrics.jsonl").read_text().splitlines():
        record = json.loads(line)
        if record["kind"] == "train":
            out.setdefault(record["step"], []).append(record["loss"])
    return out


def hf_params(run: Path) -> dict[str, np.ndarray]:
    """The exported model's tensors by HF name."""
    from jax3dc.model.safetensors_io import iter_tensors

    return dict(iter_tensors(run / "hf"))


def _tree_metadata(path: Path):
    import orbax.checkpoint as ocp

    meta = ocp.PyTreeCheckpointer().metadata(path)
    meta = getattr(meta, "item_metadata", meta)
    return getattr(meta, "tree", meta)


def checkpoint_state(run: Path, step: int) -> dict[str, np.ndarray]:
    """Trainable parameters, optimiser state, step and RNG of a checkpoint, as host arrays by
    path (read without a target, so any mesh's checkpoint loads in this one-device process)."""
    import orbax.checkpoint as ocp

    path = run / "checkpoints" / str(step) / "state"
    tree = _tree_metadata(path)
    args = jax.tree.map(lambda _: ocp.RestoreArgs(restore_type=np.ndarray), tree)
    restored = ocp.PyTreeCheckpointer().restore(path, restore_args=args)
    return {jax.tree_util.keystr(p): np.asarray(v) for p, v in jax.tree_util.tree_flatten_with_path(restored)[0]}


def checkpoint_layout(run: Path, step: int) -> dict[str, tuple[tuple[int, ...], tuple]]:
    """(mesh shape, partition spec) each array of a checkpoint's state was saved with."""
    tree = _tree_metadata(run / "checkpoints" / str(step) / "state")
    return {jax.tree_util.keystr(p): (tuple(int(n) for n in m.sharding.shape), tuple(m.sharding.partition_spec))
            for p, m in jax.tree_util.tree_flatten_with_path(tree)[0]}


def assert_same_run(run: Path, reference: Path, steps: range, rtol: float = 1e-5, atol: float = 2e-5) -> None:
    """Losses of `steps` and the exported parameters agree with the reference to float32
    tolerance; the frozen vision tower is bit-identical."""
    got, want = losses(run), losses(reference)
    for s in steps:
        np.testing.assert_allclose(got[s], want[s][-1], rtol=rtol, err_msg=f"loss of step {s}")
    ours, theirs = hf_params(run), hf_params(reference)
    assert ours.keys() == theirs.keys()
    for name, value in ours.items():
        if ".visual." in name:
            np.testing.assert_array_equal(value, theirs[name], err_msg=name)
        else:
            np.testing.assert_allclose(value, theirs[name], rtol=rtol, atol=atol, err_msg=name)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def saved_loader_positions(run: Path, step: int) -> dict:
    """The loader item of a checkpoint, as saved (every process's position)."""
    import orbax.checkpoint as ocp

    manager = ocp.CheckpointManager(run / "checkpoints", item_names=("loader",))
    try:
        return manager.restore(step, args=ocp.args.Composite(loader=ocp.args.JsonRestore()))["loader"]
    finally:
        manager.close()
