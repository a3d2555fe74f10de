"""Part meshes on disk: loading (and its errors), saving, boxes, normalisation, mass properties."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.geometry.mass import mass_properties, solid_of
from jax3dc.geometry.mesh_size import check_object_faces
from jax3dc.geometry.parts import load_parts, normalise_parts, part_boxes, save_parts
from jax3dc.materials import MATERIALS
from jax3dc.structure.schema import FAMILIES


def _box(extents, centre=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(centre)
    return mesh


def test_every_family_has_plausible_properties():
    assert set(MATERIALS) == set(FAMILIES)
    for family, props in MATERIALS.items():
        assert 10 < props.density_kg_m3 < 25000, family
        assert 0 < props.friction <= 2, family
        assert len(props.rgba) == 4 and all(0 <= c <= 1 for c in props.rgba), family
    assert MATERIALS["Metal"].density_kg_m3 > MATERIALS["Glass"].density_kg_m3 > MATERIALS["Wood"].density_kg_m3


def test_save_then_load_keeps_every_vertex_and_triangle(tmp_path):
    rng = np.random.default_rng(0)
    parts = {1: _box([1, 2, 3], [0.1, 0.2, 0.3]), 7: trimesh.creation.icosphere(subdivisions=2)}
    parts[7].vertices += rng.normal(scale=1e-3, size=parts[7].vertices.shape)
    save_parts(parts, tmp_path / "p")
    loaded = load_parts(tmp_path / "p")
    assert list(loaded) == [1, 7]
    for i in parts:
        np.testing.assert_allclose(loaded[i].vertices, parts[i].vertices, rtol=1e-8, atol=1e-9)
        np.testing.assert_array_equal(loaded[i].faces, parts[i].faces)


def test_save_is_byte_deterministic(tmp_path):
    parts = {2: _box([1, 1, 1], [-0.0, 0.5, 0.25]), 1: trimesh.creation.cylinder(0.2, 1.0)}
    save_parts(parts, tmp_path / "a")
    save_parts(dict(reversed(list(parts.items()))), tmp_path / "b")
    for name in ("1.obj", "2.obj"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert b"-0 " not in (tmp_path / "a" / "2.obj").read_bytes()


def test_all_suffixes_load_and_glb_scene_is_flattened_with_transforms(tmp_path):
    _box([1, 1, 1]).export(tmp_path / "1.stl")
    _box([1, 2, 1]).export(tmp_path / "2.ply")
    scene = trimesh.Scene()
    scene.add_geometry(_box([1, 1, 1]), node_name="a", transform=trimesh.transformations.translation_matrix([3, 0, 0]))
    scene.add_geometry(_box([1, 1, 1]), node_name="b")
    scene.export(tmp_path / "3.glb")
    (tmp_path / "parts.json").write_text("{}")  # not a mesh: ignored
    parts = load_parts(tmp_path)
    assert list(parts) == [1, 2, 3]
    assert len(parts[3].faces) == 24
    np.testing.assert_allclose(parts[3].bounds, [[-0.5, -0.5, -0.5], [3.5, 0.5, 0.5]])
    np.testing.assert_allclose(parts[2].extents, [1, 2, 1])


@pytest.mark.parametrize("setup, message", [
    (lambda d: None, "no part meshes"),
    (lambda d: _box([1, 1, 1]).export(d / "door.obj"), "positive integer"),
    (lambda d: _box([1, 1, 1]).export(d / "0.obj"), "positive integer"),
    (lambda d: (_box([1, 1, 1]).export(d / "1.obj"), _box([1, 1, 1]).export(d / "1.stl")), "given twice"),
    (lambda d: (d / "1.ply").write_text("garbage"), "cannot read"),
    (lambda d: (d / "1.obj").write_text("# no faces\nv 0 0 0\n"), "no triangles"),
    (lambda d: (d / "1.obj").write_text("v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "non-finite"),
])
def test_load_parts_errors_name_the_problem(tmp_path, setup, message):
    setup(tmp_path)
    with pytest.raises(InputFileError, match=message):
        load_parts(tmp_path)


def test_missing_directory(tmp_path):
    with pytest.raises(InputFileError, match="not found") as info:
        load_parts(tmp_path / "nowhere")
    assert info.value.path.endswith("nowhere")


def test_part_boxes_are_bounding_box_centre_and_size():
    rng = np.random.default_rng(1)
    points = rng.uniform(-2, 3, size=(40, 3))
    mesh = trimesh.convex.convex_hull(points)
    box = part_boxes({5: mesh})[5]
    np.testing.assert_allclose(box.centroid, (points.min(0) + points.max(0)) / 2)
    np.testing.assert_allclose(box.extent, points.max(0) - points.min(0))


def test_normalise_centres_and_scales_and_returns_units_per_nu():
    parts = {1: _box([2.0, 1.0, 0.5], [10, 0, 0]), 2: _box([1.0, 1.0, 1.0], [12, 0, 3])}
    out, scale = normalise_parts(parts)
    lo = np.min([m.bounds[0] for m in out.values()], axis=0)
    hi = np.max([m.bounds[1] for m in out.values()], axis=0)
    np.testing.assert_allclose((lo + hi) / 2, 0, atol=1e-12)
    assert np.max(hi - lo) == pytest.approx(1.0)
    assert scale == pytest.approx(3.75)  # z spans -0.25..3.5, the largest side (x: 9..12.5)
    np.testing.assert_allclose(out[2].extents * scale, parts[2].extents)


def test_normalise_rejects_zero_size():
    point = trimesh.Trimesh([[1, 1, 1]] * 3, [[0, 1, 2]], process=False)
    with pytest.raises(ValueError):
        normalise_parts({1: point})


def test_mass_properties_match_a_box_formula_after_scaling():
    a, b, c, s, rho = 0.4, 0.6, 1.0, 0.5, 700.0
    props = mass_properties(_box([a, b, c], [1, 2, 3]), rho, s)
    mass = rho * a * b * c * s ** 3
    assert props.solid == "mesh" and props.mass == pytest.approx(mass)
    np.testing.assert_allclose(props.center_of_mass, np.array([1, 2, 3]) * s)
    expected = mass / 12 * np.diag([(b * s) ** 2 + (c * s) ** 2, (a * s) ** 2 + (c * s) ** 2, (a * s) ** 2 + (b * s) ** 2])
    np.testing.assert_allclose(props.inertia, expected, atol=1e-12)


def test_open_mesh_uses_its_hull_and_flat_mesh_a_thin_box():
    closed = _box([1, 2, 3])
    open_mesh = trimesh.Trimesh(closed.vertices, closed.faces[:-2], process=False)
    assert abs(solid_of(open_mesh, min_thickness=1e-9)[0].volume) == pytest.approx(6.0)
    assert mass_properties(open_mesh, 1.0).solid == "convex hull"
    flat = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)
    props = mass_properties(flat, 1000.0, min_thickness_m=0.01)
    assert props.solid == "box" and props.mass == pytest.approx(1000 * 0.01)
    assert np.all(np.linalg.eigvalsh(props.inertia) > 0)


def test_face_caps_refuse_above_and_accept_at_the_cap(tmp_path):
    save_parts({1: trimesh.creation.box(), 2: trimesh.creation.box()}, tmp_path)  # 12 triangles each
    assert set(load_parts(tmp_path, max_faces=12)) == {1, 2}
    with pytest.raises(InputFileError, match="at most 11 .*--max-part-faces"):
        load_parts(tmp_path, max_faces=11)
    boxes = {1: trimesh.creation.box(), 2: trimesh.creation.box()}
    check_object_faces(boxes, 24, "the check")
    with pytest.raises(Jax3dcError, match=r"24 triangles \(part 1: 12\); the check takes at most 23 \(raise it with --max-faces\)"):
        check_object_faces(boxes, 23, "the check")
