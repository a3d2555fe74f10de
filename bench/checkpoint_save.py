"""How long an asynchronous orbax save blocks the caller, by host memory kind: N GiB of bf16
device arrays saved four times in a row (pinned host, pageable, pinned, pageable).

    python3 bench/checkpoint_save.py --gib 24 --json OUT.json

The blocked seconds are what a training step waits (train/loop.py logs them as ``save_s``);
the total includes writing to disk.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time

import jax
import jax.numpy as jnp
import orbax.checkpoint as ocp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gib", type=int, default=24, help="GiB of device arrays (1 GiB each)")
    ap.add_argument("--json", help="write the rows here")
    a = ap.parse_args()

    tree = {f"a{i}": jnp.full((2**29,), i, jnp.bfloat16) for i in range(a.gib)}
    jax.block_until_ready(tree)
    rows = []
    with tempfile.TemporaryDirectory() as root:
        for n, pinned in enumerate((True, False, True, False)):
            path = f"{root}/save{n}"
            saver = ocp.AsyncCheckpointer(ocp.PyTreeCheckpointHandler(enable_pinned_host_transfer=pinned))
            start = time.perf_counter()
            saver.save(path, args=ocp.args.PyTreeSave(tree))
            blocked = time.perf_counter() - start
            saver.wait_until_finished()
            total = time.perf_counter() - start
            saver.close()
            shutil.rmtree(path, ignore_errors=True)
            rows.append({"gib": a.gib, "pinned_host": pinned, "blocked_s": round(blocked, 2), "total_s": round(total, 2)})
            print(rows[-1], flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f)


if __name__ == "__main__":
    main()
