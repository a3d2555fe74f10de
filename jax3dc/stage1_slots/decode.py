"""One image's slot outputs -> its parts: the slots that exist, their boxes, kinds and a parent tree.

A slot is kept when its exists probability is at least ``threshold``. Its box is clipped to the
normalised frame (extent at least MIN_EXTENT, so every box is a solid). Its parent is the arg-max
of its parent logits over the other kept slots and "root" only (a pointer to a dropped slot would
name nothing). A cycle of pointers cannot be a tree: the member of each cycle with the largest root
logit becomes a root. Any outputs (an untrained network's, NaNs included) decode into a valid
forest, possibly empty.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jax3dc.stage1_slots.kinds import KINDS

MIN_EXTENT = 1e-3  # nu: the thinnest box a slot gives


@dataclass(frozen=True)
class PartSlot:
    """One part a slot wrote: its box in the normalised frame, kind, parent (an index into the same
    list, None for a root) and exists probability."""

    centre: tuple[float, float, float]
    extent: tuple[float, float, float]
    kind: str
    parent: int | None
    score: float

    def to_dict(self) -> dict:
        return {"centre": [round(v, 4) for v in self.centre], "extent": [round(v, 4) for v in self.extent],
                "kind": self.kind, "parent": self.parent, "score": round(self.score, 4)}


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.clip(x, -60.0, 60.0)))


def _break_cycles(parents: list[int | None], root_logits: np.ndarray) -> list[int | None]:
    parents = list(parents)
    for start in range(len(parents)):
        path, node = [], start
        while node is not None and node not in path:
            path.append(node)
            node = parents[node]
        if node is not None:  # the walk came back to ``node``: the cycle is path[path.index(node):]
            cycle = path[path.index(node):]
            parents[max(cycle, key=lambda i: root_logits[i])] = None
    return parents


def decode_slots(exists: np.ndarray, boxes: np.ndarray, kinds: np.ndarray, parents: np.ndarray,
                 threshold: float = 0.5) -> list[PartSlot]:
    """The kept slots of one image ([K], [K, 6], [K, kinds], [K, K + 1]), in slot order."""
    exists = np.nan_to_num(np.asarray(exists, np.float64), nan=-np.inf)
    keep = np.flatnonzero(_sigmoid(exists) >= threshold)
    boxes = np.nan_to_num(np.asarray(boxes, np.float64), nan=0.0)
    kinds = np.nan_to_num(np.asarray(kinds, np.float64), nan=-np.inf)
    logits = np.nan_to_num(np.asarray(parents, np.float64), nan=-np.inf)
    k = len(exists)
    root_logits = logits[keep, k]
    chosen: list[int | None] = []
    for slot in keep:
        candidates = [j for j in keep if j != slot]
        scores = [logits[slot, j] for j in candidates] + [logits[slot, k]]
        best = int(np.argmax(scores)) if np.isfinite(scores).any() else len(candidates)
        chosen.append(None if best == len(candidates) else int(np.flatnonzero(keep == candidates[best])[0]))
    chosen = _break_cycles(chosen, root_logits)
    out = []
    for row, slot in enumerate(keep):
        centre = np.clip(boxes[slot, :3], -0.5, 0.5)
        extent = np.clip(boxes[slot, 3:], MIN_EXTENT, 1.0)
        kind = int(np.argmax(kinds[slot])) if np.isfinite(kinds[slot]).any() else KINDS.index("other")
        out.append(PartSlot(tuple(float(v) for v in centre), tuple(float(v) for v in extent),
                            KINDS[kind] if kind < len(KINDS) else "other", chosen[row],
                            float(_sigmoid(exists[slot]))))
    return out
