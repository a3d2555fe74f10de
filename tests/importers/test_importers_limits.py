"""Caps on imported data and mesh paths kept inside the object's folder (issue: hostile inputs)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import trimesh

from data_pipeline.importers.limits import ImportLimits
from data_pipeline.importers.source import import_object
from jax3dc.errors import InputFileError


def _urdf(folder: Path, *filenames: str) -> Path:
    visuals = "".join(f'<visual><geometry><mesh filename="{f}"/></geometry></visual>' for f in filenames)
    path = folder / "robot.urdf"
    path.write_text(f'<robot name="r"><link name="a">{visuals}</link></robot>')
    return path


@pytest.fixture
def layout(tmp_path: Path) -> Path:
    """tmp/outside.obj beside tmp/obj/ (the object), with tmp/obj/m/ok.obj inside it."""
    trimesh.creation.box().export(tmp_path / "outside.obj")
    (tmp_path / "obj" / "m").mkdir(parents=True)
    trimesh.creation.box().export(tmp_path / "obj" / "m" / "ok.obj")
    return tmp_path / "obj"


@pytest.mark.parametrize("name", ["../outside.obj", "ABS", "m/link.obj"])  # package:// URIs: test_importers_ros_package
def test_mesh_outside_the_folder_is_refused_unless_allowed(layout, name):
    os.symlink(layout.parent / "outside.obj", layout / "m" / "link.obj")
    name = str(layout.parent / "outside.obj") if name == "ABS" else name
    path = _urdf(layout, name)
    with pytest.raises(InputFileError) as caught:
        import_object(path)
    message = str(caught.value)
    assert "outside the object's folder" in message and "--allow-outside" in message and "outside.obj" in message
    assert len(import_object(path, limits=ImportLimits(allow_outside=True)).parts) == 1


def test_empty_mesh_file_is_skipped_and_named(layout):
    (layout / "m" / "empty.obj").write_bytes(b"")
    obj = import_object(_urdf(layout, "m/ok.obj", "m/empty.obj"))
    assert len(obj.parts) == 1
    assert any("empty.obj" in w and "0 bytes" in w for w in obj.meta["warnings"]), obj.meta["warnings"]


def test_mjcf_empty_mesh_is_skipped_and_named(layout):
    (layout / "m" / "empty.obj").write_bytes(b"")
    path = layout / "model.xml"
    path.write_text('<mujoco><asset><mesh name="e" file="m/empty.obj"/><mesh name="k" file="m/ok.obj"/></asset>'
                    '<worldbody><body name="b"><geom type="mesh" mesh="e"/><geom type="mesh" mesh="k"/></body>'
                    '</worldbody></mujoco>')
    obj = import_object(path)
    assert len(obj.parts) == 1 and any("empty.obj" in w for w in obj.meta["warnings"])


def test_face_cap_counts_before_loading(layout):
    # faces on 4 vertices, not 3: a mesh of 3 would be dropped as one MuJoCo refuses
    (layout / "many.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n" + "f 1 2 3\nf 1 2 4\n" * 2500)
    path = _urdf(layout, "many.obj")
    with pytest.raises(InputFileError, match="5000 faces; the cap is 4000 \\(raise it with --max-faces\\)"):
        import_object(path, limits=ImportLimits(max_faces=4000))
    assert import_object(path, limits=ImportLimits(max_faces=6000)).parts


def test_replicate_is_counted_before_mujoco_expands_it(tmp_path):
    path = tmp_path / "model.xml"
    nested = '<replicate count="1000">' * 3 + '<body><geom size="1"/></body>' + "</replicate>" * 3
    path.write_text(f"<mujoco><worldbody>{nested}</worldbody></mujoco>")
    with pytest.raises(InputFileError, match="--max-bodies"):
        import_object(path)


def test_huge_height_field_is_refused_before_mujoco_allocates_it(tmp_path):
    path = tmp_path / "model.xml"
    path.write_text('<mujoco><asset><hfield name="h" nrow="100000" ncol="100000" size="1 1 1 1"/></asset>'
                    '<worldbody><geom type="hfield" hfield="h"/><body><geom size="1"/></body></worldbody></mujoco>')
    with pytest.raises(InputFileError, match="10000000000 samples.*--max-faces"):
        import_object(path)
