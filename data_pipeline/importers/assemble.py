"""From a kinematic tree to the record pieces: structure O, part meshes, boxes and meta.

The object is first turned about +Z to face -Y (SPEC §2). Parts are then normalised together:
the bounding box of the whole object is centred at the origin and its largest extent becomes
1 nu. Pivots move with the same transform and slide ranges are divided by the same factor; hinge
ranges are unchanged. ``scale`` (metres per nu) is the original largest extent times the metres
per source unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from data_pipeline.importers.frames import front_to_minus_y
from data_pipeline.importers.kinematic_tree import KinematicTree, reduce_to_parts
from data_pipeline.importers.material_guess import DEFAULT_FAMILY, GUESSED_DESC, UNKNOWN_DESC, guess_family
from jax3dc.errors import InputFileError
from jax3dc.geometry.mesh_size import MAX_COORDINATE
from jax3dc.geometry.parts import part_boxes
from jax3dc.relations import with_extracted_relations
from jax3dc.structure import canonicalize
from jax3dc.structure.schema import Box, Joint, Material, Node, Structure


@dataclass(frozen=True)
class ImportedObject:
    """One converted object: canonical structure, part meshes and boxes (nu), and meta."""

    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    boxes: dict[int, Box]
    meta: dict


def _rounded(values) -> list[float]:
    return [round(float(v), 6) for v in values]


def assemble(
    tree: KinematicTree, metres_per_unit: float, scale_note: str, front: str, info: dict
) -> ImportedObject:
    """Build the imported object.

    ``front`` is the direction the source object faces; the object is turned about +Z so that
    it faces -Y. ``info`` (category, object id, ...) is copied into meta.
    """
    part_links, attachments, fold_warnings = reduce_to_parts(tree)
    ids = {link: index + 1 for index, link in enumerate(part_links)}
    turn = front_to_minus_y(front)
    source_vertices = {link: tree.links[link].mesh.vertices @ turn.T for link in part_links}

    vertices = np.concatenate(list(source_vertices.values()))
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    centre = (low + high) / 2
    units_per_nu = float((high - low).max())
    if not np.isfinite(units_per_nu) or units_per_nu <= 0:
        raise InputFileError(tree.source, "the geometry has zero or non-finite extent")
    if np.abs(vertices).max() > MAX_COORDINATE:
        raise InputFileError(tree.source, f"the geometry extends beyond +-{MAX_COORDINATE:g} source units")

    parts = {
        ids[link]: trimesh.Trimesh((source_vertices[link] - centre) / units_per_nu,
                                   tree.links[link].mesh.faces, process=False)
        for link in part_links
    }
    boxes = part_boxes(parts)

    families: dict[str, int] = {}
    nodes: dict[int, Node] = {}
    for link in part_links:
        source = tree.links[link]
        family = guess_family(
            [n for n in (source.label, source.name) if n], list(source.material_names), list(source.shape_names)
        )
        material = families.setdefault(family, len(families))
        attachment = attachments[link]
        joint = None
        if attachment.motion is not None:
            m = attachment.motion
            factor = units_per_nu if m.kind == "slide" else 1.0
            joint = Joint(
                m.kind,
                tuple(float(v) for v in turn @ m.axis),
                tuple(float(v) for v in (turn @ m.pivot - centre) / units_per_nu),
                (m.range[0] / factor, m.range[1] / factor),
            )
        parent = None if attachment.parent is None else ids[attachment.parent]
        nodes[ids[link]] = Node(parent, material, joint, source.label or source.name)
    materials = {
        index: Material(family, UNKNOWN_DESC if family == DEFAULT_FAMILY else GUESSED_DESC.format(family.lower()))
        for family, index in families.items()
    }
    structure = finish_structure(Structure(materials, nodes, ()), parts, boxes)

    meta = {
        **info,
        "source": str(tree.source),
        "format": tree.format,
        "scale": units_per_nu * metres_per_unit,
        "scale_note": scale_note,
        "front": front,
        "normalisation": {
            "turn_about_z": [_rounded(row) for row in turn],  # source frame -> object frame rotation
            "centre": _rounded(centre),
            "source_units_per_nu": units_per_nu,
        },
        "part_names": {str(i): nodes[i].name for i in sorted(nodes)},
        "part_links": {str(ids[link]): link for link in part_links},
        "source_joints": {
            str(ids[link]): list(attachments[link].path_joints) for link in part_links if attachments[link].parent
        },
        "warnings": tree.warnings + fold_warnings,
    }
    return ImportedObject(structure, parts, boxes, meta)


def finish_structure(structure: Structure, parts: dict[int, trimesh.Trimesh], boxes: dict[int, Box]) -> Structure:
    """Canonical form (SPEC §2) with the symmetric / instance relations found in the part meshes.

    Relations are extracted after re-rooting, since they hold between siblings of the final tree;
    the second canonicalisation only orders them (it changes nothing else the second time).
    """
    return canonicalize(with_extracted_relations(canonicalize(structure, boxes), parts), boxes)
