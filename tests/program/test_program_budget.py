"""Execution budgets: steps, triangles and time are capped and reported with the line."""

import pytest

from jax3dc.errors import ProgramError
from jax3dc.program import Budget, run_program


def test_step_budget_stops_long_loops():
    text = 'a = box(1)\npart(1, "x", a)\nfor i in range(5000):\n    b = i\n'
    with pytest.raises(ProgramError) as info:
        run_program(text, Budget(max_steps=1000))
    assert "step budget" in info.value.message
    assert info.value.line in (3, 4)
    assert run_program(text, Budget(max_steps=20_000)).parts


def test_nested_loops_hit_the_step_budget():
    text = 'for i in range(1000):\n    for j in range(1000):\n        b = j\n'
    with pytest.raises(ProgramError, match="step budget"):
        run_program(text)


def test_range_size_is_capped():
    with pytest.raises(ProgramError, match="range"):
        run_program("for i in range(10000000):\n    b = i\n")


def test_triangle_budget_counts_created_meshes():
    text = 'a = sphere(1, segments=64, rings=32)\npart(1, "ball", a)\n'
    sphere_triangles = len(run_program(text).parts[1].faces)
    with pytest.raises(ProgramError) as info:
        run_program(text, Budget(max_triangles=sphere_triangles - 1))
    assert info.value.line == 1 and "triangle budget" in info.value.message


def test_triangle_budget_counts_emitted_parts():
    """One mesh named by part() many times is written many times: each emission counts."""
    text = "a = sphere(1, segments=64, rings=32)\nfor i in range(1, 1001):\n    part(i, 'copy', a)\n"
    with pytest.raises(ProgramError) as info:
        run_program(text, Budget(max_triangles=100_000))
    assert info.value.line == 3 and "triangle budget" in info.value.message
    one = run_program("a = sphere(1, segments=64, rings=32)\npart(1, 'one', a)\n")
    assert one.triangles == 2 * len(one.parts[1].faces)  # built once, emitted once


def test_time_budget_is_checked_inside_one_long_call():
    """A boolean with hundreds of cutters is one statement; the deadline still stops it."""
    cutters = ", ".join(f"box(0.001, center=({i / 2000}, 0, 0))" for i in range(900))
    text = f"a = difference(box(1), {cutters})\npart(1, 'a', a)\n"
    with pytest.raises(ProgramError) as info:
        run_program(text, Budget(max_seconds=0.05))
    assert info.value.line == 1 and "inside difference()" in info.value.message


def test_operand_count_is_capped():
    text = "a = box(1)\nb = combine(" + ", ".join(["a"] * 1001) + ")\n"
    with pytest.raises(ProgramError, match="at most 1000 meshes"):
        run_program(text)


@pytest.mark.parametrize("text", [
    "a = box(" + "9" * 400 + ")\n",
    "a = box(1e308 * 10)\n",
    "a = " + "9" * 16 + " / 1\n",
    "for i in range(" + "9" * 30 + "):\n    b = i\n",
    "a = box(1, center=(" + "1" + "0" * 300 + ", 0, 0))\n",
])
def test_huge_numbers_are_program_errors(text):
    with pytest.raises(ProgramError, match="too large|finite number"):
        run_program(text)


def test_array_is_refused_before_it_is_built():
    text = 'a = sphere(1, segments=256, rings=128)\nb = linear_array(a, 1000, (1, 0, 0))\n'
    with pytest.raises(ProgramError) as info:
        run_program(text, Budget(max_triangles=1_000_000))
    assert info.value.line == 2 and "triangle budget" in info.value.message


def test_time_budget():
    text = 'for i in range(5000):\n    a = box(1)\npart(1, "x", a)\n'
    with pytest.raises(ProgramError, match="time budget"):
        run_program(text, Budget(max_seconds=1e-6))


def test_combine_is_refused_before_it_is_built():
    text = "a = sphere(1, segments=256, rings=128)\nb = combine(" + ", ".join(["a"] * 200) + ")\n"
    with pytest.raises(ProgramError) as info:
        run_program(text)
    assert info.value.line == 2 and "triangle budget" in info.value.message


@pytest.mark.parametrize("text", [
    "a = " + "+".join(["1"] * 100_000) + "\n",
    "a = " + "-" * 100_000 + "1\n",
    "a = " + "(" * 300 + "1" + ")" * 300 + "\n",
])
def test_deep_nesting_is_a_program_error(text):
    with pytest.raises(ProgramError):
        run_program(text)


def test_runaway_scaling_is_refused():
    text = "a = box(1)\n" + "".join("a = scale(a, 1000000)\n" for _ in range(5)) + "part(1, 'a', a)\n"
    with pytest.raises(ProgramError) as info:
        run_program(text)
    assert info.value.line == 3 and "coordinates" in info.value.message


def test_single_calls_are_bounded():
    """The time budget is checked between statements, so one call must not be able to run long."""
    import time

    ring = ", ".join(f"({i}, {i % 2})" for i in range(300))
    cases = [
        (f"a = extrude([{ring}], 1)\n", "at most 256"),
        ("a = sweep([" + ", ".join(f"({i}, 0, 0)" for i in range(2000)) + "], radius=0.1)\n", "at most 1024"),
    ]
    for text, message in cases:
        start = time.perf_counter()
        with pytest.raises(ProgramError, match=message):
            run_program(text)
        assert time.perf_counter() - start < 5.0


def test_lone_surrogate_text_is_refused():
    with pytest.raises(ProgramError, match="lone surrogate"):
        run_program('part(1, "\\ud800", box())\n')
