"""What verified decoding costs on a CPU: seconds per physics verdict (``check_object``, C MuJoCo),
with and without the dynamics (limit reachability and gravity rollouts), on procedural records.

Each record's parts are rebuilt as ``jax3dc.verify`` does (``record_parts``), its target structure
is checked once untimed (imports, first-call set-up) and then timed with and without the dynamics.
Best of K costs about K distinct verdicts per object (identical candidates are checked once);
a repair about one verdict per alternative tried (``jax3dc.verify.repair``).

python3 bench/verified_cost.py --data SHARDS --records 8    (e.g. the test shards `jax3dc demo` builds)
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

from data_pipeline.record_parts import record_parts
from data_pipeline.shards import read_shard, shard_paths
from jax3dc.structure import boxes_from_dict
from jax3dc.verify.select import parse_candidate
from jax3dc.verify.verdicts import Physics


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, required=True, help="data build folder (procedural records)")
    parser.add_argument("--split", default="test", help="shards of this split (default %(default)s)")
    parser.add_argument("--records", type=int, default=8, help="records to time (default %(default)s)")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")

    records = []
    for path in shard_paths([args.data], args.split):
        records += [r for r in read_shard(path) if r.program]
        if len(records) >= args.records:
            break
    records = records[:args.records]
    if not records:
        sys.exit(f"no procedural records in the {args.split} shards of {args.data}")
    rows = {"parts": [], "with dynamics": [], "without": []}
    for record in records:
        t0 = time.perf_counter()
        parts, scale, mounted = record_parts(record)
        rows["parts"].append(time.perf_counter() - t0)
        boxes = boxes_from_dict(record.meta["boxes"])
        structure = parse_candidate(record.target, boxes.keys(), boxes)
        full, kinematic = Physics(parts, scale, mounted), Physics(parts, scale, mounted, dynamics=False)
        full.verdict(structure)
        timed = {}
        for name, physics in (("with dynamics", full), ("without", kinematic)):
            t0 = time.perf_counter()
            verdict = physics.verdict(structure)
            timed[name] = time.perf_counter() - t0
            rows[name].append(timed[name])
        print(f"{record.key:45s} parts {len(parts):3d} joints {len(structure.joints()):2d} "
              f"verdict {timed['with dynamics']:.2f} s ({timed['without']:.2f} s without dynamics), "
              f"ok {verdict.ok}", flush=True)
    print(f"\n{len(records)} records, seconds per call (mean / median / max):")
    for name, values in rows.items():
        label = "rebuild parts" if name == "parts" else f"verdict {name}"
        print(f"  {label:28s} {statistics.mean(values):.2f} / {statistics.median(values):.2f} / {max(values):.2f}")
    share = 1 - statistics.mean(rows["without"]) / statistics.mean(rows["with dynamics"])
    print(f"  dynamics share of a verdict  {share:.0%}")


if __name__ == "__main__":
    main()
