"""A decode-time check measured and not adopted (issue "Real joints", item 5): the hinge side of a
door or lid read from its own mesh, the edge away from its handle.

A real door's link carries its handle in the same mesh, so the segmentation shows a door with no
handle part, and a model that learned where hinges go from separate handle parts puts the hinge on
the wrong edge (a microwave's door hinged at its handle: the reference line 0.7 nu away). The
mesh still holds the handle as a protrusion off the door's slab. Over 366 public PartNet-Mobility
objects, 68 of 71 doors with a handle are hinged on the side away from it.

For each hinge whose axis lies along one of its part's box axes and whose part is a plate (thin
across the axis), the part's surface — with the meshes of its rigid descendants, where handles are
parts of their own — is split into the slab (the two largest planar layers across the plate) and
what stands off it. When the protrusion sits off the middle of the plate along its width and the
written pivot lies near the edge on the protrusion's side, the pivot moves to the opposite edge and
the axis turns round, so that a positive angle still swings the door the same way (a reflection
across the plate's middle turns a rotation about a into one about -a). Nothing else changes.

Measured on the held-out fifth at rest (view 0, 62 objects, the part meshes of the converted pool),
on the predictions of the candidate `c3` and of release 4 brought back from the GPU run:
    python3 docs/runs/release6_20261205/hinge_side_check.py RUN_C3/bench RUN_C2/bench POOL/conv
It moved 1-6 hinges per set and gained no joint (release 4: one fewer right), so it is not in the
package.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import trimesh

from eval.evaluators.real_objects import score
from eval.metrics.cases import load_predictions, load_references
from jax3dc.geometry.parts import load_parts
from jax3dc.structure import parse_structure, to_json
from jax3dc.structure.schema import Joint, Structure

AXIS_TOLERANCE = 0.35  # rad: an axis this close to a box direction counts as along it
PLATE_RATIO = 0.5  # a part is a plate when its thickness is under this share of its width
LAYER_BINS = 24  # bins across the plate's thickness for finding its slab
STANDOFF_BINS = 2  # bins beyond the slab where the protrusion starts
MIN_PROTRUSION = 0.002  # share of the slab's area below which nothing stands off
OFF_CENTRE = 0.15  # share of the width the protrusion must sit off the middle
NEAR_EDGE = 0.25  # share of the width within which a written pivot counts as at an edge


@dataclass(frozen=True)
class SideChange:
    """One hinge moved to the other edge: its part, and the pivot and axis before and after."""

    part: int
    before: Joint
    after: Joint


def _rigid_mesh(structure: Structure, parts: dict[int, trimesh.Trimesh], pid: int) -> trimesh.Trimesh:
    """The part with every descendant fixed to it (a handle modelled as a part of its own)."""
    meshes, stack = [parts[pid]], [pid]
    while stack:
        for child in structure.children(stack.pop()):
            if structure.nodes[child].joint is None and child in parts:
                meshes.append(parts[child])
                stack.append(child)
    return meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)


def protrusion_side(mesh: trimesh.Trimesh, normal_dim: int, width_dim: int) -> float | None:
    """Where along ``width_dim`` what stands off the plate's slab sits, as a signed share of the
    width from the middle (-0.5 .. 0.5), or None when nothing stands off it."""
    centroids = np.asarray(mesh.triangles_center, dtype=np.float64)
    areas = np.asarray(mesh.area_faces, dtype=np.float64)
    lo, hi = np.asarray(mesh.bounds, dtype=np.float64)
    thickness, width = hi[normal_dim] - lo[normal_dim], hi[width_dim] - lo[width_dim]
    if thickness <= 0 or width <= 0 or areas.sum() <= 0:
        return None
    layer = np.clip(((centroids[:, normal_dim] - lo[normal_dim]) / thickness * LAYER_BINS).astype(int), 0,
                    LAYER_BINS - 1)
    per_layer = np.bincount(layer, weights=areas, minlength=LAYER_BINS)
    slab = np.sort(np.argsort(per_layer)[-2:])  # the plate's two big faces
    outside = (layer > slab[1] + STANDOFF_BINS) | (layer < slab[0] - STANDOFF_BINS)
    if areas[outside].sum() < MIN_PROTRUSION * per_layer[slab].sum():
        return None
    u = np.average(centroids[outside, width_dim], weights=areas[outside])
    return float((u - (lo[width_dim] + hi[width_dim]) / 2) / width)


def hinge_sides(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> tuple[Structure, list[SideChange]]:
    """``structure`` with each qualifying hinge on the edge away from its part's protrusion (module
    docstring), and the changes made; ``parts`` are the meshes in the structure's own frame."""
    nodes = dict(structure.nodes)
    changes = []
    for pid, joint in structure.joints().items():
        if joint.type != "hinge" or pid not in parts:
            continue
        axis = np.asarray(joint.axis, dtype=np.float64)
        axis = axis / np.linalg.norm(axis)
        k = int(np.argmax(np.abs(axis)))
        if np.arccos(min(1.0, abs(axis[k]))) > AXIS_TOLERANCE:
            continue
        mesh = _rigid_mesh(structure, parts, pid)
        lo, hi = np.asarray(mesh.bounds, dtype=np.float64)
        extent = hi - lo
        n, u = sorted((d for d in range(3) if d != k), key=lambda d: extent[d])
        if extent[u] <= 0 or extent[n] >= PLATE_RATIO * extent[u]:
            continue
        side = protrusion_side(mesh, n, u)
        if side is None or abs(side) < OFF_CENTRE:
            continue
        near, far = (hi[u], lo[u]) if side > 0 else (lo[u], hi[u])
        pivot = np.asarray(joint.pivot, dtype=np.float64)
        if abs(pivot[u] - near) > NEAR_EDGE * extent[u]:
            continue  # already away from the protrusion, or not at an edge
        pivot[u] = far
        moved = replace(joint, pivot=tuple(float(v) for v in pivot), axis=tuple(float(-v) + 0.0 for v in axis))
        nodes[pid] = replace(nodes[pid], joint=moved)
        changes.append(SideChange(pid, joint, moved))
    return replace(structure, nodes=nodes), changes


