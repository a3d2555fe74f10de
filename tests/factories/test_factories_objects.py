"""Every factory builds valid, normalised, deterministic objects whose joints sit on their parts."""

import functools
import math

import numpy as np
import pytest

from jax3dc.errors import Jax3dcError
from jax3dc.factories import FACTORIES, generate_object
from jax3dc.program import run_program, to_blender_script
from jax3dc.structure import parse_structure, to_json
from jax3dc.structure.schema import FAMILIES, JOINT_TYPES, PLANES, Structure
from jax3dc.structure.union_find import connected_sets

SEEDS = (0, 1, 2)
CATEGORIES = sorted(FACTORIES)
SHELVES = ("cell_shelf", "large_shelf", "simple_bookcase", "triangle_shelf")
PIVOT_TOL = 0.02  # nu: a pivot lies on (or this close to) the bounding box of the part it moves


@functools.lru_cache(maxsize=None)
def make(category, seed):
    return generate_object(category, seed)


def check_spec_rules(s: Structure, part_ids):
    """SPEC §2 validation rules, checked directly and then by jax3dc.structure's own parser."""
    assert sorted(s.nodes) == sorted(part_ids)
    for pid, node in s.nodes.items():
        assert node.parent is None or node.parent in s.nodes, pid
        assert node.parent != pid
        assert node.material in s.materials
        if node.joint is not None:
            j = node.joint
            assert node.parent is not None
            assert j.type in JOINT_TYPES
            axis = np.asarray(j.axis)
            assert np.all(np.isfinite(axis)) and abs(np.linalg.norm(axis) - 1) < 1e-6
            assert np.all(np.isfinite(j.pivot))
            assert all(type(v) is float for v in (*j.axis, *j.pivot, *j.range)), "plain floats for JSON"
            assert j.range[0] <= j.range[1]
            if j.type == "hinge":
                assert -2 * math.pi <= j.range[0] and j.range[1] <= 2 * math.pi
    for pid in s.nodes:  # acyclic: every chain of parents ends
        seen, cur = set(), pid
        while cur is not None:
            assert cur not in seen, f"cycle through {pid}"
            seen.add(cur)
            cur = s.nodes[cur].parent
    for m in s.materials.values():
        assert m.family in FAMILIES
    for r in s.relations:
        assert r.a in s.nodes and r.b in s.nodes and r.a != r.b
        assert (r.plane in PLANES) if r.type == "symmetric" else r.plane is None
    parse_structure(to_json(s), part_ids=part_ids)


def test_registry_covers_the_spec():
    assert len([c for c, f in FACTORIES.items() if not f.instance_heavy]) >= 27
    assert {c for c, f in FACTORIES.items() if f.instance_heavy} == set(SHELVES)
    for needed in ("cabinet", "drawer_chest", "wardrobe", "kitchen_unit", "refrigerator", "oven", "microwave",
                   "dishwasher", "washing_machine", "storage_box", "laptop", "toilet", "trash_can", "door",
                   "window", "faucet", "lamp", "safe", "suitcase", "table", "chair", "stool", "sofa", "bed", "desk"):
        assert needed in FACTORIES


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("category", CATEGORIES)
def test_object_is_valid_and_normalised(category, seed):
    obj = make(category, seed)
    ids = sorted(obj.parts)
    assert ids == list(range(1, len(ids) + 1)) and len(ids) >= 2
    assert sorted(obj.names) == ids and all(obj.names.values())
    s = obj.structure
    check_spec_rules(s, ids)
    assert len(s.roots()) == 1, "one object, one tree"
    assert {pid: n.name for pid, n in s.nodes.items()} == obj.names
    lo = np.min([m.bounds[0] for m in obj.parts.values()], axis=0)
    hi = np.max([m.bounds[1] for m in obj.parts.values()], axis=0)
    assert np.allclose((lo + hi) / 2, 0.0, atol=1e-3)
    assert np.max(hi - lo) == pytest.approx(1.0, abs=1e-3)
    assert 0.02 < obj.scale_m_per_nu < 5.0  # metres: from a faucet to a 4-bay shelf
    for pid, mesh in obj.parts.items():
        assert len(mesh.faces) > 0
        assert mesh.is_watertight and mesh.volume > 0, (pid, obj.names[pid])
    for pid, joint in s.joints().items():
        child = obj.parts[pid]
        gap = np.maximum(0, np.maximum(child.bounds[0] - joint.pivot, np.asarray(joint.pivot) - child.bounds[1]))
        assert np.linalg.norm(gap) <= PIVOT_TOL, (pid, obj.names[pid], joint)


