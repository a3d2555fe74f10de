"""Objects composed from real part meshes (data_pipeline/compose.py), on a small library of boxes
written in the URDFormer layout and conventions, and on the real one where it is present."""

import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

from data_pipeline.compose import PartLibrary, composed_source
from data_pipeline.samples import object_records
from data_pipeline.shards import read_dataset
from data_pipeline.views import joint_transform
from jax3dc.structure import to_dict, to_json, validate

REAL_PARTS = Path(__file__).resolve().parents[3] / "shared" / "real_parts"
SEEDS = range(40)  # every layout, side doors, flaps, lids, drawers, fused and separate grips


def _write(path: Path, boxes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    trimesh.util.concatenate([trimesh.creation.box(bounds=np.array(b, dtype=float)) for b in boxes]).export(path)


def _library(root: Path) -> Path:
    """Two meshes of each kind, front +X, up +Z, at the sizes the real library has."""
    uv, t = root / "partnet_uv", 0.03
    for name in ("1", "2"):
        _write(uv / "cabinet_frames" / f"{name}.obj", [  # boards around the unit-square opening at x = 0
            ((-1.2, -t, -t), (0, 0, 1 + t)), ((-1.2, 1, -t), (0, 1 + t, 1 + t)), ((-1.2, 0, -t), (0, 1, 0)),
            ((-1.2, 0, 1), (0, 1, 1 + t)), ((-1.2, 0, 0), (-1.2 + t, 1, 1))])
        _write(uv / "doorLs" / f"{name}.obj", [((-0.01, 0, 0), (0, 0.247, 0.247))])
        _write(uv / "doorRs" / f"{name}.obj", [((-0.01, -0.247, 0), (0, 0, 0.247))])
        _write(uv / "drawers" / f"{name}.obj", [((-0.02, 0, 0), (0, 0.248, 0.248)),
                                                ((-0.59, 0.01, 0), (-0.02, 0.238, 0.01))])
        _write(uv / "handles" / f"{name}.obj", [((0, -0.005, -0.06), (0.04, 0.005, 0.06))])
        _write(uv / "knobs" / f"{name}.obj", [((0, -0.01, -0.01), (0.03, 0.01, 0.01))])
    return root


@pytest.fixture(scope="module")
def library(tmp_path_factory) -> PartLibrary:
    return PartLibrary.open(_library(tmp_path_factory.mktemp("parts")))


@pytest.fixture(scope="module")
def objects(library):
    return {seed: composed_source(seed, library) for seed in SEEDS}


def _bounds(parts):
    bounds = np.array([m.bounds for m in parts.values()])
    return bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)


def test_library_opens_either_folder_and_turns_meshes_into_the_project_frame(tmp_path, library):
    assert PartLibrary.open(library.root).files == library.files
    door = library.mesh(library.files["doorLs"][0])  # hinge (URDF y = 0) at the smallest x, front at y = 0
    np.testing.assert_allclose(door.bounds, [[0, 0, 0], [0.247, 0.01, 0.247]], atol=1e-9)
    handle = library.mesh(library.files["handles"][0])  # stands off toward -Y
    np.testing.assert_allclose(handle.bounds[:, 1], [-0.04, 0], atol=1e-9)
    with pytest.raises(FileNotFoundError, match="knobs"):
        PartLibrary.open(tmp_path)


def test_the_same_seed_gives_the_same_object(library, objects):
    again = composed_source(3, library)
    assert again.category == objects[3].category and again.object_id == objects[3].object_id
    assert to_json(again.structure) == to_json(objects[3].structure)
    for pid, mesh in objects[3].parts.items():
        np.testing.assert_array_equal(again.parts[pid].vertices, mesh.vertices)
    assert to_json(objects[4].structure) != to_json(objects[3].structure)
    assert composed_source(3, library.root, object_id="x").object_id == "x"


