"""``bounds_only`` imports read each OBJ's vertex and face lines without building a mesh: the box is
that of the vertices the faces use, and files a full load drops are dropped alike."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from data_pipeline.importers import meshes
from data_pipeline.importers.limits import FaceBudget, ImportLimits

CUBE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 9 9 9\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def _bounds(tmp_path: Path, text: str) -> np.ndarray:
    path = tmp_path / "m.obj"
    path.write_text(text)
    return meshes.load_mesh_bounds(path, tmp_path / "x.urdf", "link", FaceBudget(ImportLimits())).bounds


def test_box_of_the_vertices_that_faces_use(tmp_path):
    np.testing.assert_array_equal(_bounds(tmp_path, CUBE), [[0, 0, 0], [1, 1, 1]])  # v 9 9 9 is unused
    slashed = CUBE.replace("f 1 3 2", "f 1/1/1 3/2/1 2//1").replace("f 2 3 4", "f\t2 3 4")
    np.testing.assert_array_equal(_bounds(tmp_path, slashed), [[0, 0, 0], [1, 1, 1]])
    relative = CUBE.replace("f 1 3 2", "f -5 -3 -4")  # relative indices: every vertex counts
    np.testing.assert_array_equal(_bounds(tmp_path, relative), [[0, 0, 0], [9, 9, 9]])


def test_matches_a_full_load_of_a_real_mesh(tmp_path):
    path = tmp_path / "m.obj"
    trimesh.creation.annulus(0.2, 0.5, 0.3).export(path)
    full = meshes.load_mesh_file(path, path, "", FaceBudget(ImportLimits())).bounds
    np.testing.assert_allclose(_bounds(tmp_path, path.read_text()), full, atol=1e-12)


@pytest.mark.parametrize("text, reason", [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n", "no readable triangles"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "at least 4 vertices"),
    (CUBE.replace("f 2 3 4", "f 2 3 7"), "naming vertex 7 of 5"),
    (CUBE.replace("v 0 0 1", "v 0 zero 1"), "not three numbers"),
])
def test_files_a_full_load_would_drop_are_dropped(tmp_path, text, reason):
    with pytest.raises(meshes.UnusableMesh, match=reason):
        _bounds(tmp_path, text)
