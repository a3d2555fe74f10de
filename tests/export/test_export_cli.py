"""`jax3dc export`: files from a structure JSON and a parts folder; one-line errors; same bytes in
separate processes; and (when a Blender Python is given) the Blender script run in Blender."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from export_cases import CASES
from jax3dc.cli import main
from jax3dc.geometry.parts import save_parts
from jax3dc.structure import to_json
from tests.blender_env import blender_python

REPO = Path(__file__).resolve().parents[2]


def _object_dir(tmp_path: Path, case: str = "cabinet", meta_scale: float | None = None) -> Path:
    structure, parts = CASES[case]()
    folder = tmp_path / case
    save_parts(parts, folder / "parts")
    (folder / "structure.json").write_text(to_json(structure, names=True))
    if meta_scale is not None:
        (folder / "meta.json").write_text(json.dumps({"scale": meta_scale}))
    return folder


@pytest.mark.parametrize("fmt, main_file", [("urdf", "structure.urdf"), ("mjcf", "structure.xml"),
                                            ("gltf", "structure.glb"), ("blender", "structure_blender.py")])
def test_each_format_writes_its_files(tmp_path, capsys, fmt, main_file):
    folder = _object_dir(tmp_path)
    rc = main(["export", str(folder / "structure.json"), "--parts", str(folder / "parts"), "--format", fmt,
               "--out", str(tmp_path / "out"), "--scale", "0.5"])
    assert rc == 0
    assert (tmp_path / "out" / main_file).is_file()
    assert "6 parts, 3 joints, 0.5 m per nu" in capsys.readouterr().out


def test_scale_comes_from_meta_json_beside_the_structure(tmp_path):
    folder = _object_dir(tmp_path, "chain", meta_scale=2.5)
    assert main(["export", str(folder / "structure.json"), "--parts", str(folder / "parts"), "--format", "mjcf",
                 "--out", str(tmp_path / "out")]) == 0
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "structure.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    structure, _ = CASES["chain"]()
    j = model.joint("joint_3").id
    np.testing.assert_allclose(data.xanchor[j], np.asarray(structure.nodes[3].joint.pivot) * 2.5, atol=1e-5)


@pytest.mark.parametrize("fmt, capped", [("urdf", True), ("usd", True), ("mjcf", True), ("gltf", False)])
def test_max_faces_caps_the_formats_with_convex_pieces(tmp_path, capsys, fmt, capped):
    """The cabinet has 5 boxes of 12 triangles and a 2-triangle sticker: 62 in all."""
    folder = _object_dir(tmp_path)
    rc = main(["export", str(folder / "structure.json"), "--parts", str(folder / "parts"), "--format", fmt,
               "--out", str(tmp_path / "out"), "--max-faces", "61"])
    err = capsys.readouterr().err
    if capped:
        assert rc == 1 and f"the {fmt.upper()} export (its convex collision pieces) takes at most 61" in err
        assert not (tmp_path / "out").exists()
    else:
        assert rc == 0 and err == ""


@pytest.mark.parametrize("change, message", [
    (lambda f: (f / "parts" / "5.obj").unlink(), "part_ids"),
    (lambda f: (f / "structure.json").write_text("{nodes"), "invalid JSON"),
    (lambda f: (f / "structure.json").unlink(), "cannot read the structure"),
    (lambda f: (f / "meta.json").write_text('{"scale": -1}'), "positive number"),
    (lambda f: [p.unlink() for p in (f / "parts").iterdir()], "no part meshes"),
])
def test_bad_input_is_one_line_and_exit_1(tmp_path, capsys, change, message):
    folder = _object_dir(tmp_path)
    change(folder)
    rc = main(["export", str(folder / "structure.json"), "--parts", str(folder / "parts"), "--format", "urdf",
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 1 and message in err and len(err.strip().splitlines()) == 1


def _export_all(folder: Path, out: Path, seed: str) -> None:
    code = ("import sys; from jax3dc.cli import main\n"
            "for fmt in ('urdf', 'mjcf', 'gltf', 'blender', 'usd'):\n"
            "    assert main(['export', sys.argv[1], '--parts', sys.argv[2], '--format', fmt, '--out', sys.argv[3],"
            " '--scale', '0.9']) == 0\n")
    env = dict(os.environ, PYTHONHASHSEED=seed, PYTHONPATH=str(REPO))
    subprocess.run([sys.executable, "-c", code, str(folder / "structure.json"), str(folder / "parts"), str(out)],
                   check=True, env=env, cwd=REPO, capture_output=True)


def test_separate_processes_write_identical_bytes(tmp_path):
    folder = _object_dir(tmp_path, "two_roots")
    _export_all(folder, tmp_path / "a", "1")
    _export_all(folder, tmp_path / "b", "2")
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    # five main files, one mesh per part and the URDF's collision hull of each part (a box: one piece)
    assert len(files) == 5 + 5 + 5 and sum("_collision_" in p.name for p in files) == 5
    for rel in files:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes(), rel


_BLENDER_CHECK = """
import json, sys
import bpy
exec(compile(open(sys.argv[1]).read(), sys.argv[1], "exec"))
bpy.context.view_layer.update()
worst = 0.0
for label, expected in json.load(open(sys.argv[2])).items():
    obj = bpy.data.objects[label + "_mesh"]
    got = [obj.matrix_world @ v.co for v in obj.data.vertices]
    worst = max([worst] + [abs(a - b) for g, e in zip(got, expected) for a, b in zip(g, e)])
door = bpy.data.objects["part_3_right_door"]
door.rotation_euler = (0.4, 0.0, 3.0)  # a locked axis and past the upper limit
bpy.context.view_layer.update()
local = door.parent.matrix_world.inverted() @ door.matrix_world
print(json.dumps({"worst": worst, "euler": list(local.to_euler()), "constraints": [c.type for c in door.constraints]}))
"""


def test_blender_script_runs_in_blender(tmp_path):
    """Real Blender: every part lands where its mesh says, and a joint is held inside its range."""
    from jax3dc.export.assembly import label_of
    from jax3dc.export.blender import export_blender

    structure, parts = CASES["cabinet"]()
    script = export_blender(structure, parts, tmp_path, 1.7)
    expected = {label_of(i, n.name): (np.asarray(parts[i].vertices) * 1.7).tolist() for i, n in structure.nodes.items()}
    (tmp_path / "expected.json").write_text(json.dumps(expected))
    (tmp_path / "check.py").write_text(_BLENDER_CHECK)
    run = subprocess.run([blender_python(), str(tmp_path / "check.py"), str(script),
                          str(tmp_path / "expected.json")], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    assert result["worst"] < 1e-5
    assert result["constraints"] == ["LIMIT_ROTATION", "LIMIT_LOCATION"]
    np.testing.assert_allclose(result["euler"], [0.0, 0.0, 1.571], atol=1e-4)
