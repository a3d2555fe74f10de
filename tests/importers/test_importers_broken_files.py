"""Broken URDF / MJCF files are refused with an InputFileError naming the file and the problem."""

from __future__ import annotations

from pathlib import Path

import pytest

from data_pipeline.importers.source import import_object
from data_pipeline.importers.urdf import parse_xml
from jax3dc.errors import InputFileError

BOX_LINK = '<link name="{0}"><visual><geometry><box size="1 1 1"/></geometry></visual></link>'


def _write(tmp_path: Path, text: str, name: str = "robot.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _refused(path: Path, *words: str) -> str:
    with pytest.raises(InputFileError) as caught:
        import_object(path)
    message = str(caught.value)
    assert path.name in message
    assert "\n" not in message, message
    for word in words:
        assert word in message, message
    return message


def _robot(*body: str) -> str:
    return '<?xml version="1.0"?>\n<robot name="r">\n' + "\n".join(body) + "\n</robot>\n"


def _joint(name, parent, child, kind="fixed", extra=""):
    return f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{extra}</joint>'


def test_truncated_xml(tmp_path):
    text = _robot(BOX_LINK.format("a"), BOX_LINK.format("b"), _joint("j", "a", "b"))
    path = _write(tmp_path, text[: len(text) // 2])
    _refused(path, "malformed XML", "line")


def test_doctype_with_entities_is_refused_before_expansion(tmp_path):
    laughs = "".join(f'<!ENTITY l{i} "{"&l%d;" % (i - 1) * 10}">' for i in range(1, 10))
    text = f'<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY l0 "lol">{laughs}]>\n<robot name="&l9;"/>'
    _refused(_write(tmp_path, text), "DOCTYPE")


BILLION_LAUGHS = (
    '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY l0 "lol">'
    + "".join(f'<!ENTITY l{i} "{"&l%d;" % (i - 1) * 10}">' for i in range(1, 10))
    + ']>\n<robot name="&l9;"/>'
)
EXTERNAL_ENTITY = '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY e SYSTEM "file:///etc/passwd">]>\n<robot name="&e;"/>'
PARAMETER_ENTITY = '<!DOCTYPE robot [<!ENTITY % p SYSTEM "http://example.invalid/x.dtd"> %p;]>\n<robot/>'
BARE_DTD = '<!DOCTYPE robot SYSTEM "robot.dtd">\n<robot name="r"/>'


@pytest.mark.parametrize("text", [BILLION_LAUGHS, EXTERNAL_ENTITY, PARAMETER_ENTITY, BARE_DTD],
                         ids=["billion_laughs", "external_entity", "parameter_entity", "bare_dtd"])
def test_parse_xml_refuses_hostile_xml_in_one_line(tmp_path, text):
    path = _write(tmp_path, text)
    with pytest.raises(InputFileError) as caught:
        parse_xml(path, "robot")
    message = str(caught.value)
    assert message.startswith(f"{path}: DOCTYPE/ENTITY declarations are not accepted"), message
    assert "\n" not in message and "lol" not in message and "root:" not in message, message


def test_parse_xml_malformed_wrong_root_and_unreadable(tmp_path):
    with pytest.raises(InputFileError, match=r"model\.xml: malformed XML at line 2, column \d+: mismatched tag$"):
        parse_xml(_write(tmp_path, "<mujoco>\n<worldbody></mujoco>", "model.xml"))
    with pytest.raises(InputFileError, match=r"root element is <mujoco>, expected <robot>$"):
        parse_xml(_write(tmp_path, "<mujoco/>", "model.xml"), "robot")
    with pytest.raises(InputFileError, match=r"gone\.urdf: cannot read file"):
        parse_xml(tmp_path / "gone.urdf")
    assert parse_xml(_write(tmp_path, _robot(BOX_LINK.format("a"))), "robot").find("link").get("name") == "a"


def test_missing_mesh_names_the_mesh_and_link(tmp_path):
    text = _robot('<link name="body"><visual><geometry><mesh filename="meshes/gone.obj"/></geometry></visual></link>')
    _refused(_write(tmp_path, text), "gone.obj", "body", "not found")


def test_cycle(tmp_path):
    text = _robot(BOX_LINK.format("root"), BOX_LINK.format("a"), BOX_LINK.format("b"),
                  _joint("j0", "root", "c0"), _joint("j1", "a", "b"), _joint("j2", "b", "a"))
    _refused(_write(tmp_path, text), "link 'c0'", "not defined")
    text = _robot(BOX_LINK.format("root"), BOX_LINK.format("a"), BOX_LINK.format("b"),
                  _joint("j1", "a", "b"), _joint("j2", "b", "a"))
    _refused(_write(tmp_path, text), "cycle")


def test_multiple_parents(tmp_path):
    text = _robot(BOX_LINK.format("a"), BOX_LINK.format("b"), BOX_LINK.format("c"),
                  _joint("j1", "a", "c"), _joint("j2", "b", "c"))
    _refused(_write(tmp_path, text), "several parents", "'c'")


def test_unknown_joint_type_and_missing_limit(tmp_path):
    text = _robot(BOX_LINK.format("a"), BOX_LINK.format("b"), _joint("j1", "a", "b", "screw"))
    _refused(_write(tmp_path, text), "unknown joint type", "'screw'", "j1")
    text = _robot(BOX_LINK.format("a"), BOX_LINK.format("b"), _joint("j1", "a", "b", "revolute"))
    _refused(_write(tmp_path, text), "<limit", "j1")


def test_bad_numbers_and_reversed_limits(tmp_path):
    origin = '<origin xyz="0 zero 0"/>'
    text = _robot(BOX_LINK.format("a"), BOX_LINK.format("b"), _joint("j1", "a", "b", "fixed", origin))
    _refused(_write(tmp_path, text), "j1", "origin xyz")
    limit = '<axis xyz="0 0 1"/><limit lower="1" upper="-1"/>'
    text = _robot(BOX_LINK.format("a"), BOX_LINK.format("b"), _joint("j1", "a", "b", "revolute", limit))
    _refused(_write(tmp_path, text), "lower", "upper")


def test_no_geometry_and_unknown_format(tmp_path):
    _refused(_write(tmp_path, _robot('<link name="a"/>')), "no link has any geometry")
    _refused(_write(tmp_path, "<scene/>", "thing.xml"), "neither a URDF")


def test_mjcf_with_missing_mesh(tmp_path):
    text = """<mujoco><asset><mesh name="m" file="absent.obj"/></asset>
    <worldbody><body name="b"><geom type="mesh" mesh="m"/></body></worldbody></mujoco>"""
    _refused(_write(tmp_path, text, "model.xml"), "absent.obj")


def test_mjcf_doctype_and_malformed(tmp_path):
    text = '<?xml version="1.0"?>\n<!DOCTYPE m [<!ENTITY e SYSTEM "file:///etc/passwd">]>\n<mujoco>&e;</mujoco>'
    _refused(_write(tmp_path, text, "model.xml"), "DOCTYPE")
    _refused(_write(tmp_path, "<mujoco><worldbody><body></worldbody></mujoco>", "model.xml"), "malformed XML", "line 1")
