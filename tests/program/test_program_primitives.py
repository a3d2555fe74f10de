"""Every predefined shape is a closed, consistently wound mesh with the volume geometry predicts.

Reference volumes: exact formulas for the polyhedra the builders make (regular n-gon areas,
prism / pyramid / frustum volumes, the chamfered-box formula), and the smooth solids' analytic
volumes (sphere, torus, Pappus) at a tolerance that the segment count justifies.
"""

import math

import numpy as np
import pytest

from jax3dc.program import run_program


def ngon_area(r, n):
    return 0.5 * n * r * r * math.sin(2 * math.pi / n)


def revolve_factor(n):
    """Area of a regular n-gon over that of its circumscribed circle."""
    return n * math.sin(2 * math.pi / n) / (2 * math.pi)


def pappus_moment(points):
    """First moment of a (r, h) polygon about the axis: area x centroid radius."""
    p = np.asarray(points, dtype=float)
    x, y = p[:, 0], p[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cross = x * y1 - x1 * y
    return abs(np.sum((x + x1) * cross) / 6.0)


def shoelace(points):
    p = np.asarray(points, dtype=float)
    return 0.5 * abs(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(np.roll(p[:, 0], -1), p[:, 1]))


def build(expr):
    result = run_program(f'm = {expr}\npart(1, "p", m)\n')
    mesh = result.parts[1]
    assert mesh.is_watertight, expr
    assert mesh.is_winding_consistent, expr
    assert mesh.volume > 0, expr  # outward winding
    return mesh


L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]

CASES = [
    ("box((0.3, 0.5, 0.7), center=(1, 2, 3))", 0.3 * 0.5 * 0.7, 1e-12),
    ("cube(0.4)", 0.4 ** 3, 1e-12),
    ("cylinder(radius=0.2, depth=0.6, axis='x', segments=40)", ngon_area(0.2, 40) * 0.6, 1e-9),
    ("cylinder(radius=0.2, depth=0.6, segments=256)", math.pi * 0.04 * 0.6, 2e-4),
    ("cone(radius1=0.3, radius2=0, depth=0.9, axis='y', segments=24)", ngon_area(0.3, 24) * 0.9 / 3, 1e-9),
    ("cone(radius1=0.3, radius2=0.1, depth=0.5, segments=24)",
     0.5 / 3 * (ngon_area(0.3, 24) + ngon_area(0.1, 24) + math.sqrt(ngon_area(0.3, 24) * ngon_area(0.1, 24))), 1e-9),
    ("sphere(radius=0.5, segments=128, rings=64)", 4 / 3 * math.pi * 0.125, 2e-3),
    ("torus(major_radius=0.5, minor_radius=0.1, major_segments=128, minor_segments=64)",
     2 * math.pi ** 2 * 0.5 * 0.01, 3e-3),  # n-gon deficits (2pi/n)^2/6: 0.16% + 0.04%
    # a polygon revolved in n steps: the smooth volume scaled by the n-gon/circle area ratio
    ("torus(major_radius=0.5, minor_radius=0.1, major_segments=20, minor_segments=7)",
     revolve_factor(20) * 2 * math.pi * ngon_area(0.1, 7) * 0.5, 1e-9),
    (f"extrude({L_SHAPE}, depth=0.5, axis='y')", shoelace(L_SHAPE) * 0.5, 1e-12),
    (f"extrude({L_SHAPE[::-1]}, depth=0.5, axis='x')", shoelace(L_SHAPE) * 0.5, 1e-12),
    # annulus profile r in [1, 2], h in [0, 1]: exact polygonal ring volume
    ("lathe([(1, 0), (2, 0), (2, 1), (1, 1)], segments=48)", ngon_area(1, 48) * (4 - 1), 1e-9),
    # triangle touching the axis: a cone; Pappus for the smooth solid
    ("lathe([(0, 0), (1, 0), (0, 1)], segments=256, axis='x')", math.pi / 3, 2e-4),
    ("lathe([(0, 0), (1, 0), (0.5, 1), (0, 1.5)], segments=10)",
     revolve_factor(10) * 2 * math.pi * pappus_moment([(0, 0), (1, 0), (0.5, 1), (0, 1.5)]), 1e-9),
    ("sweep([(0, 0, 0), (0, 0, 1)], radius=0.1, segments=32)", ngon_area(0.1, 32), 1e-9),
    # a mitred bend keeps volume = section area x centreline length
    ("sweep([(0, 0, 0), (0, 0, 1), (1, 0, 1), (1, 1, 2)], radius=0.05, segments=32)",
     ngon_area(0.05, 32) * (1 + 1 + math.sqrt(2)), 1e-6),
    ("bevel((1, 2, 3), width=0.1)", 6 - 2 * 0.01 * 6 + 16 / 3 * 0.001, 1e-9),
    ("difference(box((1, 1, 1)), box((0.8, 0.8, 0.8), center=(0, -0.2, 0)))", 1 - 0.8 * 0.7 * 0.8, 1e-12),
    ("difference(box((1, 1, 1)), box((0.3, 3, 0.3)), box((0.2, 0.2, 0.2), center=(0.3, 0.3, 0.3)))",
     1 - 0.09 - 0.008, 1e-12),
    ("difference(box((1, 1, 1)), box((0.2, 0.2, 0.2), center=(5, 5, 5)))", 1.0, 1e-12),
    ("mirror(cone(0.3, 0.1, 0.5, center=(1, 0, 0), axis='x', segments=16), 'yz', (0.2, 0, 0))",
     0.5 / 3 * (ngon_area(0.3, 16) + ngon_area(0.1, 16) + math.sqrt(ngon_area(0.3, 16) * ngon_area(0.1, 16))), 1e-9),
    ("rotate(box((1, 2, 3)), 33, axis=(1, 1, 0), center=(1, 0, 0))", 6.0, 1e-9),
    ("scale(box((1, 2, 3)), (2, -1, 0.5))", 6.0, 1e-9),
    ("scale(sphere(0.5, segments=128, rings=64), 2)", 4 / 3 * math.pi, 2e-3),
]


