"""difference() through manifold3d: any closed solids, exact volumes, the deadline between steps."""

import math

import pytest
import trimesh

from jax3dc.program import csg
from jax3dc.program import solids as S


def ngon_area(r: float, n: int) -> float:
    return 0.5 * n * r * r * math.sin(2 * math.pi / n)


def as_trimesh(solid: S.Solid) -> trimesh.Trimesh:
    return trimesh.Trimesh(solid.vertices, solid.faces, process=False)


def test_tube_from_two_cylinders_has_the_polygon_ring_volume():
    """A shape the former box-only path refused: coaxial 24-gon prisms, the cutter longer."""
    outer = S.frustum(1.0, 1.0, 2.0, (0, 0, 0), "y", 24)
    inner = S.frustum(0.6, 0.6, 3.0, (0, 0, 0), "y", 24)
    tube = csg.difference(outer, [inner])
    mesh = as_trimesh(tube)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert tube.signed_volume() == pytest.approx((ngon_area(1.0, 24) - ngon_area(0.6, 24)) * 2.0, rel=1e-12)


def test_box_cuts_are_exact_and_watertight():
    """The furniture case (a carcass and a sink opening) to the last digits of float64."""
    carcass = S.box((0.8, 0.5, 1.2), (0, 0, 0.6))
    cavity = S.box((0.76, 0.49, 1.16), (0, -0.0055, 0.6))
    hole = S.box((0.3, 0.2, 0.3), (0, 0, 1.2))
    out = csg.difference(carcass, [cavity, hole])
    # the cavity leaves through the front (0.4895 of its 0.49 inside); the hole cuts the 0.02 top
    expected = 0.8 * 0.5 * 1.2 - 0.76 * 0.4895 * 1.16 - 0.3 * 0.2 * 0.02
    assert out.signed_volume() == pytest.approx(expected, rel=1e-12)
    assert as_trimesh(out).is_watertight


def test_sphere_minus_sphere_matches_the_cap_formula():
    """Two unit-ish spheres overlapping by a lens; volume within the tessellation error."""
    a = S.uv_sphere(1.0, (0, 0, 0), 128, 64)
    b = S.uv_sphere(1.0, (1.0, 0, 0), 128, 64)
    out = csg.difference(a, [b])
    h = 0.5  # each cap of the lens
    lens = 2 * math.pi * h * h * (3 - h) / 3
    assert out.signed_volume() == pytest.approx(4 / 3 * math.pi - lens, rel=2e-3)
    assert as_trimesh(out).is_watertight


def test_open_mesh_is_refused_with_its_role():
    box = S.box((1, 1, 1), (0, 0, 0))
    open_box = S.Solid(box.vertices, box.faces[:-2])
    with pytest.raises(ValueError, match="cutter 2 is not a closed solid"):
        csg.difference(box, [S.box((0.1, 0.1, 0.1), (0, 0, 0)), open_box])
    with pytest.raises(ValueError, match="base is not a closed solid"):
        csg.difference(open_box, [box])


def test_removing_everything_is_an_error():
    with pytest.raises(ValueError, match="removes the whole solid"):
        csg.difference(S.box((1, 1, 1), (0, 0, 0)), [S.box((2, 2, 2), (0, 0, 0))])


def test_deadline_is_checked_between_steps():
    """check_time runs before every batch of cutters, so a spent budget stops the call part-way."""
    cutters = [S.box((0.01, 0.01, 0.01), (i / 100 - 0.45, 0, 0)) for i in range(90)]
    calls = []

    def check_time() -> None:
        calls.append(1)
        if len(calls) == 3:
            raise TimeoutError

    with pytest.raises(TimeoutError):
        csg.difference(S.box((1, 1, 1), (0, 0, 0)), cutters, check_time)
    assert len(calls) == 3
    calls.clear()
    out = csg.difference(S.box((1, 1, 1), (0, 0, 0)), cutters[:32], lambda: calls.append(1))
    assert len(calls) == math.ceil(32 / csg.CUTTERS_PER_STEP)
    assert out.signed_volume() == pytest.approx(1 - 32 * 1e-6, rel=1e-12)
