"""Joint geometry: hand-worked values, and line distance against a numerical minimisation."""

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from eval.metrics.geometry import align_ranges, axis_angle, interval_iou, interval_overlap, line_distance


def rows(*vs):
    return np.asarray(vs, dtype=float)


def test_axis_angle_is_sign_invariant_and_exact():
    got = axis_angle(rows((1, 0, 0), (0, 0, 1), (1, 1, 0), (0, 0, 2)), rows((0, 1, 0), (0, 0, -1), (1, 0, 0), (0, 0, 1)))
    # perpendicular -> pi/2; opposite -> same line, 0; 45 degrees; lengths do not matter
    np.testing.assert_allclose(got, [math.pi / 2, 0.0, math.pi / 4, 0.0], atol=1e-12)
    # accurate for tiny angles, where arccos(dot) loses everything below ~1e-8
    tiny = axis_angle(rows((1, 0, 0)), rows((1, 1e-10, 0)))
    np.testing.assert_allclose(tiny, [1e-10], rtol=1e-6)


def test_line_distance_hand_worked():
    # x axis through the origin vs y-direction line through (3, 5, 2): a1 x a2 = z, d . z = 2
    # z axis vs a reversed z axis through (0.3, 0.4, 7): parallel, ||d x z|| = sqrt(0.09 + 0.16) = 0.5
    # two lines crossing at (1, 1, 1): 0
    got = line_distance(
        rows((0, 0, 0), (0, 0, 0), (1, 0, 1)),
        rows((1, 0, 0), (0, 0, 1), (0, 1, 0)),
        rows((3, 5, 2), (0.3, 0.4, 7), (0, 1, 1)),
        rows((0, 1, 0), (0, 0, -1), (1, 0, 0)),
    )
    np.testing.assert_allclose(got, [2.0, 0.5, 0.0], atol=1e-12)


def test_line_distance_parallel_is_the_perpendicular_offset_not_an_arbitrary_component():
    # Offset (0.3, 0.4) perpendicular to z: any single perpendicular component would give 0.3 or 0.4.
    p2 = rows((0.3, 0.4, -2.0))
    for a2 in [(0, 0, 1), (0, 0, -1), (0, 1e-9, 1)]:
        np.testing.assert_allclose(line_distance(rows((0, 0, 0)), rows((0, 0, 1)), p2, rows(a2)), [0.5], atol=1e-8)


def _numeric_line_distance(p1, a1, p2, a2):
    f = lambda t: np.sum((p1 + t[0] * a1 - p2 - t[1] * a2) ** 2)
    return math.sqrt(minimize(f, [0.0, 0.0], method="BFGS", options={"gtol": 1e-12}).fun)


def test_line_distance_matches_numerical_minimum_on_random_skew_lines():
    rng = np.random.default_rng(0)
    p1, a1, p2, a2 = (rng.normal(size=(20, 3)) for _ in range(4))
    got = line_distance(p1, a1, p2, a2)
    want = [_numeric_line_distance(*(x[i] for x in (p1, a1, p2, a2))) for i in range(20)]
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_align_ranges_negates_and_swaps_only_when_axes_oppose():
    got = align_ranges(rows((0, 0, -1), (0, 0, 1)), rows((0.2, 1.0), (0.2, 1.0)), rows((0, 0, 1), (0, 0, 1)))
    np.testing.assert_allclose(got, [[-1.0, -0.2], [0.2, 1.0]])


def test_interval_iou_hand_worked():
    a = rows((0, 2), (0, 1), (0, 1), (0.5, 0.5), (0.5, 0.5))
    b = rows((1, 3), (2, 3), (0, 4), (0.5, 0.5), (0, 1))
    # [0,2]&[1,3]: 1 / (2 + 2 - 1) = 1/3; disjoint: 0; nested: 1/4; equal points: 1; point in interval: 0
    np.testing.assert_allclose(interval_iou(a, b), [1 / 3, 0.0, 0.25, 1.0, 0.0])
    np.testing.assert_allclose(interval_overlap(a, b), [1.0, 0.0, 1.0, 0.0, 0.0])


@pytest.mark.parametrize("flip", [False, True])
def test_flipping_the_predicted_axis_with_negated_range_changes_nothing(flip):
    ref_axis, pred_axis, pred_range = rows((0, 0, 1)), rows((0.1, 0, 1)), rows((0.3, 1.2))
    if flip:
        pred_axis, pred_range = -pred_axis, -pred_range[:, ::-1]
    assert axis_angle(pred_axis, ref_axis)[0] == pytest.approx(math.atan(0.1))
    np.testing.assert_allclose(align_ranges(pred_axis, pred_range, ref_axis), [[0.3, 1.2]])


def test_line_distance_stays_finite_for_absurd_pivots():
    # squaring 1e200 would overflow; the distance is still exact
    got = line_distance(rows((0, 0, 0), (0, 0, 0)), rows((0, 0, 1), (0, 0, 1)),
                        rows((3e200, 4e200, 1.0), (0, 1e300, 0)), rows((0, 0, 1), (1, 0, 0)))
    np.testing.assert_allclose(got, [5e200, 1e300])
