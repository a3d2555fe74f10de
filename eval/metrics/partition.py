"""Multi-object partition metrics of one scene: objects are the trees of the parent map.

Every node is labelled with the root its parent chain ends in; predicted and reference labels are
then compared as two partitions of the same node set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from jax3dc.structure.schema import Structure


def object_labels(s: Structure) -> np.ndarray:
    """Root id of every node, nodes in ascending id order (the parent map is acyclic)."""
    root: dict[int, int] = {}
    for start in s.nodes:
        chain = []
        node = start
        while node not in root and s.nodes[node].parent is not None:
            chain.append(node)
            node = s.nodes[node].parent
        top = root.get(node, node)
        root[node] = top
        for c in chain:
            root[c] = top
    return np.asarray([root[i] for i in sorted(s.nodes)], dtype=np.int64)


@dataclass(frozen=True)
class PartitionScores:
    pred_objects: int
    ref_objects: int
    full_match: bool
    cluster_accuracy: float  # fraction of nodes in Hungarian-matched object pairs
    rand_index: float  # fraction of node pairs on which both partitions agree
    pair_tp: int  # node pairs in the same object on both sides
    pair_pred: int  # node pairs in the same predicted object
    pair_ref: int  # node pairs in the same reference object


def _same_object_pairs(counts: np.ndarray) -> int:
    return int((counts * (counts - 1) // 2).sum())


def partition_scores(pred_labels: np.ndarray, ref_labels: np.ndarray) -> PartitionScores:
    """Compare two labellings of the same nodes through their contingency table.

    The cluster accuracy matches predicted to reference objects one-to-one maximising the shared
    nodes (scipy's Hungarian solver). Same-object pair counts come from the table: a pair is in one
    predicted object and one reference object exactly when both nodes fall in one cell.
    """
    _, p = np.unique(pred_labels, return_inverse=True)
    _, r = np.unique(ref_labels, return_inverse=True)
    table = np.zeros((p.max() + 1, r.max() + 1), dtype=np.int64)
    np.add.at(table, (p, r), 1)
    rows, cols = linear_sum_assignment(table, maximize=True)
    n = len(pred_labels)
    tp = _same_object_pairs(table)
    pred_pairs = _same_object_pairs(table.sum(axis=1))
    ref_pairs = _same_object_pairs(table.sum(axis=0))
    total = n * (n - 1) // 2
    agree = total - pred_pairs - ref_pairs + 2 * tp  # same on both + different on both
    return PartitionScores(
        pred_objects=table.shape[0],
        ref_objects=table.shape[1],
        full_match=bool(table.shape[0] == table.shape[1] == np.count_nonzero(table)),
        cluster_accuracy=float(table[rows, cols].sum() / n),
        rand_index=float(agree / total) if total else 1.0,
        pair_tp=tp,
        pair_pred=pred_pairs,
        pair_ref=ref_pairs,
    )
