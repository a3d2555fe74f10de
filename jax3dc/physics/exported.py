"""An exported MJCF file (``jax3dc export --format mjcf``, ``predict``'s ``object.xml``) as the
physics checks' input: the object as the file has it.

What a simulator runs is the file's: each part's parent is the body it is nested in, its joint
(type, axis, pivot, range) the body's joint, in nu through the file's scale, its collision pieces
the file's inline hulls, and its mesh ``meshes/<id>.obj`` placed at the body. What MuJoCo has no
place for comes from the file's custom texts (``jax3dc.export.mjcf``): materials, relations, the
scale and whether the object is mounted; a body's part id is in its name (``part_<id>[_<slug>]``).
A file edited by hand (a range changed, a body moved, a joint moved off its body's origin) is
checked as edited; a frame the exporter never writes (a rotated body or geom) is refused in one
line rather than misread.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from pathlib import Path

import defusedxml
import defusedxml.ElementTree as DefusedET
import numpy as np
import trimesh

from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.export.assembly import frames_nu, tree_order
from jax3dc.export.mjcf import MOUNTED_TEXT, SCALE_TEXT, STRUCTURE_TEXT
from jax3dc.geometry.parts import load_part_mesh
from jax3dc.structure import parse_structure
from jax3dc.structure.schema import Joint, Structure

LABEL = re.compile(r"part_(\d+)(?:_\w*)?")  # a body's name (jax3dc.export.assembly.label_of)
ROTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")  # frame attributes the exporter never writes


@dataclass(frozen=True)
class ExportedObject:
    """The checks' inputs read from a file: structure and part meshes in nu, metres per nu, whether
    the object is mounted, and each part's collision pieces (its frame at the structure's pivot, m)."""

    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool
    pieces: dict[int, list[np.ndarray]]


def is_mjcf(path: Path) -> bool:
    """Whether ``path`` names an MJCF file (by its suffix: a structure document is .json)."""
    return path.suffix.lower() == ".xml"


def load_exported(path: Path, max_part_faces: int) -> ExportedObject:
    """Read the file and its meshes; InputFileError names what is missing or not understood."""
    try:  # the file is the user's: no DTD, so no entity expansion
        root = DefusedET.parse(path, forbid_dtd=True).getroot()
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror or e}") from None
    except ET.ParseError as e:
        raise InputFileError(path, f"not readable XML: {e}") from None
    except defusedxml.DefusedXmlException as e:
        raise InputFileError(path, f"refused XML construct ({type(e).__name__}): an MJCF needs no DTD or entities") from None
    if root.tag != "mujoco":
        raise InputFileError(path, f"not an MJCF file: its root element is <{root.tag}>, not <mujoco>")
    texts = {t.get("name"): t.get("data", "") for t in root.iter("text")}
    if STRUCTURE_TEXT not in texts or SCALE_TEXT not in texts:
        raise InputFileError(path, f"no '{STRUCTURE_TEXT}' and '{SCALE_TEXT}' custom texts: not a file written by "
                                   "jax3dc export --format mjcf (check its structure with --parts instead)")
    try:
        base = parse_structure(texts[STRUCTURE_TEXT])
    except Jax3dcError as e:
        raise InputFileError(path, f"its '{STRUCTURE_TEXT}' text is not a valid structure: {e}") from None
    scale = _number(texts[SCALE_TEXT], path, SCALE_TEXT)
    if not scale > 0:
        raise InputFileError(path, f"'{SCALE_TEXT}' must be a positive number of metres per nu, got {scale}")
    compiler = root.find("compiler")
    degrees = compiler is None or compiler.get("angle", "degree") == "degree"  # MuJoCo's default unit is the degree
    meshdir = path.parent / (compiler.get("meshdir", "") if compiler is not None else "")
    hulls = {m.get("name"): _floats(m.get("vertex", ""), path, f"mesh {m.get('name')}") for m in root.iter("mesh")
             if m.get("vertex")}
    bad = next((name for name, v in hulls.items() if len(v) % 3), None)
    if bad is not None:
        raise InputFileError(path, f"mesh '{bad}': its vertex list is not a list of 3-vectors")
    hulls = {name: v.reshape(-1, 3) for name, v in hulls.items()}
    worldbody = root.find("worldbody")
    if worldbody is None:
        raise InputFileError(path, "no <worldbody>")
    nodes, parts, pieces, origin = {}, {}, {}, {}
    stack = [(b, None, np.zeros(3)) for b in reversed(worldbody.findall("body"))]
    while stack:
        body, parent, at = stack.pop()
        name = body.get("name", "")
        label = LABEL.fullmatch(name)
        part = int(label.group(1)) if label else None
        if part not in base.nodes or part in nodes:
            raise InputFileError(path, f"body '{name}' is none of the structure's parts (part_<id>[_<name>]) "
                                       "or a second body of one")
        _refuse_rotation(body, path, f"body '{name}'")
        origin[part] = at + _floats(body.get("pos", "0 0 0"), path, f"body '{name}' pos", 3)
        joints = body.findall("joint")
        if len(joints) > 1:
            raise InputFileError(path, f"body '{name}' has {len(joints)} joints; a part has at most one")
        joint = _joint(joints[0], origin[part], scale, degrees, path) if joints else None
        nodes[part] = replace(base.nodes[part], parent=parent, joint=joint)
        mesh = load_part_mesh(meshdir / f"{part}.obj", max_part_faces)
        parts[part] = trimesh.Trimesh((np.asarray(mesh.vertices) + origin[part]) / scale, mesh.faces, process=False)
        pieces[part] = []
        for geom in body.findall("geom"):
            if geom.get("mesh") in hulls:
                _refuse_rotation(geom, path, f"geom '{geom.get('name')}'")
                if geom.get("pos"):
                    raise InputFileError(path, f"geom '{geom.get('name')}' is offset from its body: not supported")
                pieces[part].append(hulls[geom.get("mesh")] + origin[part])  # object frame, m
        stack.extend((b, part, origin[part]) for b in reversed(body.findall("body")))
    missing = sorted(set(base.nodes) - set(nodes))
    if missing:
        raise InputFileError(path, f"no body for parts {missing} of its structure")
    structure = Structure(base.materials, nodes, base.relations)
    frames = frames_nu(structure, tree_order(structure))  # the checks' part frames: at each joint's pivot
    pieces = {p: [v - frames[p] * scale for v in vs] for p, vs in pieces.items()}
    return ExportedObject(structure, parts, scale, texts.get(MOUNTED_TEXT) == "true", pieces)


def _joint(element: ET.Element, body_m: np.ndarray, scale: float, degrees: bool, path: Path) -> Joint:
    kind = element.get("type", "hinge")
    name = element.get("name", "")
    if kind not in ("hinge", "slide"):
        raise InputFileError(path, f"joint '{name}' is a {kind}: a part's joint is a hinge or a slide")
    if element.get("range") is None:
        raise InputFileError(path, f"joint '{name}' has no range")
    low, high = _floats(element.get("range"), path, f"joint '{name}' range", 2)
    unit = (math.pi / 180 if degrees else 1.0) if kind == "hinge" else 1.0 / scale
    pivot = (body_m + _floats(element.get("pos", "0 0 0"), path, f"joint '{name}' pos", 3)) / scale
    axis = _floats(element.get("axis", "0 0 1"), path, f"joint '{name}' axis", 3)
    if not np.linalg.norm(axis) > 0:
        raise InputFileError(path, f"joint '{name}' has a zero axis")
    return Joint(kind, tuple(float(a) for a in axis), tuple(float(c) for c in pivot), (float(low * unit), float(high * unit)))


def _refuse_rotation(element: ET.Element, path: Path, what: str) -> None:
    rotated = [a for a in ROTATIONS if element.get(a) is not None]
    if rotated:
        raise InputFileError(path, f"{what} is rotated ({rotated[0]}): the exporter writes unrotated frames only")


def _floats(text: str, path: Path, what: str, count: int | None = None) -> np.ndarray:
    """The numbers of an attribute (``count`` of them when given), all finite."""
    try:
        values = np.array([float(x) for x in text.split()], dtype=np.float64)
    except ValueError:
        raise InputFileError(path, f"{what}: not a list of numbers") from None
    if not np.isfinite(values).all():
        raise InputFileError(path, f"{what}: non-finite numbers")
    if count is not None and len(values) != count:
        raise InputFileError(path, f"{what}: {len(values)} numbers where {count} belong")
    return values


def _number(text: str, path: Path, what: str) -> float:
    return float(_floats(text, path, what, 1)[0])
