"""Throughput of the Table 1 metrics on one CPU core (issue 7: >= 2,000 objects per second).

Run from the repository root:  python3 bench/metrics.py [--objects 5000] [--seed 0]

Synthetic split: random part trees of 3-20 parts with boxes, hinges and slides on about a third of
the nodes and symmetric / instance relations; each prediction is its reference with noise (some
parents moved, joints dropped, added, tilted, shifted and re-ranged). Prints two figures:
  * metrics: `evaluate` on parsed, canonical structures (the Table 1 metric computation);
  * end to end: prediction JSON text -> parse + validate + canonicalise -> `evaluate`.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from eval.metrics import Reference, build_cases, evaluate  # noqa: E402
from jax3dc.structure import canonicalize, to_json  # noqa: E402
from jax3dc.structure.schema import Box, Joint, Material, Node, Relation, Structure  # noqa: E402


def _joint(rng: np.random.Generator) -> Joint:
    if rng.random() < 0.6:
        lo = float(rng.uniform(-1.5, 0.0))
        return Joint("hinge", tuple(rng.normal(size=3)), tuple(rng.uniform(-0.5, 0.5, 3)), (lo, lo + float(rng.uniform(0.5, 2.0))))
    return Joint("slide", tuple(rng.normal(size=3)), tuple(rng.uniform(-0.5, 0.5, 3)), (0.0, float(rng.uniform(0.1, 0.5))))


def _reference(rng: np.random.Generator) -> tuple[Structure, dict[int, Box]]:
    n = int(rng.integers(3, 21))
    boxes = {i: Box(tuple(rng.uniform(-0.4, 0.4, 3)), tuple(rng.uniform(0.02, 1.0, 3))) for i in range(1, n + 1)}
    nodes = {1: Node(None, 0)}
    for i in range(2, n + 1):
        nodes[i] = Node(int(rng.integers(1, i)), 0, _joint(rng) if rng.random() < 0.35 else None)
    relations = []
    for _ in range(int(rng.integers(0, 3))):
        a, b = (int(x) for x in rng.choice(np.arange(2, n + 1), size=2, replace=False)) if n > 2 else (1, 2)
        relations.append(Relation("symmetric", a, b, "yz") if rng.random() < 0.5 else Relation("instance", a, b))
    return canonicalize(Structure({0: Material("Wood")}, nodes, tuple(relations)), boxes), boxes


def _prediction(ref: Structure, rng: np.random.Generator) -> Structure:
    nodes = {}
    for i, node in ref.nodes.items():
        parent, joint = node.parent, node.joint
        if parent is not None and rng.random() < 0.15:
            parent = ref.roots()[0] if parent != ref.roots()[0] else parent
        if joint is not None:
            if rng.random() < 0.1:
                joint = None
            else:
                axis = tuple(np.asarray(joint.axis) + rng.normal(scale=0.1, size=3))
                pivot = tuple(np.asarray(joint.pivot) + rng.normal(scale=0.03, size=3))
                lo, hi = joint.range
                joint = Joint(joint.type, axis, pivot, (lo + float(rng.normal(scale=0.1)), hi + abs(float(rng.normal(scale=0.3)))))
        elif parent is not None and rng.random() < 0.05:
            joint = _joint(rng)
        nodes[i] = Node(parent, node.material, joint)
    return Structure(ref.materials, nodes, ref.relations)


def _time(fn, repeats: int = 3) -> tuple[float, float]:
    """Best wall and CPU seconds over ``repeats`` runs (CPU time is the fairer figure on a busy
    machine: it does not count time the core spent on other processes)."""
    wall = cpu = float("inf")
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall, cpu = min(wall, time.perf_counter() - t), min(cpu, time.process_time() - c)
    return wall, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--objects", type=int, default=5000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})

    rng = np.random.default_rng(args.seed)
    refs, texts = [], {}
    for k in range(args.objects):
        structure, boxes = _reference(rng)
        key = f"obj{k}"
        refs.append(Reference(key, structure, boxes))
        texts[key] = to_json(_prediction(structure, rng))
    cases = build_cases(refs, texts)
    parsed = sum(c.prediction is not None for c in cases)
    joints = sum(len(r.structure.joints()) for r in refs)

    t_metrics = _time(lambda: evaluate(cases))
    t_total = _time(lambda: evaluate(build_cases(refs, texts)), repeats=1)
    m = evaluate(cases).metrics
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}, one core")
    print(f"split: {args.objects} objects, {joints} reference joints, {parsed} predictions parsed")
    for what, (wall, cpu) in (("metrics (evaluate on canonical structures)", t_metrics),
                              ("end to end (parse + canonicalise + evaluate)", t_total)):
        print(f"{what}: {args.objects / wall:,.0f} objects/s wall ({wall:.3f} s), "
              f"{args.objects / cpu:,.0f} objects per CPU second")
    print("sample metrics:", json.dumps({k: None if m[k] is None else round(m[k], 2) for k in
                                           ("parent_acc", "edge_f1", "presence_f1", "axis_acc", "pos_err", "success")}))


if __name__ == "__main__":
    main()
