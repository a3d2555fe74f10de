"""Related parts articulate alike (jax3dc.physics.relations): hand-built mirrored doors and the
factories' own symmetric and instance pairs."""

from __future__ import annotations

import dataclasses

import pytest
import trimesh

from jax3dc.factories import generate_object
from jax3dc.physics.findings import Finding, describe
from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.physics.relations import relation_disagreements
from jax3dc.physics.tolerances import RELATION_MOTION_TOL_NU
from jax3dc.physics.verdict import check_object
from jax3dc.structure.schema import Joint, Node, Relation, Structure


def _by_joint(found: list[Finding]) -> dict[int, list[Finding]]:
    out: dict[int, list[Finding]] = {}
    for f in found:
        out.setdefault(f.joints[0], []).append(f)
    return out


def _box(lo, hi) -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=[lo, hi])


def _double_door(relation: str = "symmetric"):
    """A carcass (1) and two 0.4-wide doors on its front (2: left, hinged on its left edge; 3:
    right, hinged on its right edge), both opening outwards (towards -y) by up to 1.5 rad."""
    parts = {1: _box([-0.4, -0.3, -0.5], [0.4, 0.3, 0.5]),
             2: _box([-0.4, -0.32, -0.5], [0.0, -0.3, 0.5]),
             3: _box([0.0, -0.32, -0.5], [0.4, -0.3, 0.5]),
             4: _box([-0.4, 0.3, -0.5], [0.4, 0.32, 0.5])}
    nodes = {1: Node(parent=None, material=0),
             2: Node(parent=1, material=0, joint=Joint("hinge", (0.0, 0.0, -1.0), (-0.4, -0.3, 0.0), (0.0, 1.5))),
             3: Node(parent=1, material=0, joint=Joint("hinge", (0.0, 0.0, 1.0), (0.4, -0.3, 0.0), (0.0, 1.5))),
             4: Node(parent=1, material=0)}
    plane = "yz" if relation == "symmetric" else None
    return Structure(materials={}, nodes=nodes, relations=(Relation(relation, 2, 3, plane),)), parts


def _with_joint(structure: Structure, part: int, **changes) -> Structure:
    nodes = dict(structure.nodes)
    nodes[part] = dataclasses.replace(nodes[part], joint=dataclasses.replace(nodes[part].joint, **changes))
    return dataclasses.replace(structure, nodes=nodes)


@pytest.mark.parametrize("relation", ["symmetric", "instance"])
def test_mirrored_doors_agree_and_an_odd_one_is_flagged_on_both(relation):
    structure, parts = _double_door(relation)
    assert relation_disagreements(structure, parts) == []
    flipped = _with_joint(structure, 3, axis=(0.0, 0.0, -1.0))  # the right door opens into the carcass
    found = _by_joint(relation_disagreements(flipped, parts))
    assert set(found) == {2, 3}
    assert found[3][0].check == "relation motion" and found[3][0].parts == (2,) and found[3][0].relation == relation
    assert found[3][0].depth > RELATION_MOTION_TOL_NU
    assert describe(found[3][0]).startswith(f"disagrees with part 2 ({relation}): they move differently")
    farther = _with_joint(structure, 2, range=(0.0, 3.0))
    assert set(_by_joint(relation_disagreements(farther, parts))) == {2, 3}
    slid = _with_joint(structure, 2, type="slide")
    assert [describe(f) for f in _by_joint(relation_disagreements(slid, parts))[2]] == [
        f"disagrees with part 3 ({relation}): a hinge where the other is a slide"]
    # a slightly different range (0.02 rad: under a millimetre at the door's edge) is the same motion
    assert relation_disagreements(_with_joint(structure, 2, range=(0.0, 1.52)), parts) == []
    # the same motion written the other way round: axis flipped, range negated
    assert relation_disagreements(_with_joint(structure, 3, axis=(0.0, 0.0, -1.0), range=(-1.5, 0.0)), parts) == []


def test_a_door_on_an_unrelated_parent_is_flagged_and_a_loose_relation_is_left_alone():
    structure, parts = _double_door()
    nodes = dict(structure.nodes)
    nodes[3] = dataclasses.replace(nodes[3], parent=4)
    found = _by_joint(relation_disagreements(dataclasses.replace(structure, nodes=nodes), parts))
    assert [f.parts for f in found[3]] == [(2, 1, 4)]
    assert [describe(f) for f in found[3]] == ["disagrees with part 2 (symmetric): their parents 1 and 4 differ and are not related"]
    # parts that no translation or mirror carries onto each other: the relation says nothing of their joints
    loose = dict(parts)
    loose[3] = _box([0.0, -0.32, -0.5], [0.3, -0.3, 0.5])
    assert relation_disagreements(_with_joint(structure, 3, axis=(0.0, 0.0, -1.0)), loose) == []


@pytest.mark.parametrize("category,seed", [("cabinet", 1), ("wardrobe", 1), ("window", 0), ("dishwasher", 0)])
def test_factory_pairs_agree_and_their_range_doubled_or_swapped_twins_do_not(category, seed):
    # cabinet doors (symmetric), a wardrobe's sliding doors (instances moving as mirror images), a
    # window's sash beside its fixed pane (an instance pair with one joint), dishwasher racks (instances)
    obj = generate_object(category, seed)
    assert relation_disagreements(obj.structure, obj.parts) == []
    jointed = {p for r in obj.structure.relations for p in (r.a, r.b)
               if all(obj.structure.nodes[q].joint is not None for q in (r.a, r.b))}
    caught = [m for m in mutations_of(obj.structure, obj.parts) if m.part in jointed
              and m.kind in ("range doubled", "hinge-slide swapped")
              and _by_joint(relation_disagreements(m.structure, obj.parts)).get(m.part)]
    assert len(caught) == 2 * len(jointed)


def test_the_verdict_carries_the_reason_for_a_door_doubled_through_free_space():
    obj = generate_object("cabinet", 1)
    door = next(r.a for r in obj.structure.relations if obj.structure.nodes[r.a].joint is not None)
    doubled = next(m for m in mutations_of(obj.structure, obj.parts) if m.kind == "range doubled" and m.part == door)
    reasons = check_object(doubled.structure, obj.parts, obj.scale_m_per_nu, dynamics=False)["joints"][str(door)]["reasons"]
    assert any(r.startswith("disagrees with part") for r in reasons), reasons
