"""Mesh backend input conventions: a +Y-up (glTF) file, OBJ objects with groups inside, part limits."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from jax3dc.predict.mesh_input import Y_UP_TO_Z_UP, load_segmented_mesh
from jax3dc.errors import InputFileError
from jax3dc.palette import PALETTE_SIZE
from predict_cases import factory_object


def sorted_triangles(mesh: trimesh.Trimesh) -> np.ndarray:
    return np.sort(np.asarray(mesh.triangles).reshape(-1, 9), axis=0)


def test_y_up_glb_turns_into_the_factory_frame(tmp_path):
    """A tool that writes glTF's +Y up (front +Z) moved our +Z up, front -Y object this way."""
    parts = factory_object().parts
    z_to_y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # (x, y, z) -> (x, z, -y)
    scene = trimesh.Scene()
    for pid, mesh in parts.items():
        scene.add_geometry(trimesh.Trimesh(np.asarray(mesh.vertices) @ z_to_y.T, mesh.faces, process=False),
                           node_name=str(pid), geom_name=f"mesh_{pid}")
    path = tmp_path / "y_up.glb"
    scene.export(str(path))
    loaded, _ = load_segmented_mesh(path, up="y")
    assert sorted(loaded) == sorted(parts)
    for pid, mesh in parts.items():
        np.testing.assert_allclose(sorted_triangles(loaded[pid]), sorted_triangles(mesh), atol=1e-5)
    as_z_up, _ = load_segmented_mesh(path)  # read as +Z up, the object lies on its back
    top = max(parts, key=lambda pid: parts[pid].bounds[1, 2])
    assert not np.allclose(as_z_up[top].bounds, parts[top].bounds, atol=1e-3)


def test_y_up_to_z_up_is_a_rotation_mapping_up_and_front():
    assert np.linalg.det(Y_UP_TO_Z_UP) == pytest.approx(1.0)
    np.testing.assert_allclose(Y_UP_TO_Z_UP @ [0.0, 1.0, 0.0], [0.0, 0.0, 1.0])  # up
    np.testing.assert_allclose(Y_UP_TO_Z_UP @ [0.0, 0.0, 1.0], [0.0, -1.0, 0.0])  # front


def test_unknown_up_axis_is_refused(tmp_path):
    with pytest.raises(ValueError, match="up must be"):
        load_segmented_mesh(tmp_path / "x.obj", up="x")


def test_obj_objects_keep_their_groups_inside_one_part(tmp_path):
    """Blender writes `o name` per object and `g` groups (e.g. per material) inside it."""
    path = tmp_path / "blender.obj"
    path.write_text("o lid\ng lid_wood\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\ng lid_metal\nv 1 1 1\nf 2 4 3\n"
                    "o base\ng base_wood\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 5 6 7\n")
    parts, names = load_segmented_mesh(path)
    assert names == {1: "base", 2: "lid"}
    assert len(parts[2].faces) == 2 and len(parts[1].faces) == 1


def test_obj_groups_without_objects_are_parts(tmp_path):
    path = tmp_path / "groups.obj"
    path.write_text("g a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\ng b\nf 1 2 4\nf 1 3 4\n")
    parts, names = load_segmented_mesh(path)
    assert names == {1: "a", 2: "b"} and len(parts[2].faces) == 2


def _triangle_groups(count: int, name) -> str:
    lines = []
    for k in range(count):
        lines += [f"g {name(k)}", f"v {k} 0 0", f"v {k} 1 0", f"v {k} 0 1", f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}"]
    return "\n".join(lines) + "\n"


def test_more_parts_than_palette_colours_is_an_input_error(tmp_path):
    path = tmp_path / "many.obj"
    path.write_text(_triangle_groups(PALETTE_SIZE + 1, lambda k: f"p{k}"))
    with pytest.raises(InputFileError, match=f"{PALETTE_SIZE + 1} parts"):
        load_segmented_mesh(path)


def test_integer_names_beyond_the_palette_are_renumbered(tmp_path):
    path = tmp_path / "big_ids.obj"
    path.write_text(_triangle_groups(3, lambda k: str(500 + k)))
    parts, names = load_segmented_mesh(path)
    assert sorted(parts) == [1, 2, 3] and names == {1: "500", 2: "501", 3: "502"}