@pytest.mark.parametrize("category", CATEGORIES)
def test_same_seed_same_bytes(category):
    a, b = generate_object(category, 7), generate_object(category, 7)
    assert a.program_text == b.program_text
    assert to_json(a.structure) == to_json(b.structure)
    assert a.object_id == b.object_id
    assert make(category, 0).program_text != make(category, 1).program_text


@pytest.mark.parametrize("category", CATEGORIES)
def test_program_text_is_the_geometry(category):
    obj = make(category, 0)
    again = run_program(obj.program_text)
    assert again.names == obj.names
    for pid, mesh in obj.parts.items():
        assert np.array_equal(again.parts[pid].vertices, mesh.vertices)
        assert np.array_equal(again.parts[pid].faces, mesh.faces)
    assert {pid: m.family for pid, m in again.materials.items()} == {
        pid: obj.structure.materials[n.material].family for pid, n in obj.structure.nodes.items()}
    compile(to_blender_script(obj.program_text), category, "exec")


def _rotated_centroid(mesh, joint, angle):
    a = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    r = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)
    c = mesh.bounds.mean(axis=0)
    return (c - joint.pivot) @ r.T + joint.pivot


def _moving(category, seeds, names):
    for seed in seeds:
        obj = make(category, seed)
        for pid, joint in obj.structure.joints().items():
            if obj.names[pid] in names:
                yield obj, pid, joint


OPENS_TOWARDS_FRONT = {  # hinged parts whose opening swings them out of the front (-Y)
    "cabinet": {"door"}, "wardrobe": {"door"}, "kitchen_unit": {"door"}, "refrigerator": {"fridge_door", "freezer_door"},
    "oven": {"door"}, "microwave": {"door"}, "dishwasher": {"door"}, "washing_machine": {"door"}, "safe": {"door"},
    "door": {"leaf"},
}
OPENS_UPWARDS = {"storage_box": {"lid"}, "toilet": {"seat", "lid"}, "trash_can": {"lid"}, "washing_machine": {"lid"}}
VARIANT_SEEDS = range(6)  # enough seeds to meet each design variant (front loader / top loader, ...)


@pytest.mark.parametrize("category", sorted(OPENS_TOWARDS_FRONT))
def test_doors_swing_out_of_the_front(category):
    found = 0
    for obj, pid, joint in _moving(category, VARIANT_SEEDS, OPENS_TOWARDS_FRONT[category]):
        if category == "wardrobe" and joint.type == "slide":  # sliding doors run sideways on their tracks
            assert abs(joint.axis[0]) == pytest.approx(1.0) and joint.range[1] > 0.1
            found += 1
            continue
        assert joint.type == "hinge"
        before = obj.parts[pid].bounds.mean(axis=0)
        if category == "dishwasher":  # shown open, folded down: closing lifts it back against the front
            closed = _rotated_centroid(obj.parts[pid], joint, joint.range[0])
            assert joint.range[1] == 0 and abs(joint.axis[0]) == pytest.approx(1.0)
            assert closed[1] > before[1] + 0.02 and closed[2] > before[2] + 0.02
            assert joint.pivot[2] == pytest.approx(obj.parts[pid].bounds[1][2], abs=0.01)  # folded: hinge at its top
            found += 1
            continue
        after = _rotated_centroid(obj.parts[pid], joint, joint.range[1])
        assert after[1] < before[1] - 0.02, (obj.object_id, pid)
        if category == "oven":  # drop-down door: horizontal hinge at the bottom front edge
            assert abs(joint.axis[0]) == pytest.approx(1.0)
            assert joint.pivot[2] == pytest.approx(obj.parts[pid].bounds[0][2], abs=0.01)
            assert after[2] < before[2]
        else:  # side-hinged door: vertical axis on the door's side edge
            assert abs(joint.axis[2]) == pytest.approx(1.0)
            bx = obj.parts[pid].bounds[:, 0]
            assert min(abs(joint.pivot[0] - bx[0]), abs(joint.pivot[0] - bx[1])) < 0.02
        found += 1
    assert found >= 2


@pytest.mark.parametrize("category", sorted(OPENS_UPWARDS))
def test_lids_lift(category):
    found = 0
    for obj, pid, joint in _moving(category, VARIANT_SEEDS, OPENS_UPWARDS[category]):
        before = obj.parts[pid].bounds.mean(axis=0)
        after = _rotated_centroid(obj.parts[pid], joint, joint.range[1])
        assert abs(joint.axis[0]) == pytest.approx(1.0) and after[2] > before[2] + 0.02
        assert joint.pivot[1] > before[1], "hinged at the back"
        found += 1
    assert found >= 2


