"""Stage-1 program scores: the record's own program scores perfectly, changes are seen."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import cdist

from eval.metrics.programs import box_iou, chamfer, score_program, summarise

PROGRAM = """mat = material('Wood', 'oak')
body_1 = box(size=(1, 0.5, 0.5), center=(0, 0, 0))
part(1, 'body', body_1, material=mat)
lid_2 = box(size=(1, 0.5, 0.1), center=(0, 0, 0.3))
part(2, 'lid', lid_2, material=mat)
"""


def test_box_iou_against_volumes() -> None:
    a = np.array([[0, 0, 0], [2, 1, 1]], float)
    b = np.array([[1, 0, 0], [3, 1, 1]], float)
    assert box_iou(a, a) == 1.0
    assert box_iou(a, b) == pytest.approx(1 / 3)  # overlap 1 of union 3
    assert box_iou(a, a + 5) == 0.0


def test_chamfer_matches_brute_force() -> None:
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(50, 3)), rng.normal(size=(70, 3))
    d = cdist(a, b)
    assert chamfer(a, b) == pytest.approx((d.min(1).mean() + d.min(0).mean()) / 2)


def test_own_program_is_perfect_and_changes_are_scored() -> None:
    same = score_program("k", PROGRAM, PROGRAM)
    assert same.runs and same.ids and same.count_err == 0 and same.box_iou == 1.0 and same.chamfer == 0.0
    moved = score_program("k", PROGRAM, PROGRAM.replace("center=(0, 0, 0.3)", "center=(0, 0, 0.5)"))
    assert moved.runs and moved.ids and moved.box_iou == pytest.approx((1 + 0.0) / 2)  # lid boxes apart
    assert moved.chamfer > 0.01
    dropped = score_program("k", PROGRAM, PROGRAM.split("lid_2")[0])
    assert dropped.runs and not dropped.ids and dropped.count_err == 1 and dropped.box_iou == pytest.approx(0.5)
    broken = score_program("k", PROGRAM, "import os\n")
    assert not broken.runs and broken.box_iou == 0.0 and broken.chamfer is None and broken.error
    row = summarise([same, moved, dropped, broken])
    assert row["runs"] == 75.0 and row["ids"] == 50.0 and row["count_err"] == 0.75  # a broken program misses every part
    assert row["box_iou"] == pytest.approx(100 * (1 + 0.5 + 0.5 + 0) / 4)
