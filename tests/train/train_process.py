"""A tiny training run in a fresh process, for the sharding, resume and multi-process tests.

    python3 tests/train/train_process.py --devices N [--pause-after K] [--nan-at K] KEY=VALUE ...

--devices must take effect before jax is imported (XLA reads the simulated CPU device count
once), which is why these runs live in their own process. KEY=VALUE are TrainConfig overrides
(as `jax3dc train --set`). The run joins a multi-process job when JAX_COORDINATOR_ADDRESS and
friends are set, exactly as `jax3dc train` does.

--pause-after K: after step K (and any checkpoint it started) write `paused` in the output
dir and wait to be killed; the test kills the process from outside with SIGKILL.
--nan-at K: the K-th training batch carries a NaN in its loss mask (a corrupt batch); the run
must stop with NonFiniteLossError, whose message goes to `nonfinite.txt` (exit code 3).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--devices", type=int, default=1, help="simulated CPU devices in this process")
    p.add_argument("--pause-after", type=int, default=0)
    p.add_argument("--nan-at", type=int, default=0)
    p.add_argument("overrides", nargs="*", help="TrainConfig overrides KEY=VALUE")
    return p.parse_args(argv)


class CorruptAt:
    """A loader whose `at`-th batch (1-based, counted over the run) has a NaN loss mask."""

    def __init__(self, inner, at: int):
        self.inner, self.at = inner, at

    def __iter__(self):
        return self

    def __next__(self):
        batch = next(self.inner)
        if self.inner.get_state()["step"] == self.at:  # the synthetic loader counts batches
            batch["loss_mask"] = batch["loss_mask"].copy()
            batch["loss_mask"][0, 1] = float("nan")
        return batch

    def get_state(self):
        return self.inner.get_state()

    def set_state(self, state):
        self.inner.set_state(state)


def main(argv: list[str]) -> int:
    args = _args(argv)
    os.environ["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={args.devices}"
    sys.path.insert(0, ROOT)
    from train import loop
    from train.config import TrainConfig, apply_overrides
    from train.distributed import initialize_from_env

    initialize_from_env()
    cfg = apply_overrides(TrainConfig(), args.overrides)

    if args.nan_at:
        make = loop.make_loader

        def make_loader(cfg, model, split, *a, **kw):
            inner = make(cfg, model, split, *a, **kw)
            return CorruptAt(inner, args.nan_at) if split == "train" else inner

        loop.make_loader = make_loader

    def on_step(step: int, _metrics: dict) -> None:
        if step == args.pause_after:
            with open(os.path.join(cfg.output_dir, "paused"), "w") as f:
                f.write(str(step))
            while True:  # killed from outside
                time.sleep(1)

    try:
        loop.run(cfg, on_step=on_step)
    except loop.NonFiniteLossError as e:
        with open(os.path.join(cfg.output_dir, "nonfinite.txt"), "w") as f:
            f.write(str(e))
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