@pytest.mark.parametrize("category", ["drawer_chest", "nightstand", "desk", "dishwasher"])
def test_drawers_slide_out_of_the_front(category):
    found = 0
    for obj, pid, joint in _moving(category, SEEDS, {"drawer", "rack"}):
        assert joint.type == "slide"
        assert joint.axis == pytest.approx((0.0, -1.0, 0.0))
        assert 0 < joint.range[1] < 1.0
        found += 1
    assert found >= 2


def test_other_articulations():
    for seed in SEEDS:
        laptop = make("laptop", seed)
        (screen,) = [p for p, n in laptop.names.items() if n == "screen_lid"]
        j = laptop.structure.nodes[screen].joint
        assert j.type == "hinge" and abs(j.axis[0]) == pytest.approx(1.0) and j.range[0] < 0 < j.range[1]
        faucet = make("faucet", seed)
        (lever,) = [p for p, n in faucet.names.items() if n == "lever"]
        assert faucet.structure.nodes[lever].joint.type == "hinge"
        window = make("window", seed)
        sash_joints = [j for p, j in window.structure.joints().items() if window.names[p] == "sash"]
        assert sash_joints and all(j.type in ("hinge", "slide") for j in sash_joints)


def test_relations_follow_the_design():
    for obj in [make("wardrobe", s) for s in range(8)]:
        doors = tuple(sorted(p for p, n in obj.names.items() if n == "door"))
        related = [r for r in obj.structure.relations if (r.a, r.b) == doors]
        if obj.structure.nodes[doors[0]].joint.type == "hinge":  # mirrored hinged doors
            assert [(r.type, r.plane) for r in related] == [("symmetric", "yz")]
        else:  # sliding doors on two tracks: copies, not mirror images
            assert [(r.type, r.plane) for r in related] == [("instance", None)]
    for category in SHELVES:
        for seed in SEEDS:
            rels = make(category, seed).structure.relations
            assert sum(r.type == "instance" for r in rels) >= 1, (category, seed)


def test_unknown_category_and_bad_seed_are_typed_errors():
    with pytest.raises(Jax3dcError, match="unknown category"):
        generate_object("spaceship", 0)
    with pytest.raises(Jax3dcError, match="seed"):
        generate_object("cabinet", -1)


def test_identical_across_processes_and_hash_seeds():
    """Nothing depends on Python's per-process hash seed (sets, dict order of str keys)."""
    import os
    import subprocess
    import sys

    code = ("import hashlib, json, dataclasses\n"
            "from jax3dc.factories import FACTORIES, generate_object\n"
            "h = hashlib.sha256()\n"
            "for c in sorted(FACTORIES):\n"
            "    g = generate_object(c, 3)\n"
            "    h.update(g.program_text.encode())\n"
            "    h.update(json.dumps(dataclasses.asdict(g.structure), sort_keys=True, default=str).encode())\n"
            "print(h.hexdigest())\n")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    digests = set()
    for hash_seed in ("1", "12345"):
        env = dict(os.environ, PYTHONHASHSEED=hash_seed, PYTHONPATH=root)
        out = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True,
                             check=True)
        digests.add(out.stdout.strip())
    assert len(digests) == 1


def _instance_groups(relations):
    """Part -> the smallest part of its instance group (itself when it is in none)."""
    pairs = [(r.a, r.b) for r in relations if r.type == "instance"]
    anchor = {p: group[0] for group in connected_sets({i for pair in pairs for i in pair}, pairs) for p in group}
    return lambda part: anchor.get(part, part)


@pytest.mark.parametrize("category", CATEGORIES)
def test_extracted_relations_agree_with_the_design(category):
    """jax3dc.relations, reading only the meshes, finds exactly the copies the factory built."""
    from tests.factory_samples import build_normalised

    for seed in range(4):
        built = build_normalised(category, seed)
        extracted = built.structure.relations
        same_group = _instance_groups(extracted)
        symmetric = {(r.a, r.b, r.plane) for r in extracted if r.type == "symmetric"}
        for r in built.intended_relations:
            if r.type == "symmetric":
                assert (min(r.a, r.b), max(r.a, r.b), r.plane) in symmetric, (category, seed, r)
            else:
                assert same_group(r.a) == same_group(r.b), (category, seed, r)
        intended_pairs = {(min(r.a, r.b), max(r.a, r.b)) for r in built.intended_relations}
        assert {(r.a, r.b) for r in extracted} <= intended_pairs, (category, seed)
