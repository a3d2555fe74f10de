"""Wall time of ``jax3dc physics sweep`` over a data build: objects checked in parallel processes
against one process (the command before ``--workers``), on the same objects in one run.

The build holds ``--objects`` factory objects (categories in turn, seeds counting up), written as
the sweep reads them: target structure + part program, no images (the sweep uses none). Each
``--workers`` count runs the whole command, report included; printed: seconds, objects per second,
the speed-up against the first count, and whether every count wrote the same verdicts.

GPU machine's 16 cores: python3 bench/physics_sweep.py --objects 80 --workers 1,8,16
CPU smoke:              python3 bench/physics_sweep.py --objects 4 --workers 1,2
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from anywhere: the repo root's packages


def write_build(directory: Path, objects: int) -> None:
    """A one-shard data build of ``objects`` factory objects, one rest-pose record each."""
    from data_pipeline.factories import FACTORIES, generate_object
    from data_pipeline.record import Record
    from data_pipeline.shards import write_dataset
    from jax3dc.structure import to_json

    categories = sorted(FACTORIES)
    records = []
    for i in range(objects):
        category, seed = categories[i % len(categories)], i // len(categories)
        obj = generate_object(category, seed)
        meta = {"category": category, "object_id": obj.object_id, "view": 0, "scale": obj.scale_m_per_nu,
                "moved_joint": None, "augmentation": None}
        records.append(Record(f"{category}/{obj.object_id}/0", b"", b"", "", to_json(obj.structure),
                              obj.program_text, meta))
    write_dataset(directory, records)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--objects", type=int, default=80, help="objects in the build (default %(default)s)")
    parser.add_argument("--workers", default="1,16", help="comma list of worker counts; the first is the baseline")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    from jax3dc.cli import main as jax3dc

    counts = [int(w) for w in args.workers.split(",")]
    print(f"{os.cpu_count()} cores, {args.objects} objects")
    with tempfile.TemporaryDirectory() as tmp:
        build = Path(tmp) / "build"
        write_build(build, args.objects)
        seconds, verdicts = {}, {}
        for workers in counts:
            out = Path(tmp) / f"report{workers}"
            t0 = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):
                code = jax3dc(["physics", "sweep", str(build), "--out", str(out), "--workers", str(workers)])
            seconds[workers] = time.perf_counter() - t0
            if code != 0:
                raise SystemExit(f"physics sweep with {workers} worker(s) exited {code}")
            verdicts[workers] = (out / "verdicts.jsonl").read_text()
            print(f"workers {workers:3d}: {seconds[workers]:7.1f} s, {args.objects / seconds[workers]:6.2f} objects/s, "
                  f"{seconds[counts[0]] / seconds[workers]:5.2f}x workers {counts[0]}")
        same = all(v == verdicts[counts[0]] for v in verdicts.values())
        print(f"verdicts identical across worker counts: {same}")
        if not same:
            raise SystemExit(1)


if __name__ == "__main__":
    main()