def test_objects_validate_with_a_mesh_per_part_normalised_like_the_factories(objects):
    assert {o.category for o in objects.values()} == {"composed_cabinet", "composed_appliance", "composed_chest"}
    for obj in objects.values():
        ids = sorted(obj.structure.nodes)
        assert ids == list(range(1, len(ids) + 1)) == sorted(obj.parts)
        assert validate(to_dict(obj.structure), part_ids=obj.parts) == []
        assert all(len(m.faces) > 0 for m in obj.parts.values())
        assert obj.structure.joints() and obj.program is None and obj.parameters is None
        lo, hi = _bounds(obj.parts)
        assert abs(float(np.max(hi - lo)) - 1.0) < 1e-6
        np.testing.assert_allclose((lo + hi) / 2, 0.0, atol=1e-6)
        assert 0.25 <= obj.scale_m_per_nu <= 2.5
        names = {n.name for n in obj.structure.nodes.values()}
        assert names <= {"body", "door", "drawer", "lid", "handle", "knob"} and obj.structure.nodes[1].name == "body"


def _grip_points(obj, pid: int) -> tuple[np.ndarray, bool]:
    """The vertices of a front's handle or knob: its child part, or the fused vertices standing in
    front of the panel (the panel's front: the smallest y of its vertices on its outermost x)."""
    children = obj.structure.children(pid)
    if children:
        return np.vstack([obj.parts[c].vertices for c in children]), False
    v = np.asarray(obj.parts[pid].vertices)
    lo, hi = v.min(axis=0), v.max(axis=0)
    on_edge = np.isclose(v[:, 0], lo[0]) | np.isclose(v[:, 0], hi[0])
    return v[v[:, 1] < v[on_edge, 1].min() - 1e-9], True


def test_doors_hinge_on_the_edge_away_from_their_handle_and_open_outward(objects):
    seen = {"side": 0, "flap": 0, "fused": 0, "separate": 0}
    for obj in objects.values():
        body_front = obj.parts[1].bounds[0][1]
        for pid, node in obj.structure.nodes.items():
            if node.name != "door":
                continue
            j = node.joint
            grip, fused = _grip_points(obj, pid)
            seen["fused" if fused else "separate"] += 1
            panel = np.asarray(obj.parts[pid].vertices)
            lo, hi = panel.min(axis=0), panel.max(axis=0)
            assert hi[1] <= body_front + 1e-9  # in front of the body, not inside it
            assert len(grip) and j.type == "hinge" and j.range[0] == 0.0 and j.range[1] > 0.5
            assert abs(j.pivot[1] - hi[1]) < 1e-6  # on the door's back face: the body's front plane
            c = 2 if abs(j.axis[0]) > 0.99 else 0  # a flap's hinge runs along x, its free edge is up or down
            seen["flap" if c == 2 else "side"] += 1
            handle_high = grip[:, c].mean() > (lo[c] + hi[c]) / 2
            hinge_edge = lo[c] if handle_high else hi[c]
            assert abs(j.pivot[c] - hinge_edge) < 1e-6
            free = panel[np.isclose(panel[:, c], hi[c] if handle_high else lo[c])]
            moved = (joint_transform(j, 0.3) @ np.c_[free, np.ones(len(free))].T).T[:, :3]
            assert np.all(moved[:, 1] < free[:, 1] - 0.05 * (hi[c] - lo[c]))
    assert all(seen.values()), seen


def test_lids_open_upward_and_drawers_slide_out_to_the_front(objects):
    lids = drawers = 0
    for obj in objects.values():
        for pid, node in obj.structure.nodes.items():
            v = np.asarray(obj.parts[pid].vertices)
            if node.name == "lid":
                lids += 1
                front = v[np.isclose(v[:, 1], v[:, 1].min())]
                moved = (joint_transform(node.joint, 0.3) @ np.c_[front, np.ones(len(front))].T).T
                assert np.all(moved[:, 2] > front[:, 2] + 0.05)
                assert v[:, 2].min() >= obj.parts[1].bounds[1][2] - 1e-9  # on top of the body
            elif node.name == "drawer":
                drawers += 1
                j = node.joint
                assert j.type == "slide" and j.axis == (0.0, -1.0, 0.0) and 0 < j.range[1] < np.ptp(v[:, 1])
                centre = (v.min(axis=0) + v.max(axis=0)) / 2  # in y the grip (fused or not) is no part of it
                np.testing.assert_allclose(np.asarray(j.pivot)[[0, 2]], centre[[0, 2]], atol=1e-9)
                assert v[:, 1].min() < j.pivot[1] < v[:, 1].max()
                assert v[:, 1].min() < obj.parts[1].bounds[0][1]  # its front stands before the body
    assert lids and drawers


