"""Blender script export: valid Python, one jx_part per part call, strings escaped, no injection."""

import ast

import pytest

from jax3dc.errors import ProgramError
from jax3dc.program import FUNCTIONS, to_blender_script

EVERY_FUNCTION = '''
wood = material("Wood", "oak")
a = box((1, 1, 1))
b = cube(0.5)
c = cylinder(0.1, 1, center=(0, 0, 1), axis="x", segments=12)
d = cone(0.2, 0.05, 0.5)
e = sphere(0.3)
f = torus(0.5, 0.1, axis="y")
g = extrude([(0, 0), (1, 0), (0, 1)], 0.2, axis="y")
h = lathe([(0, 0), (0.3, 0), (0.2, 0.5), (0, 0.6)])
i = sweep([(0, 0, 0), (0, -0.1, 0), (0, -0.1, 0.3)], radius=0.01)
j = sweep([(0, 0, 0), (1, 0, 0)], profile=[(0, 0), (0.1, 0), (0, 0.1)])
k = bevel((1, 1, 1), 0.1)
l = difference(a, box((0.5, 2, 0.5)))
m = combine(a, b, c)
n = linear_array(b, 3, (1, 0, 0))
o = grid_array(b, (2, 2, 1), (1, 1, 1))
p = radial_array(b, 6, "z", (0, 0, 0))
q = mirror(d, "xz", (0, 0, 0))
r = translate(e, (1, 2, 3))
s = rotate(f, 45, "z", (0, 0, 0))
t = scale(g, (1, 2, 1))
for x in range(2):
    part(x + 1, "piece", translate(l, (x * 2, 0, 0)), material=wood)
part(3, "other", combine(h, i, j, k, m, n, o, p, q, r, s, t), material="Metal")
'''


def test_every_function_exports_to_a_compilable_script():
    used = {node.func.id for node in ast.walk(ast.parse(EVERY_FUNCTION))
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)}
    assert set(FUNCTIONS) <= used | {"range"}
    script = to_blender_script(EVERY_FUNCTION)
    compile(script, "<blender>", "exec")
    tree = ast.parse(script)
    defined = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    called = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    assert {c for c in called if c.startswith("jx_")} <= defined
    assert "import bpy" in script and "import bmesh" in script
    program_part = script.split("# ---- the part program ----", 1)[1]
    assert program_part.count("jx_part(") == 2
    assert "v_wood = jx_material('Wood', 'oak')" in program_part


@pytest.mark.parametrize("name", ['a"b', "it's", "x\ny", "\\\"; import os; os.system('rm -rf /') #", "x'''y"])
def test_names_are_escaped_literals(name):
    text = f"part(1, {name!r}, box(1))\n"
    script = to_blender_script(text)
    tree = ast.parse(script)
    strings = [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)]
    assert name in strings
    imports = [n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))]
    assert sorted(a.name for n in imports for a in n.names) == ["Matrix", "Vector", "bmesh", "bpy", "math"]


def test_program_names_cannot_shadow_the_preamble():
    script = to_blender_script("bpy = box(1)\npart(1, 'a', bpy)\n")
    assert "v_bpy = jx_box(1)" in script
    compile(script, "<blender>", "exec")


def test_invalid_programs_are_rejected_not_exported():
    with pytest.raises(ProgramError) as info:
        to_blender_script("a = box(1)\nimport os\n")
    assert info.value.line == 2
