"""Wall time of ``jax3dc physics sweep`` over a data build, by backend and worker count, on the
same objects in one run.

The build holds factory objects (categories in turn, seeds counting up), written as the sweep
reads them: target structure + part program, no images (the sweep uses none). Each (backend,
workers) run is the whole command, report included, over the first N objects of the build for each
``--sizes`` N; printed per run: seconds, objects per second and the ratio against the first run of
that size; whether object verdicts, joint verdicts and whole verdict lines equal the first run's;
for MJX the device's launches, compiles and compile seconds. ``--report DIR`` keeps every run's
figures (runs.jsonl), each run's per-object costs and the plots of objects per second against
sweep size and of seconds per object against its parts and collision pieces.

GPU host, the issue's figure: python3 bench/physics_sweep.py --sizes 1000 --backends c,mjx --workers 16 --report R
GPU host, worker scaling:      python3 bench/physics_sweep.py --sizes 80 --workers 1,16
CPU smoke:                     python3 bench/physics_sweep.py --sizes 4 --workers 1,2
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import tempfile
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from data_pipeline.record import Record
from data_pipeline.shards import write_dataset
from jax3dc.cli import main as jax3dc
from jax3dc.factories import FACTORIES, generate_object
from jax3dc.structure import to_json


def _record(index: int):
    categories = sorted(FACTORIES)
    category, seed = categories[index % len(categories)], index // len(categories)
    obj = generate_object(category, seed)
    meta = {"category": category, "object_id": obj.object_id, "view": 0, "scale": obj.scale_m_per_nu,
            "moved_joint": None, "augmentation": None}
    return Record(f"{category}/{obj.object_id}/0", b"", b"", "", to_json(obj.structure), obj.program_text, meta)


def write_build(directory: Path, objects: int, workers: int = 1) -> None:
    """A one-shard data build of ``objects`` factory objects, one rest-pose record each."""
    if workers > 1:
        with ProcessPoolExecutor(workers) as pool:
            records = list(pool.map(_record, range(objects), chunksize=16))
    else:
        records = [_record(i) for i in range(objects)]
    write_dataset(directory, records)


def _verdicts(path: Path) -> dict[str, dict]:
    return {line["object"]: line for line in map(json.loads, path.read_text().splitlines())}


def _same(a: dict[str, dict], b: dict[str, dict]) -> dict[str, int]:
    """How many objects have equal object verdicts, equal verdicts on every joint, and equal lines."""
    common = [k for k in a if k in b and "ok" in a[k] and "ok" in b[k]]
    return {"objects": len(common), "object_verdicts": sum(a[k]["ok"] == b[k]["ok"] for k in common),
            "joint_verdicts": sum({j: v["ok"] for j, v in a[k]["joints"].items()} == {j: v["ok"] for j, v in b[k]["joints"].items()}
                                  for k in common),
            "lines": sum(json.dumps(a[k]) == json.dumps(b[k]) for k in common)}


def _plot(runs: list[dict], costs: dict[str, list[dict]], out: Path) -> None:
    import matplotlib  # lazy: matplotlib (0.19 s with pyplot) for the plots only
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: after the Agg backend is chosen

    fig, ax = plt.subplots(figsize=(5, 3.2))
    for label in sorted({r["label"] for r in runs}):
        mine = sorted((r["objects"], r["objects_per_s"]) for r in runs if r["label"] == label)
        ax.plot(*zip(*mine), marker="o", label=label)
    ax.set_xscale("log")
    ax.set_xlabel("objects in the sweep")
    ax.set_ylabel("objects per second")
    ax.set_title("physics sweep: throughput against sweep size")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "sweep_size.png", dpi=100)
    plt.close(fig)
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.2), sharey=True)
    for label, rows in sorted(costs.items()):
        for ax, key in zip(axes, ("parts", "pieces")):
            ax.scatter([r[key] for r in rows], [r["seconds"] for r in rows], s=6, alpha=0.5, label=label)
            ax.set_xlabel(f"{key} per object" if key == "parts" else "collision pieces per object")
    axes[0].set_ylabel("check seconds per object (one worker)")
    axes[0].legend(fontsize=7)
    fig.suptitle("physics sweep: cost against object size")
    fig.tight_layout()
    fig.savefig(out / "object_size.png", dpi=100)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="80", help="comma list of sweep sizes (objects); the build holds the largest")
    parser.add_argument("--objects", type=int, help="one sweep size (as --sizes N)")
    parser.add_argument("--backends", default="c", help="comma list of backends (c, mjx)")
    parser.add_argument("--workers", default="1,16", help="comma list of worker counts")
    parser.add_argument("--runs", help="comma list of backend:workers runs instead of every backend with every count "
                                       "(c:16,mjx:16,mjx:32)")
    parser.add_argument("--report", type=Path, help="keep runs.jsonl, per-run costs and the plots here")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")

    sizes = [args.objects] if args.objects else [int(n) for n in args.sizes.split(",")]
    runs_of = [(b, int(w)) for b in args.backends.split(",") for w in args.workers.split(",")]
    if args.runs:
        runs_of = [(run.split(":")[0], int(run.split(":")[1])) for run in args.runs.split(",")]
    print(f"{os.cpu_count()} cores, sizes {sizes}, runs {runs_of}")
    runs, costs, failed = [], {}, False
    with tempfile.TemporaryDirectory() as tmp:
        build = Path(tmp) / "build"
        t0 = time.perf_counter()
        write_build(build, max(sizes), workers=os.cpu_count() or 1)
        print(f"build of {max(sizes)} objects: {time.perf_counter() - t0:.1f} s")
        for size in sizes:
            first = None
            for backend, workers in runs_of:
                label = f"{backend}, {workers} workers"
                out = Path(tmp) / f"report_{size}_{backend}_{workers}"
                t0 = time.perf_counter()
                with contextlib.redirect_stdout(io.StringIO()):
                    code = jax3dc(["physics", "sweep", str(build), "--out", str(out), "--workers", str(workers),
                                   "--backend", backend, "--limit", str(size)])
                seconds = time.perf_counter() - t0
                if code != 0:
                    raise SystemExit(f"physics sweep ({label}) exited {code}")
                summary = json.loads((out / "summary.json").read_text())
                verdicts = _verdicts(out / "verdicts.jsonl")
                first = first or (seconds, verdicts)
                same = _same(first[1], verdicts)
                run = {"label": label, "backend": backend, "workers": workers, "objects": size, "seconds": round(seconds, 2),
                       "objects_per_s": round(size / seconds, 3), "ratio": round(first[0] / seconds, 3), "same": same,
                       "device": summary.get("device")}
                runs.append(run)
                costs.setdefault(label, [])
                if size == max(sizes):
                    costs[label] = [json.loads(line) for line in (out / "costs.jsonl").read_text().splitlines()]
                device = summary.get("device")
                print(f"{size:5d} objects, {label:18s}: {seconds:7.1f} s, {size / seconds:6.2f} objects/s, {run['ratio']:5.2f}x the "
                      f"first; same as the first: objects {same['object_verdicts']}/{same['objects']}, joints "
                      f"{same['joint_verdicts']}/{same['objects']}, lines {same['lines']}/{same['objects']}"
                      + (f"; device: {device}" if device else ""), flush=True)
                for key in [k for k in first[1] if json.dumps(first[1][k]) != json.dumps(verdicts.get(k))][:5]:
                    a, b = first[1][key], verdicts.get(key, {})
                    print(f"    differs: {key}: ok {a.get('ok')} -> {b.get('ok')}; findings only in the first: "
                          f"{[f for f in a.get('findings', []) if f not in b.get('findings', [])]}; only here: "
                          f"{[f for f in b.get('findings', []) if f not in a.get('findings', [])]}")
                failed |= same["object_verdicts"] != same["objects"] or same["joint_verdicts"] != same["objects"]
                if args.report:
                    args.report.mkdir(parents=True, exist_ok=True)
                    shutil.copy(out / "costs.jsonl", args.report / f"costs_{size}_{backend}_{workers}.jsonl")
        if args.report:
            (args.report / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in runs))
            _plot(runs, costs, args.report)
    if failed:
        raise SystemExit("verdicts differ between runs")


if __name__ == "__main__":
    main()