CONV = Path(sys.argv[3])
def run(bench: Path, label: str) -> dict:

    refs = load_references(bench / 'model' / 'references.jsonl')
    preds = load_predictions(bench / label / 'predictions.jsonl')
    out = {}
    for look in ('heldout', 'heldout_varied'):
        tail = [] if look == 'heldout' else ['heldout_varied']
        keys = [r.key for r in refs if r.key.split('/')[2:] == ['0', *tail] and (CONV / r.key.split('/')[1]).is_dir()]
        fixed, moved = {}, 0
        for key in keys:
            doc = preds.get(key)
            parts = load_parts(CONV / key.split('/')[1] / 'parts')
            try:
                s = parse_structure(doc, part_ids=parts) if isinstance(doc, str) else None
            except Exception:
                s = None
            if s is None:
                fixed[key] = doc; continue
            s2, changes = hinge_sides(s, parts)
            moved += len(changes)
            fixed[key] = to_json(s2)
        records = [SimpleNamespace(key=k, meta={'category': k.split('/')[0], 'augmentation': None}) for k in keys]
        before = score(refs, preds, records); after = score(refs, fixed, records)
        f = lambda r: (round(r['metrics']['success'], 1), f"{r['all_joints']['success']}/{r['all_joints']['ref_joints']}",
                       f"{(r['door_like'] or {}).get('success')}/{(r['door_like'] or {}).get('ref_joints')}", round(r['hinge_edge_acc'] or 0, 1))
        out[look] = (len(keys), moved, f(before), f(after))
        print(label, look, len(keys), 'records', moved, 'hinges moved', 'before', f(before), 'after', f(after), flush=True)
    return out
if __name__ == '__main__':
    run(Path(sys.argv[1]), 'model')
    run(Path(sys.argv[2]), 'compare')
