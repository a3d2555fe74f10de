"""Runs a checked part program by walking its syntax tree (no exec / eval), within a budget."""

from __future__ import annotations

import ast
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh

from jax3dc.errors import ProgramError
from jax3dc.program.library import FUNCTIONS, MAX_COPIES, ArgumentError, OutOfTime, PartCall, deadline
from jax3dc.program.solids import Solid
from jax3dc.program.syntax import SIGNATURES, parse_program
from jax3dc.structure.schema import Material

DEFAULT_MAX_SECONDS = 5.0
"""Wall-clock limit of one program run."""
DEFAULT_MAX_TRIANGLES = 2_000_000
"""Limit on the triangles of all meshes a program creates (intermediate ones included) plus those
it emits as parts: one mesh named by part() a thousand times is written a thousand times."""
DEFAULT_MAX_STEPS = 100_000
"""Limit on executed statements, loop iterations included."""
MAX_RANGE = 10_000
MAX_INTEGER = 10**15
"""Largest whole number a program may write or compute (beyond it floats and ranges overflow)."""
MAX_COORDINATE = 1e9
"""Meshes whose vertices leave +-MAX_COORDINATE (e.g. after repeated scaling) are refused."""


@dataclass(frozen=True)
class Budget:
    """Limits on one run; exceeding any is a ProgramError naming the line. Model output is
    untrusted, so every run has one (time is checked between statements and inside long calls
    such as a boolean with many cutters; triangles are counted when built and when emitted)."""

    max_seconds: float = DEFAULT_MAX_SECONDS
    max_triangles: int = DEFAULT_MAX_TRIANGLES
    max_steps: int = DEFAULT_MAX_STEPS


@dataclass
class ProgramResult:
    """The named parts of a program: meshes, semantic names and materials by part id."""

    parts: dict[int, trimesh.Trimesh]
    names: dict[int, str]
    materials: dict[int, Material] = field(default_factory=dict)
    triangles: int = 0


_ARRAYS = {"linear_array", "grid_array", "radial_array"}


