"""ROS package URIs (``package://<pkg>/meshes/...``) resolved within the package that a
``package.xml`` above the URDF names, and never outside it (issue 46)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

from data_pipeline.importers.limits import ImportLimits
from data_pipeline.importers.source import import_object
from jax3dc.errors import InputFileError

ROBOT = """<robot name="cabinet">
  <link name="body"><visual><geometry><mesh filename="package://{pkg}/meshes/{body}"/></geometry></visual></link>
  <link name="door"><visual><geometry><mesh filename="package://{pkg}/meshes/door.obj"/></geometry></visual></link>
  <joint name="hinge" type="revolute"><origin xyz="0.5 -0.55 0"/><axis xyz="0 0 1"/>
    <parent link="body"/><child link="door"/><limit lower="0" upper="1.5"/></joint>
</robot>
"""


def _manifest(folder: Path, name: str) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "package.xml").write_text(f'<?xml version="1.0"?>\n<package format="3"><name> {name} </name>'
                                        "<version>1.0.0</version></package>\n")


def _urdf(package: Path, pkg: str = "cabinet_description", body: str = "body.stl") -> Path:
    (package / "urdf").mkdir(parents=True, exist_ok=True)
    path = package / "urdf" / "cabinet.urdf"
    path.write_text(ROBOT.format(pkg=pkg, body=body))
    return path


@pytest.fixture
def package(tmp_path: Path) -> Path:
    """A ROS workspace: ws/src/cabinet_description/{package.xml, urdf/, meshes/} beside a file outside."""
    root = tmp_path / "ws" / "src" / "cabinet_description"
    _manifest(root, "cabinet_description")
    (root / "meshes").mkdir()
    trimesh.creation.box(extents=(1.0, 1.0, 2.0)).export(root / "meshes" / "body.stl")
    door = trimesh.creation.box(extents=(1.0, 0.05, 2.0))
    door.apply_translation((0.0, -0.55, 0.0))
    door.export(root / "meshes" / "door.obj")
    trimesh.creation.box().export(tmp_path / "outside.obj")
    return root


def test_package_uris_resolve_in_the_package_above_the_urdf(package):
    _manifest(package / "urdf", "not_this_one")  # a nearer package of another name is passed over
    obj = import_object(_urdf(package))
    assert len(obj.parts) == 2
    (joint,) = obj.structure.joints().values()
    assert joint.type == "hinge" and np.allclose(np.abs(joint.axis), (0, 0, 1))
    assert obj.parts[1].extents.max() == pytest.approx(1.0)  # the 2-high body, normalised


def test_unknown_package_names_the_uri_and_where_it_looked(package):
    with pytest.raises(InputFileError) as caught:
        import_object(_urdf(package, pkg="other_robot"))
    message = str(caught.value)
    assert "'package://other_robot/meshes/body.stl'" in message and "not found" in message
    assert str(package / "urdf") in message  # where the search started
    assert str(package / "package.xml") in message and "'cabinet_description'" in message  # what it saw


@pytest.mark.parametrize("body", ["../../../../outside.obj", "link.obj", "/../../outside.obj"])
def test_paths_leaving_the_package_are_refused_even_when_outside_is_allowed(package, body):
    os.symlink(package.parents[2] / "outside.obj", package / "meshes" / "link.obj")
    path = _urdf(package, body=body)
    for limits in (ImportLimits(), ImportLimits(allow_outside=True)):
        with pytest.raises(InputFileError) as caught:
            import_object(path, limits=limits)
        message = str(caught.value)
        assert str(path) in message and f"'package://cabinet_description/meshes/{body}'" in message
        assert "leaves package 'cabinet_description'" in message and "outside.obj" in message


def test_a_dotdot_that_stays_in_the_package_is_fine(package):
    assert len(import_object(_urdf(package, body="../meshes/body.stl")).parts) == 2


@pytest.mark.parametrize("uri", ["package://cabinet_description", "package:///meshes/body.stl"])
def test_malformed_package_uri_is_named(package, uri):
    path = _urdf(package)
    path.write_text(path.read_text().replace("package://cabinet_description/meshes/body.stl", uri))
    with pytest.raises(InputFileError, match="is not package://<package>/<path to a file>") as caught:
        import_object(path)
    assert repr(uri) in str(caught.value)


def test_hostile_package_xml_is_not_parsed_and_is_named(package):
    (package / "package.xml").write_text('<!DOCTYPE p [<!ENTITY x "cabinet_description">]><package><name>&x;</name>'
                                         "</package>")
    with pytest.raises(InputFileError) as caught:
        import_object(_urdf(package))
    assert f"{package / 'package.xml'} is unreadable or has no <name>" in str(caught.value)