def test_a_broken_library_file_is_skipped_with_a_warning_that_names_it(tmp_path):
    root = _library(tmp_path)
    (root / "partnet_uv" / "handles" / "bad.obj").write_text("not a mesh \x00 at all\n")
    (root / "partnet_uv" / "doorLs" / "0.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")  # no faces
    library = PartLibrary.open(root)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        made = [composed_source(seed, library) for seed in range(12)]
    shown = [str(w.message) for w in caught]
    for name in ("bad.obj", "0.obj"):
        assert any(name in text for text in shown), shown
        assert any(name in text for obj in made for text in obj.warnings)
    for obj in made:
        assert validate(to_dict(obj.structure), part_ids=obj.parts) == []


@pytest.mark.skipif(not (REAL_PARTS / "partnet_uv").is_dir(), reason="../shared/real_parts is not here")
def test_objects_from_the_real_library_validate_and_render():
    library = PartLibrary.open(REAL_PARTS)
    made = [composed_source(seed, library) for seed in range(5)]
    for obj in made:
        assert validate(to_dict(obj.structure), part_ids=obj.parts) == []
        assert sum(len(m.faces) for m in obj.parts.values()) <= 60_000
    records = object_records(made[0], views=2, seed=0, size=64)
    assert len(records) == 2 and all(r.image_png for r in records)


def test_data_build_composes_objects_from_a_part_library(tmp_path, capsys):
    """`data build --composed N --parts DIR` renders N composed objects with the factories' records;
    without --parts, or with a folder that is no library, it stops with a line that says so."""
    from jax3dc.cli import main

    root = _library(tmp_path / "lib")
    out = tmp_path / "data"
    assert main(["data", "build", "--out", str(out), "--objects", "1", "--composed", "3", "--parts", str(root),
                 "--views", "1", "--size", "32", "--quiet"]) == 0
    records = list(read_dataset(out))
    assert sum(r.meta["category"].startswith("composed_") for r in records) == 3 and len(records) == 4
    with pytest.raises(SystemExit, match="--composed needs --parts"):
        main(["data", "build", "--out", str(tmp_path / "x"), "--objects", "0", "--composed", "1", "--quiet"])
    assert main(["data", "build", "--out", str(tmp_path / "y"), "--objects", "0", "--composed", "1",
                 "--parts", str(tmp_path), "--quiet"]) == 1
    assert "no .obj files" in capsys.readouterr().err


def test_a_frame_whose_opening_no_ray_hits_composes_with_trimeshs_own_ray_engine(tmp_path, monkeypatch):
    """Without embree, trimesh answers rays with its rtree engine, which gives a 1-D empty array when
    nothing is hit (every ray through an open-backed frame): composing must not depend on the engine."""
    from data_pipeline import compose

    monkeypatch.setattr(trimesh.ray, "has_embree", False)  # meshes made from here on use the rtree engine
    t = 0.03
    path = tmp_path / "open.obj"
    _write(path, [((-1.2, -t, -t), (0, 0, 1 + t)), ((-1.2, 1, -t), (0, 1 + t, 1 + t)),
                  ((-1.2, 0, -t), (0, 1, 0)), ((-1.2, 0, 1), (0, 1, 1 + t))])  # four boards, no back
    assert compose._frame_front(str(path)) == pytest.approx(0.0, abs=1e-9)
