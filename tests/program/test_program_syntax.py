"""The part-program checker rejects everything outside the language, naming the line."""

import pytest

from jax3dc.errors import ProgramError
from jax3dc.program import parse_program, run_program, to_blender_script

GOOD_HEAD = 'a = box((1, 1, 1))\npart(1, "body", a)\n'

REJECTED = [
    ("import os\n", 1, "import"),
    (GOOD_HEAD + "from os import path\n", 3, "import"),
    (GOOD_HEAD + "b = a.vertices\n", 3, "attribute"),
    ('box((1, 1, 1)).__class__\n', 1, "attribute"),
    (GOOD_HEAD + "__builtins__ = 1\n", 3, "dunder"),
    (GOOD_HEAD + "b = __import__\n", 3, "dunder"),
    (GOOD_HEAD + "b = (1, 2)[0]\n", 3, "subscript"),
    (GOOD_HEAD + "f = lambda x: x\n", 3, "lambda"),
    (GOOD_HEAD + "b = [x for x in (1, 2)]\n", 3, "comprehension"),
    (GOOD_HEAD + "def f():\n    pass\n", 3, "def"),
    (GOOD_HEAD + "class A:\n    pass\n", 3, "class"),
    (GOOD_HEAD + "while 1:\n    pass\n", 3, "while"),
    (GOOD_HEAD + "for i in (1, 2):\n    pass\n", 3, "range"),
    (GOOD_HEAD + "open('/etc/passwd')\n", 3, "not a predefined function"),
    (GOOD_HEAD + "b = eval('1')\n", 3, "not a predefined function"),
    (GOOD_HEAD + "b = c\n", 3, "unknown name"),
    (GOOD_HEAD + "box = 1\n", 3, "predefined"),
    (GOOD_HEAD + "b = box\n", 3, "function"),
    (GOOD_HEAD + "b = box(**{})\n", 3, "kwargs"),
    (GOOD_HEAD + "b = box(*(1,))\n", 3, "args"),
    (GOOD_HEAD + "b = box(colour=1)\n", 3, "colour"),
    (GOOD_HEAD + "b = 1 if 1 else 2\n", 3, "conditional"),
    (GOOD_HEAD + "b = 2 ** 10\n", 3, "+ - * /"),
    (GOOD_HEAD + "b = {1: 2}\n", 3, "dictionar"),
    (GOOD_HEAD + "b = True\n", 3, "literal"),
    (GOOD_HEAD + "b = f'{a}'\n", 3, "f-string"),
    (GOOD_HEAD + "a += 1\n", 3, "augmented"),
    (GOOD_HEAD + "b = (\n", 3, "syntax"),
]


@pytest.mark.parametrize("text,line,fragment", REJECTED)
def test_rejected_with_line(text, line, fragment):
    with pytest.raises(ProgramError) as info:
        run_program(text)
    assert info.value.line == line
    assert fragment.lower() in info.value.message.lower()
    assert str(line) in str(info.value)
    with pytest.raises(ProgramError):
        to_blender_script(text)


RUNTIME_ERRORS = [
    ('a = box((1, 1, 1))\npart(1, "x", a)\nb = box((1, -1, 1))\n', 3, "size"),
    ('a = box((1, 1, 1))\npart(1, "x", a)\npart(1, "y", a)\n', 3, "twice"),
    ('a = box((1, 1, 1))\nb = a / 2\n', 2, "numbers"),
    ('a = 1 / 0\n', 1, "zero"),
    ('a = cylinder(radius=0.1, depth=1, axis="w")\n', 1, "axis"),
    ('a = cylinder(radius=0.1, depth=1, segments=100000)\n', 1, "segments"),
    ('a = material("Unobtainium")\n', 1, "family"),
    ('a = box(1)\npart(1, "x", a, material=3)\n', 2, "material"),
    ('a = sphere(1)\nb = difference(a, box(3))\n', 2, "removes the whole solid"),
    ('a = extrude(((0, 0), (2, 2), (2, 0), (0, 1)), 1)\n', 1, "simple"),
    ('a = extrude(((0, 0), (1, 1), (1, 0), (0, 1)), 1)\n', 1, "zero area"),
    ('a = box(1)\n', None, "names no part"),
]


@pytest.mark.parametrize("text,line,fragment", RUNTIME_ERRORS)
def test_runtime_errors_name_the_line(text, line, fragment):
    with pytest.raises(ProgramError) as info:
        run_program(text)
    assert info.value.line == line
    assert fragment.lower() in info.value.message.lower()


def test_accepted_program_with_loop_arithmetic_and_keywords():
    text = (
        "# a row of shelves\n"
        "w = 0.5\n"
        "wood = material(\"Wood\", \"oak\")\n"
        "for i in range(3):\n"
        "    board = box(size=(w, 0.3, 0.02), center=(0, 0, -0.4 + i * w / 2))\n"
        "    part(i + 1, \"shelf\", board, material=wood)\n"
        "part(4, \"post\", cylinder(0.01, 1, center=(-w / 2 - 0.01, 0, 0)), material=\"Metal\")\n"
    )
    tree = parse_program(text)
    assert len(tree.body) == 4
    result = run_program(text)
    assert sorted(result.parts) == [1, 2, 3, 4]
    assert result.names == {1: "shelf", 2: "shelf", 3: "shelf", 4: "post"}
    assert result.materials[1].desc == "oak" and result.materials[4].family == "Metal"
    zs = [result.parts[i].bounds.mean(axis=0)[2] for i in (1, 2, 3)]
    assert zs == pytest.approx([-0.4, -0.15, 0.1])
