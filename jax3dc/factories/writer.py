"""ProgramWriter: factories describe an object in metres; the writer emits its part program.

A factory calls the writer's methods (one per predefined function of the part-program
language) with coordinates in metres, names parts with their parent, material and joint, and
marks copies of one design with a shared `twin` key. `finish` evaluates the metric statements once to
find the bounding box, then re-emits every number in the normalised frame (bbox centre at the
origin, largest extent 1) — points are shifted and scaled, lengths only scaled, angles and counts
kept — so the program text is the single source of the geometry, and the structure's pivots and
slide ranges are mapped with the same affine map. The parts are the meshes of running that text;
symmetric / instance relations are extracted from them (jax3dc.relations, the SPEC §4 rule), and
the factory's own twin keys give the relations it intended, which tests compare with the extraction.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from itertools import combinations
from typing import Any

import numpy as np

from jax3dc.program import FUNCTIONS, ProgramResult, run_program
from jax3dc.program.library import PartCall
from jax3dc.relations import extract_relations
from jax3dc.structure.schema import Joint, Material, Node, Relation, Structure

POINT, LENGTH, PLAIN = "point", "length", "plain"
DECIMALS = 4
MIRROR_TOL = 2e-3  # nu; centroids this close count as mirror images


@dataclass(frozen=True)
class Ref:
    """A program variable holding a mesh or material."""

    name: str


@dataclass(frozen=True)
class Arg:
    keyword: str | None
    value: Any
    kind: str  # POINT, LENGTH or PLAIN; applies elementwise inside tuples / lists


@dataclass(frozen=True)
class Statement:
    target: str | None
    function: str
    args: tuple[Arg, ...]


@dataclass(frozen=True)
class JointSpec:
    """A joint in metres: hinge range in radians, slide range in metres."""

    type: str
    axis: tuple[float, float, float]
    pivot: tuple[float, float, float]
    range: tuple[float, float]


@dataclass(frozen=True)
class PartSpec:
    part_id: int
    name: str
    parent: int | None
    material: int
    joint: JointSpec | None
    twin: str | None


@dataclass
class Normalised:
    program_text: str
    result: ProgramResult
    structure: Structure  # relations extracted from the part meshes (jax3dc.relations, SPEC §4)
    scale_m_per_nu: float
    intended_relations: tuple[Relation, ...]  # what the factory built as copies (twin keys), for checks


def _as_tuples(value: Any) -> Any:
    """Writer arguments as the interpreter passes them: lists and tuples become tuples."""
    if isinstance(value, (list, tuple)):
        return tuple(_as_tuples(v) for v in value)
    return value


def fmt(x: float) -> str:
    """Number literal with at most DECIMALS decimals and no trailing zeros."""
    s = f"{x:.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _literal(value: Any, kind: str, shift: np.ndarray, scale: float) -> str:
    if isinstance(value, Ref):
        return value.name
    if isinstance(value, str):
        return repr(value)
    if isinstance(value, bool):
        raise TypeError("booleans are not part of the language")
    if isinstance(value, int) and kind == PLAIN:
        return str(value)
    if isinstance(value, (tuple, list)):
        items = list(value)
        if kind == POINT and len(items) == 3 and all(not isinstance(v, (tuple, list)) for v in items):
            items = [(float(v) - shift[i]) * scale for i, v in enumerate(items)]
            return "(" + ", ".join(fmt(v) for v in items) + ")"
        inner = [_literal(v, kind, shift, scale) for v in items]
        return "[" + ", ".join(inner) + "]" if any(isinstance(v, (tuple, list)) for v in items) \
            else "(" + ", ".join(inner) + ")"
    x = float(value)
    return fmt(x * scale if kind in (LENGTH, POINT) else x)


class ProgramWriter:
    """Collects statements and part specs in metres; see the module docstring."""

    def __init__(self) -> None:
        self.statements: list[Statement] = []
        self.parts: list[PartSpec] = []
        self.materials: list[Material] = []
        self._material_refs: list[Ref] = []
        self._counts: dict[str, int] = {}

    # ---- recording ----
    def _var(self, stem: str) -> str:
        self._counts[stem] = self._counts.get(stem, 0) + 1
        return f"{stem}{self._counts[stem]}"

    def call(self, function: str, *args: Arg, stem: str | None = None) -> Ref:
        target = self._var(stem or function)
        self.statements.append(Statement(target, function, tuple(args)))
        return Ref(target)

    def material(self, family: str, desc: str) -> int:
        """Registers a material; returns its structure id (0, 1, ...)."""
        for i, m in enumerate(self.materials):
            if m == Material(family, desc):
                return i
        ref = self.call("material", Arg(None, family, PLAIN), Arg(None, desc, PLAIN), stem="mat")
        self.materials.append(Material(family, desc))
        self._material_refs.append(ref)
        return len(self.materials) - 1

    def part(self, name: str, mesh: Ref, material: int, parent: int | None = None,
             joint: JointSpec | None = None, twin: str | None = None) -> int:
        """Names `mesh` as the next part id; returns the id."""
        pid = len(self.parts) + 1
        self.statements.append(Statement(None, "part", (
            Arg(None, pid, PLAIN), Arg(None, name, PLAIN), Arg(None, mesh, PLAIN),
            Arg("material", self._material_refs[material], PLAIN))))
        self.parts.append(PartSpec(pid, name, parent, material, joint, twin))
        return pid

    # ---- the language's functions, with argument kinds ----
    def box(self, size, center) -> Ref:
        return self.call("box", Arg(None, tuple(size), LENGTH), Arg("center", tuple(center), POINT))

    def bevel(self, size, width, center) -> Ref:
        return self.call("bevel", Arg(None, tuple(size), LENGTH), Arg("width", width, LENGTH),
                         Arg("center", tuple(center), POINT))

    def cylinder(self, radius, depth, center, axis="z", segments=24) -> Ref:
        return self.call("cylinder", Arg("radius", radius, LENGTH), Arg("depth", depth, LENGTH),
                         Arg("center", tuple(center), POINT), Arg("axis", axis, PLAIN),
                         Arg("segments", segments, PLAIN))

    def cone(self, radius1, radius2, depth, center, axis="z", segments=24) -> Ref:
        return self.call("cone", Arg("radius1", radius1, LENGTH), Arg("radius2", radius2, LENGTH),
                         Arg("depth", depth, LENGTH), Arg("center", tuple(center), POINT),
                         Arg("axis", axis, PLAIN), Arg("segments", segments, PLAIN))

    def sphere(self, radius, center, segments=16, rings=8) -> Ref:
        return self.call("sphere", Arg("radius", radius, LENGTH), Arg("center", tuple(center), POINT),
                         Arg("segments", segments, PLAIN), Arg("rings", rings, PLAIN))

    def torus(self, major, minor, center, axis="z", major_segments=24, minor_segments=8) -> Ref:
        return self.call("torus", Arg("major_radius", major, LENGTH), Arg("minor_radius", minor, LENGTH),
                         Arg("center", tuple(center), POINT), Arg("axis", axis, PLAIN),
                         Arg("major_segments", major_segments, PLAIN), Arg("minor_segments", minor_segments, PLAIN))

    def extrude(self, profile, depth, center, axis="z") -> Ref:
        return self.call("extrude", Arg(None, [tuple(p) for p in profile], LENGTH), Arg("depth", depth, LENGTH),
                         Arg("center", tuple(center), POINT), Arg("axis", axis, PLAIN))

    def lathe(self, profile, center, axis="z", segments=24) -> Ref:
        return self.call("lathe", Arg(None, [tuple(p) for p in profile], LENGTH), Arg("center", tuple(center), POINT),
                         Arg("axis", axis, PLAIN), Arg("segments", segments, PLAIN))

    def sweep(self, path, radius, segments=8) -> Ref:
        return self.call("sweep", Arg(None, [tuple(p) for p in path], POINT), Arg("radius", radius, LENGTH),
                         Arg("segments", segments, PLAIN))

    def difference(self, base: Ref, *cutters: Ref) -> Ref:
        return self.call("difference", Arg(None, base, PLAIN), *[Arg(None, c, PLAIN) for c in cutters])

    def combine(self, *meshes: Ref) -> Ref:
        return self.call("combine", *[Arg(None, m, PLAIN) for m in meshes])

    def linear_array(self, mesh: Ref, count: int, offset) -> Ref:
        return self.call("linear_array", Arg(None, mesh, PLAIN), Arg("count", count, PLAIN),
                         Arg("offset", tuple(offset), LENGTH))

    def grid_array(self, mesh: Ref, counts, spacing) -> Ref:
        return self.call("grid_array", Arg(None, mesh, PLAIN), Arg("counts", tuple(counts), PLAIN),
                         Arg("spacing", tuple(spacing), LENGTH))

    def radial_array(self, mesh: Ref, count: int, center, axis="z") -> Ref:
        return self.call("radial_array", Arg(None, mesh, PLAIN), Arg("count", count, PLAIN),
                         Arg("axis", axis, PLAIN), Arg("center", tuple(center), POINT))

    def mirror(self, mesh: Ref, plane: str, center) -> Ref:
        return self.call("mirror", Arg(None, mesh, PLAIN), Arg(None, plane, PLAIN), Arg("center", tuple(center), POINT))

    def translate(self, mesh: Ref, offset) -> Ref:
        return self.call("translate", Arg(None, mesh, PLAIN), Arg(None, tuple(offset), LENGTH))

    def rotate(self, mesh: Ref, angle_deg: float, axis, center) -> Ref:
        return self.call("rotate", Arg(None, mesh, PLAIN), Arg(None, angle_deg, PLAIN), Arg("axis", axis, PLAIN),
                         Arg("center", tuple(center), POINT))

    def scale(self, mesh: Ref, factor, center) -> Ref:
        return self.call("scale", Arg(None, mesh, PLAIN), Arg(None, tuple(factor), PLAIN),
                         Arg("center", tuple(center), POINT))

    def turn(self, quarter_turns: int, axis: str = "z") -> None:
        """Turns everything written so far by `quarter_turns` x 90 degrees about +X, +Y or +Z
        through the metric origin: each part's mesh by a `rotate` statement written just before
        its `part`, each joint's axis and pivot by the same rotation.

        Factories build in one pose (facing -Y, standing); this lets one face another way or lie
        down without rewriting its geometry, and keeps the structure on its parts (the mesh calls
        alone would leave the joints behind). Quarter turns only, applied to joints as an exact
        matrix of 0 and +-1, so axes stay unit vectors with no 1e-16 residues.
        """
        k = quarter_turns % 4
        if k == 0:
            return
        if axis not in ("x", "y", "z"):
            raise ValueError(f"turn axis must be x, y or z, not {axis!r}")
        c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[k]
        a, b = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]  # the plane turned, in the right-hand order

        def turned(v: tuple[float, float, float]) -> tuple[float, float, float]:
            out = [float(x) for x in v]
            out[a], out[b] = float(c * v[a] - s * v[b]), float(s * v[a] + c * v[b])
            return tuple(x + 0.0 for x in out)  # no -0.0

        angle = (0.0, 90.0, 180.0, -90.0)[k]
        statements = []
        for st in self.statements:
            if st.function == "part":
                target = self._var("turned")
                statements.append(Statement(target, "rotate", (
                    st.args[2], Arg(None, angle, PLAIN), Arg("axis", axis, PLAIN),
                    Arg("center", (0.0, 0.0, 0.0), POINT))))
                st = replace(st, args=(st.args[0], st.args[1], Arg(None, Ref(target), PLAIN), *st.args[3:]))
            statements.append(st)
        self.statements = statements
        self.parts = [p if p.joint is None else
                      replace(p, joint=replace(p.joint, axis=turned(p.joint.axis), pivot=turned(p.joint.pivot)))
                      for p in self.parts]

    # ---- output ----
    def _readable_names(self) -> dict[str, str]:
        """The mesh each part names is called after the part (`door_3`), the rest keep `box2`."""
        renames = {}
        for st in self.statements:
            if st.function == "part":
                pid, name, mesh = (a.value for a in st.args[:3])
                if isinstance(mesh, Ref) and mesh.name not in renames:
                    renames[mesh.name] = f"{re.sub(r'[^0-9a-zA-Z]+', '_', name).strip('_') or 'part'}_{pid}"
        return renames

    def program_text(self, shift=(0.0, 0.0, 0.0), scale: float = 1.0) -> str:
        shift = np.asarray(shift, dtype=np.float64)
        renames = self._readable_names()
        lines = []
        for st in self.statements:
            args = []
            for a in st.args:
                value = Ref(renames.get(a.value.name, a.value.name)) if isinstance(a.value, Ref) else a.value
                lit = _literal(value, a.kind, shift, scale)
                args.append(f"{a.keyword}={lit}" if a.keyword else lit)
            call = f"{st.function}({', '.join(args)})"
            lines.append(f"{renames.get(st.target, st.target)} = {call}" if st.target else call)
        return "\n".join(lines) + "\n"

    def metric_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounding box (metres) of all parts, by calling the language's functions on the
        recorded statements directly: the same geometry as running the metric text, without
        printing and parsing it."""
        env: dict[str, Any] = {}
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for st in self.statements:
            args, kwargs = [], {}
            for a in st.args:
                value = env[a.value.name] if isinstance(a.value, Ref) else _as_tuples(a.value)
                if a.keyword:
                    kwargs[a.keyword] = value
                else:
                    args.append(value)
            out = FUNCTIONS[st.function](*args, **kwargs)
            if st.target:
                env[st.target] = out
            if isinstance(out, PartCall):
                lo = np.minimum(lo, out.solid.vertices.min(axis=0))
                hi = np.maximum(hi, out.solid.vertices.max(axis=0))
        return lo, hi

    def finish(self) -> Normalised:
        """Normalise, run the final program and build the structure (SPEC §2 frame)."""
        lo, hi = self.metric_bounds()
        centre = (lo + hi) / 2.0
        scale = 1.0 / float(np.max(hi - lo))
        text = self.program_text(centre, scale)
        result = run_program(text)
        nodes = {}
        for p in self.parts:
            joint = None
            if p.joint is not None:
                j = p.joint
                pivot = tuple(round(float((v - centre[i]) * scale), DECIMALS) for i, v in enumerate(j.pivot))
                rng = j.range if j.type == "hinge" else tuple(float(v * scale) for v in j.range)
                axis = np.asarray(j.axis, dtype=np.float64)
                axis = tuple(float(v) for v in axis / np.linalg.norm(axis))
                joint = Joint(j.type, axis, pivot, tuple(round(float(v), DECIMALS) for v in rng))
            nodes[p.part_id] = Node(parent=p.parent, material=p.material, joint=joint, name=p.name)
        bare = Structure(dict(enumerate(self.materials)), nodes, ())
        structure = replace(bare, relations=extract_relations(bare, result.parts))
        return Normalised(text, result, structure, 1.0 / scale, twin_relations(self.parts, result))


