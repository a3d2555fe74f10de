"""A plain-text reference of the part-program language, generated from the function table.

Used as `jax3dc program reference` output and as the language description a code-writing
model can be given; generated so that it can never drift from what the interpreter accepts.
"""

from __future__ import annotations

import inspect

from jax3dc.program.interpreter import DEFAULT_MAX_SECONDS, DEFAULT_MAX_STEPS, DEFAULT_MAX_TRIANGLES
from jax3dc.program.library import FUNCTIONS

_HEADER = f"""\
Part programs: Python syntax, interpreted (never executed by Python).
Statements: `name = expression`, a call such as `part(...)`, `for i in range(n):` with an
indented body. Expressions: numbers, 'text', tuples/lists, + - * / on numbers, names bound
earlier, calls of the functions below (positional or keyword arguments).
Units: lengths in the program's units, angles in degrees, axis is "x", "y" or "z".
Frame: +Z up, the object's front faces -Y. Each part ends in part(id, name, mesh, material=...).
Budget: {DEFAULT_MAX_SECONDS:g} s, {DEFAULT_MAX_TRIANGLES} triangles, {DEFAULT_MAX_STEPS} statements.
"""


def language_reference() -> str:
    lines = [_HEADER, "Functions:"]
    seen = set()
    for name, fn in FUNCTIONS.items():
        alias = fn in seen
        seen.add(fn)
        signature = str(inspect.signature(fn)).split(" ->")[0]
        doc = (inspect.getdoc(fn) or "").split("\n\n")[0].replace("\n", " ")
        if alias:
            doc = f"same as {fn.__name__ if fn.__name__ in FUNCTIONS else 'the function above'}"
        lines.append(f"  {name}{signature}" + (f"\n      {doc}" if doc else ""))
    return "\n".join(lines) + "\n"
