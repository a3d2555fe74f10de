"""URDF reader, with the conventions of PartNet-Mobility / PhysX-Mobility objects.

The layout is ``mobility.urdf`` beside ``semantics.txt`` (``<link> <motion> <label>`` per line)
and ``textured_objs/*.obj``. Frames are composed exactly as URDF defines them: a link's frame
is its parent's frame times the joint origin (xyz, then rpy as fixed-axis X-Y-Z rotations);
a joint's axis is given in the child frame and its pivot is the child frame's origin. This also
applies PartNet-Mobility's root joint ``rpy="1.5708 0 -1.5708"``, which turns its Y-up meshes
into the Z-up object frame.

Joint types: revolute and continuous become hinges (continuous: range [-pi, pi], one full turn
either way from the rest pose), prismatic becomes a slide, fixed is a rigid attachment, and
floating / planar (which a structure cannot express) are imported as rigid with a warning.

A mesh file that cannot be a piece (see ``meshes``) is dropped with one warning naming it and the
reason; a link whose every piece is dropped is an error naming the link, since importing the object
without that part would silently change its structure. A flat piece is kept: a link's pieces are
merged into one part mesh before any simulator sees them, and PartNet-Mobility models whole parts
(door_8877's door) as one flat mesh.

Mesh files are read relative to the URDF's folder, or, for ROS ``package://<pkg>/...`` URIs, within
the package ``<pkg>`` found at or above that folder (see ``ros_package``).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from tqdm import tqdm

from data_pipeline.importers import meshes
from data_pipeline.importers.frames import pose, rpy_matrix, scaling
from data_pipeline.importers.kinematic_tree import Edge, KinematicTree, Link, Motion
from data_pipeline.importers.limits import FaceBudget, ImportLimits, inside_folder
from data_pipeline.importers.ros_package import PACKAGE_PREFIX, PackageResolver
from data_pipeline.importers.safe_xml import parse_xml
from jax3dc.errors import InputFileError

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
HINGE_LIMIT = 2 * math.pi  # SPEC §2: hinge ranges lie within [-2pi, 2pi]
MOVING_SEMANTICS = {"hinge": ("revolute", "continuous"), "slider": ("prismatic",)}


def _numbers(path: Path, where: str, text: str | None, count: int, default: tuple[float, ...] | None):
    """``count`` finite numbers from an attribute; ``default`` None means the attribute is required."""
    if text is None:
        if default is None:
            raise InputFileError(path, f"{where}: attribute is missing")
        return np.array(default, dtype=float)
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputFileError(path, f"{where}: expected {count} finite numbers, got {text!r}")
    return np.array(values, dtype=float)


def _origin(path: Path, element: ET.Element, where: str) -> np.ndarray:
    origin = element.find("origin")
    if origin is None:
        return np.eye(4)
    xyz = _numbers(path, f"{where} <origin xyz>", origin.get("xyz"), 3, (0.0, 0.0, 0.0))
    rpy = _numbers(path, f"{where} <origin rpy>", origin.get("rpy"), 3, (0.0, 0.0, 0.0))
    return pose(rpy_matrix(*rpy), xyz)


def read_semantics(path: Path) -> dict[str, tuple[str, str]]:
    """``semantics.txt`` of PartNet-Mobility: link name -> (motion word, semantic label)."""
    if not path.is_file():
        return {}
    table = {}
    for line in path.read_text(errors="replace").splitlines():
        words = line.split()
        if len(words) >= 3:
            table[words[0]] = (words[1], " ".join(words[2:]))
    return table


def _mesh_path(urdf: Path, filename: str) -> Path:
    """The path of a plain mesh filename (``file://`` or relative to the URDF's folder)."""
    if filename.startswith("file://"):
        return Path(filename[len("file://"):])
    return urdf.parent / filename


def _geometry(urdf: Path, element: ET.Element, where: str, limits: ImportLimits, budget: FaceBudget,
              packages: PackageResolver, bounds_only: bool):
    """Mesh of one <visual>/<collision>, in the frame of its link; meshes.UnusableMesh for a mesh
    file that cannot be a piece. A ``package://`` file must stay in its package, a plain one in
    the URDF's folder (unless ``limits`` allow outside). ``bounds_only``: a mesh file becomes its
    bounding box (``meshes.load_mesh_bounds``)."""
    geometry = element.find("geometry")
    shape = None if geometry is None else next(iter(geometry), None)
    if shape is None:
        raise InputFileError(urdf, f"{where}: <geometry> is missing or empty")
    if shape.tag == "mesh":
        filename = shape.get("filename")
        if not filename:
            raise InputFileError(urdf, f"{where} <mesh>: no filename")
        if filename.startswith(PACKAGE_PREFIX):
            mesh_path = packages.resolve(filename, f"{where} <mesh>")
        else:
            mesh_path = inside_folder(_mesh_path(urdf, filename), urdf.parent, urdf, f"{where} <mesh>", limits)
        load = meshes.load_mesh_bounds if bounds_only else meshes.load_mesh_file
        mesh = load(mesh_path, urdf, where, budget)
        factors = _numbers(urdf, f"{where} <mesh scale>", shape.get("scale"), 3, (1.0, 1.0, 1.0))
        mesh.apply_transform(scaling(factors))  # before the check: a zero scale factor flattens the mesh
        reason = meshes.refusal(np.asarray(mesh.vertices), colliding=False)
        if reason is not None:
            raise meshes.UnusableMesh(f"mesh file {mesh_path} {reason}")
        return mesh
    if shape.tag == "box":
        primitive = meshes.box(_numbers(urdf, f"{where} <box size>", shape.get("size"), 3, None))
    elif shape.tag == "cylinder":
        radius = _numbers(urdf, f"{where} <cylinder radius>", shape.get("radius"), 1, None)[0]
        length = _numbers(urdf, f"{where} <cylinder length>", shape.get("length"), 1, None)[0]
        primitive = meshes.cylinder(radius, length)
    elif shape.tag == "sphere":
        primitive = meshes.sphere(_numbers(urdf, f"{where} <sphere radius>", shape.get("radius"), 1, None)[0])
    else:
        raise InputFileError(urdf, f"{where}: unsupported geometry <{shape.tag!s:.40}>")
    budget.admit(len(primitive.faces), f"<{shape.tag}>", urdf, where)  # many primitives add up too
    return primitive


def _label(name: str | None) -> str:
    """PartNet-Mobility visual names carry a node number ("glass-17"); keep the words."""
    return re.sub(r"-\d+$", "", name or "").strip()


def read_urdf(path: Path, progress: bool = False, limits: ImportLimits = ImportLimits(),
              bounds_only: bool = False) -> KinematicTree:
    """Parse a URDF into a :class:`KinematicTree` in the URDF's own units (taken as metres).

    ``bounds_only`` reads each mesh file as its bounding box, for structure checks that need no
    surface: frames and joints are those of the full read, and so are part boxes where visuals are
    turned by quarter turns (all of PartNet-Mobility but one edited oven; a box turned by another
    angle is larger than its mesh's), with 2.5 times less CPU on the real pool."""
    path = Path(path)
    budget = FaceBudget(limits)
    robot = parse_xml(path, "robot")
    warnings: list[str] = []

    link_elements: dict[str, ET.Element] = {}
    for element in robot.findall("link"):
        name = element.get("name")
        if not name:
            raise InputFileError(path, "<link> without a name")
        if name in link_elements:
            raise InputFileError(path, f"link {name!r} is defined twice")
        link_elements[name] = element
    if not link_elements:
        raise InputFileError(path, "no <link> elements")
    if len(link_elements) > limits.max_bodies:
        raise InputFileError(path, f"{len(link_elements)} links; the cap is {limits.max_bodies} "
                                   "(raise it with --max-bodies)")

    joint_elements: dict[str, ET.Element] = {}  # child link -> joint element
    joint_names: set[str] = set()
    for element in robot.findall("joint"):
        name = element.get("name") or "<unnamed>"
        where = f"joint {name!r}"
        if name in joint_names:
            raise InputFileError(path, f"{where} is defined twice")
        joint_names.add(name)
        kind = element.get("type")
        if kind not in JOINT_TYPES:
            raise InputFileError(path, f"{where}: unknown joint type {kind!r} (expected one of {JOINT_TYPES})")
        ends = {}
        for end in ("parent", "child"):
            tag = element.find(end)
            link = None if tag is None else tag.get("link")
            if not link:
                raise InputFileError(path, f"{where}: <{end} link=...> is missing")
            if link not in link_elements:
                raise InputFileError(path, f"{where}: {end} link {link!r} is referenced but not defined")
            ends[end] = link
        if ends["parent"] == ends["child"]:
            raise InputFileError(path, f"{where}: link {ends['child']!r} is its own parent")
        if ends["child"] in joint_elements:
            other = joint_elements[ends["child"]].get("name")
            raise InputFileError(
                path, f"{where}: link {ends['child']!r} has several parents (also joint {other!r})"
            )
        joint_elements[ends["child"]] = element

    roots = [name for name in link_elements if name not in joint_elements]
    if not roots:
        raise InputFileError(path, "the joints form a cycle: every link has a parent")
    if len(roots) > 1:
        raise InputFileError(path, f"several root links {roots}: a URDF must be one tree")

    # Frames of every link, root first; links never reached hang on a cycle.
    children: dict[str, list[str]] = {name: [] for name in link_elements}
    for child, element in joint_elements.items():
        children[element.find("parent").get("link")].append(child)
    world: dict[str, np.ndarray] = {roots[0]: np.eye(4)}
    order = [roots[0]]
    for name in order:
        for child in children[name]:
            where = f"joint {joint_elements[child].get('name')!r}"
            world[child] = world[name] @ _origin(path, joint_elements[child], where)
            order.append(child)
    unreached = [name for name in link_elements if name not in world]
    if unreached:
        raise InputFileError(path, f"the joints form a cycle through links {unreached}")

    semantics = read_semantics(path.parent / "semantics.txt")
    edges = [_edge(path, element, world, warnings) for element in joint_elements.values()]
    for child, element in joint_elements.items():
        motion_word = semantics.get(child, ("", ""))[0]
        kind = element.get("type")
        if motion_word in MOVING_SEMANTICS and kind not in MOVING_SEMANTICS[motion_word]:
            warnings.append(
                f"semantics.txt calls link {child!r} a {motion_word} but joint "
                f"{element.get('name')!r} is {kind}; the URDF is followed"
            )

    shapes = {
        name: element.findall("visual") or element.findall("collision")
        for name, element in link_elements.items()
    }
    bar = tqdm(total=sum(map(len, shapes.values())), desc="meshes", unit="mesh", disable=not progress)
    packages = PackageResolver(path)
    links: dict[str, Link] = {}
    for name, element in link_elements.items():
        pieces, shape_names, material_names, dropped = [], [], [], []
        for index, shape in enumerate(shapes[name]):
            where = f"link {name!r} <{shape.tag}> #{index + 1}"
            bar.update()
            try:
                local = _geometry(path, shape, where, limits, budget, packages, bounds_only)
            except meshes.UnusableMesh as e:
                warnings.append(f"{where}: {e}; that piece is dropped")
                dropped.append(str(e))
                continue
            pieces.append(meshes.transformed(local, world[name] @ _origin(path, shape, where)))
            shape_names.append(_label(shape.get("name")))
            material = shape.find("material")
            material_names.append("" if material is None else material.get("name") or "")
        if dropped and not pieces:
            raise InputFileError(path, f"link {name!r} has no geometry left: every piece was dropped "
                                       f"({'; '.join(dropped)})")
        label = semantics[name][1] if name in semantics else None
        links[name] = Link(name, meshes.merged(pieces), label, tuple(n for n in shape_names if n),
                           tuple(dict.fromkeys(n for n in material_names if n)))
    bar.close()
    return KinematicTree(path, "urdf", roots[0], links, edges, warnings)


def _edge(path: Path, element: ET.Element, world: dict[str, np.ndarray], warnings: list[str]) -> Edge:
    name = element.get("name") or "<unnamed>"
    where = f"joint {name!r}"
    kind = element.get("type")
    parent = element.find("parent").get("link")
    child = element.find("child").get("link")
    if kind == "fixed":
        return Edge(parent, child, name, kind)
    if kind in ("floating", "planar"):
        warnings.append(f"{where} is {kind}, which a structure cannot express; imported as rigid")
        return Edge(parent, child, name, kind)
    axis_element = element.find("axis")
    local_axis = _numbers(
        path, f"{where} <axis xyz>", None if axis_element is None else axis_element.get("xyz"), 3, (1.0, 0.0, 0.0)
    )
    if np.linalg.norm(local_axis) < 1e-9:
        raise InputFileError(path, f"{where} <axis>: the axis is zero")
    frame = world[child]
    axis = frame[:3, :3] @ (local_axis / np.linalg.norm(local_axis))
    if kind == "continuous":
        lo, hi = -math.pi, math.pi
    else:
        limit = element.find("limit")
        if limit is None:
            raise InputFileError(path, f"{where}: a {kind} joint needs <limit lower=... upper=...>")
        lo = _numbers(path, f"{where} <limit lower>", limit.get("lower"), 1, (0.0,))[0]
        hi = _numbers(path, f"{where} <limit upper>", limit.get("upper"), 1, (0.0,))[0]
        if lo > hi:
            raise InputFileError(path, f"{where} <limit>: lower {lo} is above upper {hi}")
        if kind == "revolute" and (lo < -HINGE_LIMIT or hi > HINGE_LIMIT):
            warnings.append(f"{where}: range [{lo:.3f}, {hi:.3f}] rad clipped to [-2pi, 2pi]")
            lo, hi = max(lo, -HINGE_LIMIT), min(hi, HINGE_LIMIT)
    motion = Motion(
        "slide" if kind == "prismatic" else "hinge", axis, frame[:3, 3].copy(), (float(lo), float(hi)), name
    )
    return Edge(parent, child, name, kind, (motion,))
