"""Dirty real inputs import: mesh files that are missing, unreadable, or that MuJoCo refuses are
dropped, one warning each naming the file and the reason; the other parts import as if the bad
pieces were never there; a part left with no geometry is an error naming it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from data_pipeline.importers.meshes import refusal
from data_pipeline.importers.source import import_object
from data_pipeline.shards import load_manifest
from jax3dc.cli import main
from jax3dc.errors import InputFileError
from jax3dc.structure import to_json

TRIANGLE = "v 0 0 0\nv 0.3 0 0\nv 0 0.3 0\nf 1 2 3\n"
FLAT = "v -0.4 -0.4 0.5\nv 0.4 -0.4 0.5\nv 0.4 0.4 0.5\nv -0.4 0.4 0.5\nf 1 2 3\nf 1 3 4\n"
GARBAGE = bytes(range(256)) * 4
# (file, words of its reason) for every bad piece of the dirty body; gone.obj is never written
URDF_BAD = {"tri.obj": "has 3 vertices; MuJoCo needs at least 4 vertices", "gone.obj": "not found",
            "garbage.stl": "has no readable triangles"}
MJCF_BAD = {"tri.obj": "has 3 vertices; MuJoCo needs at least 4 vertices", "gone.obj": "not found",
            "garbage.ply": "cannot read mesh file", "flat.obj": "has zero volume: its vertices all lie in one plane"}


def _meshes(folder: Path) -> None:
    """Good meshes (a body box, a lid slab), a 3-vertex mesh, a flat quad and two garbage files."""
    folder.mkdir(parents=True, exist_ok=True)
    trimesh.creation.box(extents=(1.0, 1.0, 1.0)).export(folder / "body.obj")
    lid = trimesh.creation.box(extents=(1.0, 1.0, 0.05))
    lid.apply_translation((0.0, 0.0, 0.525))
    lid.export(folder / "lid.obj")
    (folder / "tri.obj").write_text(TRIANGLE)
    (folder / "flat.obj").write_text(FLAT)
    (folder / "garbage.stl").write_bytes(GARBAGE)
    (folder / "garbage.ply").write_bytes(GARBAGE)


def _urdf(folder: Path, body: list[str], lid: list[str]) -> Path:
    """Links body and lid (hinged) whose visuals are the given mesh files."""
    def visuals(files: list[str]) -> str:
        return "".join(f'<visual><geometry><mesh filename="{f}"/></geometry></visual>' for f in files)

    path = folder / "robot.urdf"
    path.write_text(f'<robot name="r"><link name="body">{visuals(body)}</link><link name="lid">{visuals(lid)}</link>'
                    '<joint name="hinge" type="revolute"><parent link="body"/><child link="lid"/>'
                    '<axis xyz="1 0 0"/><limit lower="0" upper="1.5"/></joint></robot>')
    return path


def _mjcf(folder: Path, body: list[str], lid: list[str], visual_only: tuple[str, ...] = ()) -> Path:
    """Bodies body and lid (hinged) with one mesh geom per file; files in ``visual_only`` get
    contype = conaffinity = 0."""
    files = sorted(set(body + lid))
    assets = "".join(f'<mesh name="{Path(f).stem}_{Path(f).suffix[1:]}" file="{f}"/>' for f in files)

    def geoms(files: list[str]) -> str:
        return "".join(f'<geom type="mesh" mesh="{Path(f).stem}_{Path(f).suffix[1:]}"'
                       + (' contype="0" conaffinity="0"' if f in visual_only else "") + "/>" for f in files)

    path = folder / "model.xml"
    path.write_text(f'<mujoco><asset>{assets}</asset><worldbody><body name="body">{geoms(body)}'
                    f'<body name="lid"><joint name="hinge" type="hinge" axis="1 0 0" range="0 1.5"/>{geoms(lid)}'
                    "</body></body></worldbody></mujoco>")
    return path


def _assert_same_object(dirty, clean) -> None:
    """Same structure and part meshes: what was dropped left no trace on the rest."""
    assert to_json(dirty.structure) == to_json(clean.structure)
    assert dirty.meta["part_links"] == clean.meta["part_links"] == {"1": "body", "2": "lid"}
    for i, mesh in clean.parts.items():
        np.testing.assert_array_equal(dirty.parts[i].faces, mesh.faces)
        np.testing.assert_allclose(dirty.parts[i].vertices, mesh.vertices, atol=1e-12)


def _assert_warned(warnings: list[str], bad: dict[str, str], ending: str) -> None:
    """One warning per bad file, naming it and its reason; nothing else."""
    assert len(warnings) == len(bad), warnings
    for name, reason in bad.items():
        (line,) = [w for w in warnings if f"/{name} " in w or f"/{name}:" in w]
        assert reason in line and line.endswith(ending), line


def test_urdf_drops_bad_pieces_and_names_each(tmp_path):
    good = ["body.obj", "flat.obj"]  # a flat piece is kept: the link's pieces are merged into one part
    _meshes(tmp_path / "dirty")
    dirty = import_object(_urdf(tmp_path / "dirty", ["body.obj", "tri.obj", "gone.obj", "flat.obj", "garbage.stl"],
                                ["lid.obj"]))
    _meshes(tmp_path / "clean")
    clean = import_object(_urdf(tmp_path / "clean", good, ["lid.obj"]))
    assert clean.meta["warnings"] == []
    _assert_same_object(dirty, clean)
    assert len(dirty.parts[1].vertices) == 8 + 4  # the body box and the flat quad
    _assert_warned(dirty.meta["warnings"], URDF_BAD, "; that piece is dropped")
    assert all(w.startswith("link 'body' <visual> #") for w in dirty.meta["warnings"])


def test_mjcf_drops_bad_meshes_and_names_each(tmp_path):
    _meshes(tmp_path / "dirty")
    dirty = import_object(_mjcf(tmp_path / "dirty", ["body.obj", "tri.obj", "gone.obj", "flat.obj", "garbage.ply"],
                                ["lid.obj"]))
    _meshes(tmp_path / "clean")
    clean = import_object(_mjcf(tmp_path / "clean", ["body.obj"], ["lid.obj"]))
    assert clean.meta["warnings"] == []
    _assert_same_object(dirty, clean)
    _assert_warned(dirty.meta["warnings"], MJCF_BAD, "; it and the geoms using it are dropped (in body 'body')")


def test_mjcf_keeps_a_flat_mesh_that_collides_with_nothing(tmp_path):
    """MuJoCo needs a convex hull only for a colliding geom; a flat render mesh compiles."""
    _meshes(tmp_path)
    obj = import_object(_mjcf(tmp_path, ["body.obj", "flat.obj"], ["lid.obj"], visual_only=("body.obj", "flat.obj")))
    assert obj.meta["warnings"] == []
    assert len(obj.parts[1].vertices) == 8 + 4


@pytest.mark.parametrize("fmt", ["urdf", "mjcf"])
def test_a_part_whose_every_piece_is_bad_is_an_error_naming_it(tmp_path, fmt):
    _meshes(tmp_path)
    write, kind = (_urdf, "link") if fmt == "urdf" else (_mjcf, "body")
    path = write(tmp_path, ["body.obj"], ["tri.obj", "gone.obj", "garbage.ply"])
    with pytest.raises(InputFileError) as caught:
        import_object(path)
    message = str(caught.value)
    assert f"{kind} 'lid' has no geometry left" in message and "\n" not in message, message
    for name in ("tri.obj", "gone.obj", "garbage.ply"):
        assert name in message, message
    assert "'body'" not in message, message  # the body keeps its box: only the lid is named


def test_mesh_refusals():
    """The rules MuJoCo applies, with round-off of a flat file not mistaken for thickness."""
    box = np.asarray(trimesh.creation.box().vertices)
    assert refusal(box, colliding=True) is None
    assert "3 vertices" in refusal(box[:3], colliding=False)
    duplicated = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0]], float)
    assert "3 distinct vertices" in refusal(duplicated, colliding=False)
    line = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
    assert "one line" in refusal(line, colliding=False)
    flat = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 1e-14], [0, 1, 0]], float)
    assert refusal(flat, colliding=False) is None
    assert "one plane" in refusal(flat, colliding=True)
    thin = flat.copy()
    thin[2, 2] = 1e-6  # a millionth of its size out of the plane: a solid, if a thin one
    assert refusal(thin, colliding=True) is None


def test_convert_cli_prints_each_warning_once(tmp_path, capsys):
    _meshes(tmp_path / "obj")
    path = _urdf(tmp_path / "obj", ["body.obj", "tri.obj", "gone.obj", "garbage.stl"], ["lid.obj"])
    assert main(["data", "convert", str(path), "--out", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    warnings = [line for line in err.splitlines() if line.startswith("warning: ")]
    assert len(warnings) == len(URDF_BAD), err
    for name in URDF_BAD:
        assert sum(name in line for line in warnings) == 1, err


def test_data_import_of_a_dirty_object_renders(tmp_path, capsys):
    """`jax3dc data import` keeps the object (its bad pieces dropped) instead of skipping it, and
    names each dropped file once on stderr."""
    _meshes(tmp_path / "obj")
    _urdf(tmp_path / "obj", ["body.obj", "tri.obj", "gone.obj", "garbage.stl"], ["lid.obj"])
    out = tmp_path / "out"
    code = main(["data", "import", str(tmp_path / "obj"), "--out", str(out), "--views", "1", "--size", "32",
                 "--split", "train", "--quiet"])
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err, err
    manifest = load_manifest(out)
    assert manifest["skipped"] == {} and manifest["shards"]["train-00000.array_record"]["records"] == 1
    for name in ("tri.obj", "gone.obj", "garbage.stl"):
        assert sum(name in line for line in err.splitlines() if line.startswith("warning:")) == 1, (name, err)