def twin_relations(parts: list[PartSpec], result: ProgramResult) -> tuple[Relation, ...]:
    """Relations the factory intends between copies of one design (same `twin` key and parent).

    The SPEC §4 rule applied to the factory's own knowledge of which parts are copies: a pair is
    `symmetric` when its centroids mirror across a principal plane through the parent's
    bounding-box centre (the object's centre for roots), else `instance`. Used to check that
    the extraction from meshes (jax3dc.relations) finds what was built.
    """
    centres = {pid: (m.bounds[0] + m.bounds[1]) / 2.0 for pid, m in result.parts.items()}
    groups: dict[tuple[str, int | None], list[int]] = {}
    for p in parts:
        if p.twin is not None:
            groups.setdefault((p.twin, p.parent), []).append(p.part_id)
    out = []
    for (_, parent), ids in sorted(groups.items(), key=lambda kv: kv[1][0]):
        origin = centres[parent] if parent is not None else np.zeros(3)
        for a, b in combinations(sorted(ids), 2):
            plane = None
            for axis, name in ((0, "yz"), (1, "xz"), (2, "xy")):
                mirrored = centres[a].copy()
                mirrored[axis] = 2 * origin[axis] - mirrored[axis]
                if np.linalg.norm(mirrored - centres[b]) < MIRROR_TOL:
                    plane = name
                    break
            out.append(Relation("symmetric", a, b, plane) if plane else Relation("instance", a, b))
    return tuple(sorted(out, key=lambda r: (r.type, r.a, r.b)))