class _Run:
    def __init__(self, budget: Budget):
        self.budget = budget
        self.env: dict[str, Any] = {}
        self.parts: dict[int, PartCall] = {}
        self.triangles = 0
        self.steps = 0
        self.deadline = time.perf_counter() + budget.max_seconds

    # -- statements --
    def statements(self, body: list[ast.stmt]) -> None:
        for stmt in body:
            self.tick(stmt.lineno)
            if isinstance(stmt, ast.Assign):
                self.env[stmt.targets[0].id] = self.value(stmt.value)
            elif isinstance(stmt, ast.Expr):
                self.value(stmt.value)
            elif isinstance(stmt, ast.For):
                self.loop(stmt)

    def loop(self, stmt: ast.For) -> None:
        bounds = [self.value(a) for a in stmt.iter.args]
        if any(isinstance(b, bool) or not isinstance(b, int) for b in bounds):
            raise ProgramError(stmt.lineno, "range arguments must be whole numbers")
        if len(bounds) == 3 and bounds[2] == 0:
            raise ProgramError(stmt.lineno, "range step must not be zero")
        r = range(*bounds)
        if len(r) > MAX_RANGE:
            raise ProgramError(stmt.lineno, f"range has {len(r)} steps; at most {MAX_RANGE} are allowed")
        for i in r:
            self.tick(stmt.lineno)
            self.env[stmt.target.id] = i
            self.statements(stmt.body)

    def tick(self, line: int) -> None:
        self.steps += 1
        if self.steps > self.budget.max_steps:
            raise ProgramError(line, f"step budget exceeded ({self.budget.max_steps} statements)")
        if time.perf_counter() > self.deadline:
            raise ProgramError(line, f"time budget exceeded ({self.budget.max_seconds:g} s; raise it with --max-seconds)")

    # -- expressions --
    def value(self, node: ast.expr) -> Any:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, int) and abs(node.value) > MAX_INTEGER:
                raise ProgramError(node.lineno, f"number too large (whole numbers are limited to +-{MAX_INTEGER:g})")
            return node.value
        if isinstance(node, (ast.Tuple, ast.List)):
            return tuple(self.value(e) for e in node.elts)
        if isinstance(node, ast.Name):
            if node.id not in self.env:
                raise ProgramError(node.lineno, f"name {node.id!r} has no value here")
            return self.env[node.id]
        if isinstance(node, ast.UnaryOp):
            x = self.number(node.operand)
            return -x if isinstance(node.op, ast.USub) else x
        if isinstance(node, ast.BinOp):
            return self.arithmetic(node)
        if isinstance(node, ast.Call):
            return self.call(node)
        raise ProgramError(getattr(node, "lineno", None), f"{type(node).__name__} is not allowed")

    def number(self, node: ast.expr) -> int | float:
        x = self.value(node)
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise ProgramError(node.lineno, "arithmetic works on numbers only")
        return x

    def arithmetic(self, node: ast.BinOp) -> int | float:
        a, b = self.number(node.left), self.number(node.right)
        if isinstance(node.op, ast.Add):
            out = a + b
        elif isinstance(node.op, ast.Sub):
            out = a - b
        elif isinstance(node.op, ast.Mult):
            out = a * b
        else:
            if b == 0:
                raise ProgramError(node.lineno, "division by zero")
            out = a / b
        if isinstance(out, int) and abs(out) > MAX_INTEGER:
            raise ProgramError(node.lineno, f"number too large (whole numbers are limited to +-{MAX_INTEGER:g})")
        return out

    def call(self, node: ast.Call) -> Any:
        name = node.func.id
        fn = FUNCTIONS[name]
        args = [self.value(a) for a in node.args]
        kwargs = {kw.arg: self.value(kw.value) for kw in node.keywords}
        if name in _ARRAYS:
            self.check_array_size(node, fn, args, kwargs)
        elif name == "combine":
            incoming = sum(a.triangle_count for a in args if isinstance(a, Solid))
            self.check_triangles(node, incoming)
        try:
            with deadline(self.deadline):
                out = fn(*args, **kwargs)
        except ArgumentError as exc:
            raise ProgramError(node.lineno, f"{name}(): {exc}") from None
        except OutOfTime:
            raise ProgramError(node.lineno, f"time budget exceeded ({self.budget.max_seconds:g} s; raise it with "
                                            f"--max-seconds) inside {name}()") from None
        if isinstance(out, Solid):
            if len(out.vertices) and not np.abs(out.vertices).max() <= MAX_COORDINATE:
                raise ProgramError(node.lineno, f"{name}(): coordinates beyond +-{MAX_COORDINATE:g}")
            self.check_triangles(node, out.triangle_count)
            self.triangles += out.triangle_count
        if isinstance(out, PartCall):
            if out.part_id in self.parts:
                raise ProgramError(node.lineno, f"part id {out.part_id} is named twice")
            self.check_triangles(node, out.solid.triangle_count)  # each part is written out on its own
            self.triangles += out.solid.triangle_count
            self.parts[out.part_id] = out
        return out

    def check_array_size(self, node: ast.Call, fn, args, kwargs) -> None:
        """Refuse an array whose copies would exceed the triangle budget before building it."""
        bound = SIGNATURES[node.func.id].bind(*args, **kwargs)
        bound.apply_defaults()
        mesh = bound.arguments["mesh"]
        if not isinstance(mesh, Solid):
            return  # the function reports the wrong argument type itself
        counts = bound.arguments.get("counts", (bound.arguments.get("count", 1),))
        copies = 1
        for c in counts if isinstance(counts, tuple) else (counts,):
            copies *= c if isinstance(c, int) and 0 < c <= MAX_COPIES else 1
        self.check_triangles(node, copies * mesh.triangle_count)

    def check_triangles(self, node: ast.Call, incoming: int) -> None:
        if self.triangles + incoming > self.budget.max_triangles:
            raise ProgramError(node.lineno, f"triangle budget exceeded ({self.budget.max_triangles}; "
                                            "raise it with --max-triangles)")


def run_program(text: str, budget: Budget = Budget()) -> ProgramResult:
    """Check and interpret a part program; every `part(...)` call becomes one part mesh."""
    tree = parse_program(text)
    run = _Run(budget)
    try:
        run.statements(tree.body)
    except RecursionError:
        raise ProgramError(None, "the program is nested too deeply") from None
    except (OverflowError, MemoryError) as exc:  # a number or a size no check above foresaw
        raise ProgramError(None, f"a value is too large to compute ({type(exc).__name__})") from None
    if not run.parts:
        raise ProgramError(None, "the program names no part (call part(id, name, mesh))")
    parts, names, materials = {}, {}, {}
    for pid in sorted(run.parts):
        call = run.parts[pid]
        parts[pid] = trimesh.Trimesh(call.solid.vertices, call.solid.faces, process=False)
        names[pid] = call.name
        if call.material is not None:
            materials[pid] = call.material
    return ProgramResult(parts, names, materials, run.triangles)
