"""RS-dgIoU and the part scores of issue 64 on cases computed by hand."""

from __future__ import annotations

import numpy as np
import pytest

from eval.metrics.part_boxes import giou_3d, rs_dgiou, score_part_boxes, summarise

UNIT = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
HALF_SHIFTED = UNIT + [0.5, 0.0, 0.0]  # overlaps UNIT by half: IoU 1/3, enclosing box = union, gIoU 1/3
FAR = UNIT + [3.0, 0.0, 0.0]  # disjoint: enclosing 4, union 2, gIoU 0 - 2/4 = -0.5


def test_giou_by_hand():
    assert giou_3d(UNIT, UNIT) == pytest.approx(1.0)
    assert giou_3d(UNIT, HALF_SHIFTED) == pytest.approx(1 / 3)
    assert giou_3d(UNIT, FAR) == pytest.approx(-0.5)


def test_rs_dgiou_by_hand():
    assert rs_dgiou([UNIT], [UNIT]) == pytest.approx(0.0)
    assert rs_dgiou([UNIT], [HALF_SHIFTED]) == pytest.approx(2 / 3)
    assert rs_dgiou([UNIT], [FAR]) == pytest.approx(1.5)
    # one extra predicted part: predicted side (0 + 2) / 2 = 1, reference side 0 / 1 = 0
    assert rs_dgiou([UNIT], [UNIT, FAR]) == pytest.approx(0.5)
    # one reference part missed: reference side (0 + 2) / 2, predicted side 0
    assert rs_dgiou([UNIT, FAR], [UNIT]) == pytest.approx(0.5)
    assert rs_dgiou([UNIT], []) == 2.0 and rs_dgiou([], []) == 0.0
    # the pairing follows box distance: each prediction goes to the reference part it sits on
    assert rs_dgiou([UNIT, FAR], [FAR, UNIT]) == pytest.approx(0.0)


def test_matched_extra_and_kinds_by_hand():
    score = score_part_boxes("k", [UNIT, FAR, FAR + [0, 5, 0]], ["door", None, "handle"],
                             [UNIT, FAR, HALF_SHIFTED + [0, 20, 0]], ["door", "lid", "knob"])
    assert (score.reference, score.predicted, score.matched, score.extra) == (3, 3, 2, 1)
    assert (score.kinds_scored, score.kinds_right) == (1, 1)  # the FAR pair's reference names no kind
    low = score_part_boxes("k", [UNIT], ["door"], [HALF_SHIFTED], ["door"])  # IoU 1/3 < 0.5: not matched
    assert (low.matched, low.extra) == (0, 1)
    total = summarise([score, low])
    assert total["matched_share"] == pytest.approx(2 / 4) and total["extra_share"] == pytest.approx(2 / 4)
    assert total["kind_accuracy"] == 1.0 and total["rs_dgiou"] == pytest.approx((score.dgiou + 2 / 3) / 2, abs=1e-4)
