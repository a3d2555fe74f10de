"""The exported Blender script, run in real Blender, builds the same parts as the interpreter.

Needs a Python with the `bpy` module (it requires numpy < 2, so it lives in its own virtual
environment that .ci/run creates and names in JAX3DC_BLENDER_PYTHON (see tests/blender_env.py).
"""

import json
import subprocess

import numpy as np
import pytest

from jax3dc.factories import FACTORIES, generate_object
from jax3dc.program import run_program, to_blender_script

from test_program_primitives import CASES
from tests.blender_env import blender_python


REPORT = '''
import json
report = {}
for obj in bpy.data.objects:
    if "part_id" in obj:
        bm = bmesh.new()
        bm.from_mesh(obj.data)
        co = [v.co for v in bm.verts]
        report[int(obj["part_id"])] = {
            "name": obj["part_name"], "volume": bm.calc_volume(signed=True),
            "lo": [min(c[i] for c in co) for i in range(3)], "hi": [max(c[i] for c in co) for i in range(3)],
            "materials": [m.get("family") for m in obj.data.materials]}
print("PARTS" + json.dumps(report))
'''


def run_in_blender(text, tmp_path):
    script = tmp_path / "build.py"
    script.write_text(to_blender_script(text) + REPORT)
    out = subprocess.run([blender_python(), str(script)], capture_output=True, text=True, timeout=600)
    lines = [line for line in out.stdout.splitlines() if line.startswith("PARTS")]
    assert out.returncode == 0 and lines, out.stderr[-3000:]
    return {int(k): v for k, v in json.loads(lines[-1][5:]).items()}


def test_every_primitive_matches(tmp_path):
    text = "".join(f"part({i + 1}, 'case', {expr})\n" for i, (expr, _, _) in enumerate(CASES))
    ours = run_program(text).parts
    blender = run_in_blender(text, tmp_path)
    assert sorted(blender) == sorted(ours)
    for pid, (expr, _, _) in zip(sorted(ours), CASES):
        assert blender[pid]["volume"] == pytest.approx(ours[pid].volume, rel=1e-5), expr
        if "torus" not in expr:  # Blender starts the torus' tube circle at another angle
            assert np.allclose(blender[pid]["lo"], ours[pid].bounds[0], atol=1e-5), expr
            assert np.allclose(blender[pid]["hi"], ours[pid].bounds[1], atol=1e-5), expr


def test_every_factory_object_matches(tmp_path):
    for category in sorted(FACTORIES):
        obj = generate_object(category, 0)
        blender = run_in_blender(obj.program_text, tmp_path)
        assert {pid: p["name"] for pid, p in blender.items()} == obj.names, category
        for pid, mesh in obj.parts.items():
            assert blender[pid]["volume"] == pytest.approx(mesh.volume, rel=1e-3, abs=1e-7), (category, pid)
            assert blender[pid]["materials"] == [obj.structure.materials[obj.structure.nodes[pid].material].family]
