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


def test_blender_refuses_what_run_refuses(tmp_path, capsys):
    """The Blender script is written only for a program that runs within the same budget."""
    cases = {
        "loop.py": "a = box(1)\npart(1, 'a', a)\nfor i in range(9000):\n    for j in range(9000):\n        b = j\n",
        "segments.py": "part(1, 'a', cylinder(0.5, 1, segments=10000))\n",
        "emitted.py": "a = sphere(1, segments=128, rings=64)\nfor i in range(1, 200):\n    part(i, 'c', a)\n",
    }
    for name, text in cases.items():
        src = tmp_path / name
        src.write_text(text)
        script = tmp_path / f"{name}.bpy"
        assert main(["program", "run", str(src)]) == 1
        run_error = capsys.readouterr().err.strip().split(": error: ")[1]
        assert main(["program", "blender", str(src), "-o", str(script)]) == 1
        blender_error = capsys.readouterr().err.strip().split(": error: ")[1]
        assert blender_error == run_error and "\n" not in blender_error
        assert not script.exists()


def test_unwritable_output_is_one_line(tmp_path, capsys):
    src = tmp_path / "p.py"
    src.write_text(PROGRAM)
    missing = tmp_path / "no" / "such" / "s.py"
    assert main(["program", "blender", str(src), "-o", str(missing)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "s.py" in err and "No such file" in err
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["program", "run", str(src), "--out", str(blocker / "parts")]) == 1
    assert "cannot write" in capsys.readouterr().err
