"""Parent accuracy and directed edge F1, vectorised over the nodes of a batch of objects.

Both sides have the same node ids (validation checks a prediction against the reference part
ids), so a node's parent on each side is one row of two aligned arrays.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from jax3dc.structure.schema import Structure

NO_PARENT = -1


@dataclass(frozen=True)
class ParentRows:
    """Node rows of a batch: object ``o`` owns ``offsets[o]:offsets[o + 1]``; -1 = root."""

    offsets: np.ndarray
    pred_parent: np.ndarray
    ref_parent: np.ndarray


def parent_rows(preds: Sequence[Structure], refs: Sequence[Structure]) -> ParentRows:
    """Aligned parent arrays, nodes in ascending id order within each object."""
    counts, pred_parent, ref_parent = [], [], []
    for p, r in zip(preds, refs, strict=True):
        counts.append(len(r.nodes))
        for i in sorted(r.nodes):
            rp, pp = r.nodes[i].parent, p.nodes[i].parent
            ref_parent.append(NO_PARENT if rp is None else rp)
            pred_parent.append(NO_PARENT if pp is None else pp)
    offsets = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return ParentRows(offsets, np.asarray(pred_parent, np.int64), np.asarray(ref_parent, np.int64))


@dataclass(frozen=True)
class TreeCounts:
    """Per object: nodes, nodes with the right parent, and edge counts for F1."""

    nodes: np.ndarray
    parent_correct: np.ndarray
    edge_tp: np.ndarray
    edge_pred: np.ndarray
    edge_ref: np.ndarray


def tree_counts(rows: ParentRows) -> TreeCounts:
    """Count per object; a root counts as correct when it is a root on both sides.

    Edges are child -> parent pairs; roots have none. Since the child ids are shared, an edge is a
    true positive exactly when the node has the same non-null parent on both sides.
    """
    n_obj = len(rows.offsets) - 1
    obj = np.repeat(np.arange(n_obj), np.diff(rows.offsets))
    same = rows.pred_parent == rows.ref_parent
    has_ref = rows.ref_parent != NO_PARENT
    has_pred = rows.pred_parent != NO_PARENT

    def per_object(flags: np.ndarray) -> np.ndarray:
        return np.bincount(obj, weights=flags, minlength=n_obj).astype(np.int64)

    return TreeCounts(
        nodes=np.diff(rows.offsets),
        parent_correct=per_object(same),
        edge_tp=per_object(same & has_ref),
        edge_pred=per_object(has_pred),
        edge_ref=per_object(has_ref),
    )
