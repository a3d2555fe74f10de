"""Summarise a jax profiler trace (the perfetto ``*.trace.json.gz`` that
``jax.profiler.trace(dir, create_perfetto_trace=True)`` writes): GPU kernel time by kind
(matmul, attention, collective, other), how much collective time is hidden under compute, and
the heaviest kernels.

    python3 bench/profile_summary.py TRACE_DIR [--top 25]

Why: a step that scales badly is either waiting on collectives that do not overlap compute, or
doing more compute than it should; this tells the two apart from one trace.
"""

import argparse
import glob
import gzip
import json
import os
import re
from collections import defaultdict

KINDS = (
    ("collective", re.compile(r"nccl|all-gather|all_gather|allgather|reduce-scatter|reduce_scatter|"
                              r"reducescatter|all-reduce|all_reduce|allreduce|collective|sendrecv", re.I)),
    ("attention", re.compile(r"cudnn|flash|fmha|sdpa|attention", re.I)),
    ("matmul", re.compile(r"gemm|cutlass|nvjet|xmma|cublas|sm90_|sm80_|dot", re.I)),
    ("memcpy", re.compile(r"memcpy|memset", re.I)),
)


def kind_of(name: str) -> str:
    for kind, pattern in KINDS:
        if pattern.search(name):
            return kind
    return "other"


def union_length(intervals: list[tuple[float, float]]) -> float:
    total, end = 0.0, float("-inf")
    for a, b in sorted(intervals):
        if b <= end:
            continue
        total += b - max(a, end)
        end = b
    return total


def overlap_length(a: list[tuple[float, float]], b: list[tuple[float, float]]) -> float:
    """Length of (union of a) ∩ (union of b)."""
    return union_length(a) + union_length(b) - union_length(a + b)


def load_events(trace_dir: str) -> tuple[list[dict], dict[int, str], dict[tuple[int, int], str]]:
    paths = sorted(glob.glob(os.path.join(trace_dir, "**", "*.trace.json.gz"), recursive=True))
    if not paths:
        raise SystemExit(f"no *.trace.json.gz under {trace_dir}")
    with gzip.open(paths[-1], "rt") as f:
        doc = json.load(f)
    events = doc["traceEvents"] if isinstance(doc, dict) else doc
    procs = {e["pid"]: e["args"]["name"] for e in events if e.get("ph") == "M" and e.get("name") == "process_name"}
    threads = {(e["pid"], e["tid"]): e["args"]["name"] for e in events
               if e.get("ph") == "M" and e.get("name") == "thread_name"}
    return events, procs, threads


def summarise(trace_dir: str, top: int) -> None:
    events, procs, threads = load_events(trace_dir)
    gpu_pids = {pid for pid, name in procs.items() if re.search(r"GPU|gpu|device:", name)}
    for pid in sorted(gpu_pids):
        kernels = [e for e in events if e.get("pid") == pid and e.get("ph") == "X" and "dur" in e
                   and not re.search(r"XLA Modules|XLA Ops|Steps|TraceMe", threads.get((pid, e["tid"]), ""))]
        if not kernels:
            continue
        by_kind: dict[str, list[tuple[float, float]]] = defaultdict(list)
        by_name: dict[str, float] = defaultdict(float)
        for e in kernels:
            by_kind[kind_of(e["name"])].append((e["ts"], e["ts"] + e["dur"]))
            by_name[e["name"]] += e["dur"]
        span = max(b for v in by_kind.values() for _, b in v) - min(a for v in by_kind.values() for a, _ in v)
        compute = [iv for k, v in by_kind.items() if k != "collective" for iv in v]
        print(f"== {procs[pid]}: {len(kernels)} kernels over {span / 1e3:.1f} ms")
        for kind, ivs in sorted(by_kind.items(), key=lambda kv: -union_length(kv[1])):
            print(f"   {kind:11s} busy {union_length(ivs) / 1e3:9.1f} ms  ({len(ivs)} kernels)")
        comm = by_kind.get("collective", [])
        if comm:
            hidden = overlap_length(comm, compute)
            print(f"   collective time under compute: {hidden / 1e3:.1f} ms of {union_length(comm) / 1e3:.1f} ms; "
                  f"GPU idle {(span - union_length(compute + comm)) / 1e3:.1f} ms")
        count = defaultdict(int)
        for e in kernels:
            count[e["name"]] += 1
        for name, dur in sorted(by_name.items(), key=lambda kv: -kv[1])[:top]:
            print(f"   {dur / 1e3:9.2f} ms  {count[name]:7d}x {kind_of(name):10s} {name[:100]}")
        print("   most launched:")
        for name, n in sorted(count.items(), key=lambda kv: -kv[1])[:top]:
            print(f"   {n:7d}x {by_name[name] / 1e3:9.2f} ms  {name[:100]}")
        ops = defaultdict(int)
        for e in events:
            if e.get("pid") == pid and e.get("ph") == "X" and "XLA Ops" in threads.get((pid, e["tid"]), ""):
                ops[e["name"]] += 1
        if ops:
            print("   HLO ops launched most often:")
            for name, n in sorted(ops.items(), key=lambda kv: -kv[1])[:top]:
                print(f"   {n:7d}x {name[:100]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trace_dir")
    ap.add_argument("--top", type=int, default=25)
    a = ap.parse_args()
    summarise(a.trace_dir, a.top)


if __name__ == "__main__":
    main()
