"""eval.evaluators.scene_grouping's account of a scene still wrong after grouping: merged and split are told
apart, a right partition is no miss, and the legend cue is read from the boxes."""

from __future__ import annotations

from eval.evaluators.scene_grouping import Miss, miss
from jax3dc.structure import Box, Material, Node, Relation, Structure


def structure(parents: dict[int, int | None], relations: tuple[Relation, ...] = ()) -> Structure:
    return Structure({0: Material("Wood")}, {p: Node(q, 0) for p, q in parents.items()}, relations)


def box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Box:
    return Box(tuple((a + b) / 2 for a, b in zip(lo, hi)), tuple(b - a for a, b in zip(lo, hi)))


# A table (top 1 on leg 2) with a cup 3 on it: one body.
BOXES = {1: box((-0.5, -0.2, 0.0), (0.5, 0.2, 0.05)), 2: box((-0.1, -0.1, -0.5), (0.1, 0.1, 0.0)),
         3: box((0.0, -0.05, 0.05), (0.1, 0.05, 0.15))}
REFERENCE = structure({1: None, 2: 1, 3: None})


def test_a_right_partition_is_no_miss_and_a_merged_one_is_told_from_a_split_one() -> None:
    assert miss(REFERENCE, REFERENCE, REFERENCE, BOXES) is None
    one_tree = structure({1: None, 2: 1, 3: 1}, (Relation("support", 3, 1),))
    assert miss(one_tree, one_tree, REFERENCE, BOXES) == Miss(False, True, False, "one body", True)
    torn = structure({1: None, 2: None, 3: None})
    assert miss(torn, torn, REFERENCE, BOXES) == Miss(True, False, True, "one body", False)
