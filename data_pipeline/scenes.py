"""Multi-object scenes (SPEC §4): furniture on the floor, small items resting on top of it.

A scene holds one or two pieces of furniture standing side by side on the floor and one small
item category repeated one to three times (the copies are instances of each other). Items go
on the top surface of a piece of furniture (``support`` relation: item root rests on that part)
while they fit, else on the floor. Objects keep their real sizes (metres) before the scene is
normalised as a whole. Two granularities of the same scene: ``part`` (every part of every object;
one tree per object) and ``object`` (each object one rigid part).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import trimesh

from data_pipeline.samples import SourceObject, derived_rng, factory_source, normalised
from jax3dc.structure import Node, Relation, Structure

FURNITURE = ("table", "desk", "cabinet", "nightstand", "cell_shelf", "simple_bookcase", "drawer_chest")
ITEMS = ("kettle", "kitchen_pot", "bucket", "toaster", "stapler", "desk_fan", "globe", "laptop", "printer")
GAP_M = 0.05


def _metric(obj: SourceObject, offset: np.ndarray) -> SourceObject:
    """``obj`` in metres, translated by ``offset`` (pivots moved, slide ranges scaled)."""
    s = obj.scale_m_per_nu
    parts = {p: trimesh.Trimesh(m.vertices * s + offset, m.faces, process=False) for p, m in obj.parts.items()}
    nodes = {}
    for pid, n in obj.structure.nodes.items():
        j = n.joint
        if j is not None:
            scale = s if j.type == "slide" else 1.0
            j = replace(j, pivot=tuple(float(v) for v in np.asarray(j.pivot) * s + offset),
                        range=(j.range[0] * scale, j.range[1] * scale))
        nodes[pid] = replace(n, joint=j)
    return replace(obj, structure=replace(obj.structure, nodes=nodes), parts=parts, scale_m_per_nu=1.0)


def _bounds(parts: dict[int, trimesh.Trimesh]) -> np.ndarray:
    return np.array([np.vstack([m.bounds for m in parts.values()]).min(0),
                     np.vstack([m.bounds for m in parts.values()]).max(0)])


def _top_part(obj: SourceObject) -> int:
    """The part whose top is highest (ties: the widest), where items are put."""
    return max(obj.parts, key=lambda p: (round(obj.parts[p].bounds[1, 2], 4),
                                         float(np.prod(obj.parts[p].extents[:2]))))


def _combine(objects: list[SourceObject], supports: list[tuple[int, int, int]]) -> tuple[Structure, dict, list[int]]:
    """One structure of several objects; ``supports`` (item index, furniture index, furniture part).
    Returns the structure, the parts and each object's id offset."""
    materials, nodes, parts, offsets = {}, {}, {}, []
    next_id, next_mat = 1, 0
    for obj in objects:
        offset = next_id - 1
        mat_map = {}
        for mid, mat in sorted(obj.structure.materials.items()):
            mat_map[mid] = next_mat
            materials[next_mat] = mat
            next_mat += 1
        for pid, n in sorted(obj.structure.nodes.items()):
            nodes[pid + offset] = replace(n, parent=None if n.parent is None else n.parent + offset,
                                          material=mat_map[n.material])
            parts[pid + offset] = obj.parts[pid]
        offsets.append(offset)
        next_id += len(obj.parts)
    relations = tuple(Relation("support", objects[i].structure.roots()[0] + offsets[i], part + offsets[f])
                      for i, f, part in supports)
    return Structure(materials=materials, nodes=nodes, relations=relations), parts, offsets


def object_level(structure: Structure, parts: dict[int, trimesh.Trimesh], objects: list[SourceObject],
                 offsets: list[int]) -> tuple[Structure, dict]:
    """Each object one rigid part (ids 1..K in object order); support relations kept per object."""
    owner = {pid + offsets[k]: k for k, obj in enumerate(objects) for pid in obj.parts}
    new_parts, nodes = {}, {}
    for k, obj in enumerate(objects):
        ids = [pid + offsets[k] for pid in sorted(obj.parts)]
        root = obj.structure.roots()[0] + offsets[k]
        new_parts[k + 1] = trimesh.util.concatenate([parts[p] for p in ids])
        nodes[k + 1] = Node(parent=None, material=structure.nodes[root].material)
    used = sorted({n.material for n in nodes.values()})
    remap = {m: i for i, m in enumerate(used)}
    nodes = {p: replace(n, material=remap[n.material]) for p, n in nodes.items()}
    relations = tuple(Relation("support", owner[r.a] + 1, owner[r.b] + 1) for r in structure.relations)
    return Structure({remap[m]: structure.materials[m] for m in used}, nodes, relations), new_parts


def make_scene(seed: int, index: int) -> list[SourceObject]:
    """Scene ``index`` of a build with ``seed`` at part and object granularity."""
    rng = derived_rng(seed, "scene", index)

    def factory(category: str) -> SourceObject:
        obj_seed = int(rng.integers(1 << 31))
        return factory_source(category, obj_seed)

    furniture_cats = rng.choice(FURNITURE, size=int(rng.integers(1, 3)), replace=False)
    item = factory(str(rng.choice(ITEMS)))
    copies = int(rng.integers(1, 4))
    placed: list[SourceObject] = []
    x = 0.0
    for cat in furniture_cats:
        obj = factory(str(cat))
        lo, hi = _bounds(_metric(obj, np.zeros(3)).parts)
        placed.append(_metric(obj, np.array([x - lo[0], -(lo[1] + hi[1]) / 2, -lo[2]])))
        x += hi[0] - lo[0] + GAP_M
    item_lo, item_hi = _bounds(_metric(item, np.zeros(3)).parts)
    width = item_hi[0] - item_lo[0]
    supports = []
    free = {f: _bounds({0: placed[f].parts[_top_part(placed[f])]}) for f in range(len(placed))}
    cursor = {f: free[f][0][0] for f in free}
    for c in range(copies):
        host = next((f for f in free if cursor[f] + width <= free[f][1][0]), None)
        if host is not None:
            top = free[host]
            offset = np.array([cursor[host] - item_lo[0], (top[0][1] + top[1][1]) / 2 - (item_lo[1] + item_hi[1]) / 2,
                               top[1][2] - item_lo[2]])
            cursor[host] += width + GAP_M / 2
            supports.append((len(placed), host, _top_part(placed[host])))
        else:
            offset = np.array([x - item_lo[0], -(item_lo[1] + item_hi[1]) / 2, -item_lo[2]])
            x += width + GAP_M
        placed.append(_metric(item, offset))
    structure, parts, offsets = _combine(placed, supports)
    structure, parts_nu, size = normalised(structure, parts)
    scene_id = f"scene_{seed:06d}_{index:06d}"
    part_scene = SourceObject("scene", scene_id, structure, parts_nu, size, granularity="part")
    obj_structure, obj_parts = object_level(structure, parts_nu, placed, offsets)
    return [part_scene, SourceObject("scene", scene_id, obj_structure, obj_parts, size, granularity="object")]
