"""Whatever text comes in (model output is untrusted), the interpreter either returns parts or
raises ProgramError: no other exception escapes, and nothing runs outside the language."""

import math

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jax3dc.errors import ProgramError
from jax3dc.program import Budget, FUNCTIONS, run_program, to_blender_script

SMALL = Budget(max_seconds=2.0, max_triangles=200_000, max_steps=2_000)
TOKENS = sorted(FUNCTIONS) + ["range", "for", "in", "=", "(", ")", ",", ":", "\n", "    ", "a", "b", "i", "1",
                              "-2.5", "0", "1e308", "'x'", "[", "]", "+", "*", "/", "-", "center=", "axis=",
                              "'z'", "part", "import", ".", "__class__", "lambda", "1e-320", "nan"]


def outcome(text):
    try:
        result = run_program(text, SMALL)
    except ProgramError as exc:
        assert exc.line is None or exc.line >= 1
        return "rejected"
    for mesh in result.parts.values():
        assert len(mesh.faces) > 0
    return "ran"


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(TOKENS), max_size=30).map(" ".join))
def test_token_soup_is_rejected_or_runs(text):
    outcome(text)
    try:
        compile(to_blender_script(text), "<fuzz>", "exec")
    except ProgramError:
        pass


numbers = st.one_of(st.integers(-10**6, 10**6), st.floats(allow_nan=False, allow_infinity=False, width=64),
                    st.sampled_from([0, -1, 1e-300, 1e300, 3, 256, 257]))
values = st.recursive(numbers | st.sampled_from(["'x'", "'y'", "'z'", "'yz'", "'Wood'", "m"]),
                      lambda inner: st.lists(inner, max_size=4).map(lambda xs: "(" + ", ".join(map(str, xs)) + ",)"),
                      max_leaves=12)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(sorted(FUNCTIONS)), st.lists(values, max_size=4),
       st.dictionaries(st.sampled_from(["size", "center", "radius", "depth", "axis", "segments", "count",
                                        "offset", "profile", "path", "width", "angle", "factor", "plane"]),
                       values, max_size=3))
def test_random_calls_are_rejected_or_run(name, args, kwargs):
    call = f"{name}({', '.join(map(str, args + [f'{k}={v}' for k, v in kwargs.items()]))})"
    text = f"m = box(1)\nr = {call}\npart(1, 'p', r)\n"
    if outcome(text) == "ran":
        mesh = run_program(text, SMALL).parts[1]
        assert math.isfinite(mesh.volume) and mesh.vertices.size and abs(mesh.vertices).max() < 1e7
