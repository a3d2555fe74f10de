"""Time of checking the largest documents `validate` accepts, against `json.loads` of the same text
(the floor: every check reads the parsed document once). The unit tests check what these documents
give; their time is measured here, where load on a shared machine cannot fail a test.

Run from the repository root:  python3 bench/structure_validate.py [--repeats 5]

Cases: a 3,000-node chain with a joint on every node (depth 3,000), 20,000 relations, and a
document over MAX_DOCUMENT_BYTES (refused by its size). CPU time (process_time), fastest of the
repeats; the ratio is validate / json.loads, so a check that grows faster than the text shows.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable

from jax3dc.structure import MAX_DOCUMENT_BYTES, parse_structure, validate


def _chain(n: int) -> str:
    nodes: dict = {"1": {"parent": None, "material": 0}}
    for i in range(2, n + 1):
        nodes[str(i)] = {"parent": i - 1, "material": 0, "joint": {
            "type": "slide", "axis": [0.577, 0.577, 0.577], "pivot": [0.1, 0.2, 0.3], "range": [0, 0.5]}}
    return json.dumps({"materials": {"0": {"family": "Wood"}}, "nodes": nodes, "relations": []})


def _relations(n: int) -> str:
    nodes = {"1": {"parent": None, "material": 0}}
    nodes |= {str(i): {"parent": 1, "material": 0} for i in range(2, 6)}
    relations = [{"type": "instance", "a": 1 + k % 5, "b": 1 + (k + 1) % 5} for k in range(n)]
    return json.dumps({"materials": {"0": {"family": "Wood"}}, "nodes": nodes, "relations": relations})


def _best(fn: Callable[[], object], repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per case; the fastest counts")
    args = parser.parse_args()
    chain, relations = _chain(3000), _relations(20000)
    oversize = chain[:-1] + ',"pad":"' + "x" * MAX_DOCUMENT_BYTES + '"}'
    cases = {
        "chain of 3000 joints (parse_structure)": (chain, lambda: parse_structure(chain, part_ids=range(1, 3001))),
        "20000 relations (validate)": (relations, lambda: validate(relations)),
        "over the size limit (validate)": (oversize, lambda: validate(oversize)),
    }
    for name, (text, check) in cases.items():
        ours = _best(check, args.repeats)
        floor = _best(lambda: json.loads(text), args.repeats)
        print(f"{name}: {len(text) / 1e6:.2f} MB, {ours * 1e3:.3f} ms; json.loads {floor * 1e3:.1f} ms; "
              f"ratio {ours / floor:.3f}")


if __name__ == "__main__":
    main()