@pytest.mark.parametrize("expr,volume,rel", CASES)
def test_primitive_volume(expr, volume, rel):
    mesh = build(expr)
    assert mesh.volume == pytest.approx(volume, rel=rel)


def test_primitives_are_placed_where_asked():
    m = build("cylinder(radius=0.1, depth=2, center=(1, 2, 3), axis='y')")
    assert np.allclose(m.bounds, [[0.9, 1, 2.9], [1.1, 3, 3.1]], atol=1e-9)
    m = build("mirror(box((1, 1, 1), center=(2, 0, 0)), 'yz')")
    assert np.allclose(m.bounds, [[-2.5, -0.5, -0.5], [-1.5, 0.5, 0.5]])
    m = build("rotate(box((2, 0.2, 0.2), center=(1, 0, 0)), 90, axis='z')")
    assert np.allclose(m.bounds, [[-0.1, 0, -0.1], [0.1, 2, 0.1]], atol=1e-9)
    m = build("extrude([(0, 0), (1, 0), (0, 2)], depth=0.5, axis='y', center=(0, 1, 0))")
    assert np.allclose(m.bounds, [[0, 0.75, 0], [1, 1.25, 2]])


def test_arrays_copy_the_mesh():
    unit = 0.1 * 0.2 * 0.3
    a = run_program('b = box((0.1, 0.2, 0.3))\npart(1, "a", linear_array(b, 4, (0.5, 0, 0)))\n').parts[1]
    assert a.volume == pytest.approx(4 * unit) and a.bounds[1][0] == pytest.approx(1.55)
    g = run_program('b = box((0.1, 0.2, 0.3))\npart(1, "a", grid_array(b, (2, 3, 1), (1, 1, 1)))\n').parts[1]
    assert g.volume == pytest.approx(6 * unit) and np.allclose(g.bounds[1], [1.05, 2.1, 0.15])
    r = run_program('b = box((0.1, 0.1, 0.1), center=(1, 0, 0))\npart(1, "a", radial_array(b, 4))\n').parts[1]
    assert r.volume == pytest.approx(4 * 0.001)
    assert np.allclose(r.bounds, [[-1.05, -1.05, -0.05], [1.05, 1.05, 0.05]], atol=1e-9)
    for mesh in (a, g, r):
        assert mesh.is_watertight and mesh.is_winding_consistent
