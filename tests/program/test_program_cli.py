"""`jax3dc program`: run writes one mesh per part, errors are one line naming the line, exit 1."""

import json

import trimesh

from jax3dc.cli import main

PROGRAM = 'wood = material("Wood", "oak")\npart(1, "seat", box((1, 1, 0.1)), material=wood)\n' \
          'part(2, "leg", cylinder(0.05, 1, center=(0, 0, -0.55)))\n'


def test_run_writes_part_meshes(tmp_path, capsys):
    src = tmp_path / "p.py"
    src.write_text(PROGRAM)
    out = tmp_path / "parts"
    assert main(["program", "run", str(src), "--out", str(out)]) == 0
    assert "seat" in capsys.readouterr().out
    seat = trimesh.load(out / "1.obj", force="mesh")
    assert abs(seat.volume - 0.1) < 1e-9
    meta = json.loads((out / "parts.json").read_text())
    assert meta["1"] == {"name": "seat", "material": {"family": "Wood", "desc": "oak"}}
    assert meta["2"]["material"] is None


def test_bad_program_is_one_line_error(tmp_path, capsys):
    src = tmp_path / "bad.py"
    src.write_text(PROGRAM + "import os\n")
    assert main(["program", "run", str(src)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "line 4" in err and "import" in err


def test_missing_file_and_blender_output(tmp_path, capsys):
    assert main(["program", "run", str(tmp_path / "nope.py")]) == 1
    assert "nope.py" in capsys.readouterr().err
    src = tmp_path / "p.py"
    src.write_text(PROGRAM)
    script = tmp_path / "s.py"
    assert main(["program", "blender", str(src), "-o", str(script)]) == 0
    compile(script.read_text(), str(script), "exec")
    assert main(["program", "reference"]) == 0
    assert "lathe(" in capsys.readouterr().out
