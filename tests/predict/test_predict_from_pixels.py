"""`jax3dc predict IMAGE --out DIR` with nothing else (issue 49): the shipped stage-1 network reads
a bare procedural image (no --stage1, no camera, no parts), the shipped structure model writes the
structure, and every output a user needs is there: a valid structure over stage 1's parts, exports
that load in MuJoCo, and a physics verdict."""

from __future__ import annotations

import json

import mujoco

from jax3dc.cli import main
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import load_parts
from jax3dc.parameters import parse_parameters
from jax3dc.structure import parse_structure
from predict_cases import write_image


# 14 s on 2 shared cores (41 s with a benchmark beside it): both shipped models load and compile
def test_a_bare_image_gives_a_structure_exports_and_a_verdict(tmp_path, capsys):
    image = write_image(tmp_path / "cabinet.png")  # a factory object's render, nothing about it given
    out = tmp_path / "out"
    assert main(["predict", str(image), "--out", str(out)]) == 0
    parts = load_parts(out / "parts")
    obj = run_parameters(parse_parameters((out / "parameters.txt").read_text(), SCHEMAS))
    assert sorted(parts) == sorted(obj.parts)  # stage 1 is the factory run on the network's text
    structure = parse_structure((out / "structure.json").read_text(), part_ids=parts)  # raises if invalid
    for export in ("object.xml", "object.urdf"):
        model = mujoco.MjModel.from_xml_path(str(out / export))
        assert model.nbody >= len(parts) and model.njnt >= len(structure.joints()), export
    for name in ("object.usda", "object.glb", "object_blender.py", "seg.png", "viewer.html", "report.html"):
        assert (out / name).is_file(), name
    verdict = json.loads((out / "physics.json").read_text())
    assert isinstance(verdict["ok"], bool)
    printed = capsys.readouterr().out
    assert f"{len(parts)} parts, {len(structure.joints())} joints" in printed
    assert ("passes" if verdict["ok"] else "fails") in printed
