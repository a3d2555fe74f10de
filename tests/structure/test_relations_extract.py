"""Relation extraction on meshes built in the test: mirrored pairs, rows of copies, near misses."""

import numpy as np
import pytest
import trimesh

from jax3dc.relations import (
    MIRROR_TOLERANCE,
    extract_relations,
    principal_extents,
    shape_signature,
    with_extracted_relations,
)
from jax3dc.structure import Material, Node, Relation, Structure


def box(extents, centre, rotation=None):
    mesh = trimesh.creation.box(extents=extents)
    if rotation is not None:
        mesh.apply_transform(rotation)
    mesh.apply_translation(centre)
    return mesh


def flat(parent_of):
    return Structure({0: Material("Wood")}, {i: Node(p, 0) for i, p in parent_of.items()})


def test_mirrored_pair_of_boxes_is_symmetric_with_the_right_plane():
    # body 1 centred at (0.1, 0, 0); doors 2 and 3 mirror across x = 0.1 (the yz plane through it)
    parts = {1: box((1.0, 0.5, 0.8), (0.1, 0.0, 0.0)),
             2: box((0.3, 0.02, 0.7), (-0.15, -0.26, 0.05)),
             3: box((0.3, 0.02, 0.7), (0.35, -0.26, 0.05))}
    rels = extract_relations(flat({1: None, 2: 1, 3: 1}), parts)
    assert rels == (Relation("symmetric", 2, 3, "yz"),)


@pytest.mark.parametrize("k,plane", [(0, "yz"), (1, "xz"), (2, "xy")])
def test_each_principal_plane_through_the_parent_centre(k, plane):
    centre = np.array([0.05, -0.02, 0.1])
    a = np.array([0.3, 0.25, 0.4])
    b = a.copy()
    b[k] = 2 * centre[k] - a[k]
    parts = {1: box((1, 1, 1), centre), 2: box((0.1, 0.2, 0.05), a), 3: box((0.1, 0.2, 0.05), b)}
    assert extract_relations(flat({1: None, 2: 1, 3: 1}), parts) == (Relation("symmetric", 2, 3, plane),)
    # the same pair about a parent centred elsewhere is only an instance pair
    parts[1] = box((1, 1, 1), centre + 0.05)
    assert extract_relations(flat({1: None, 2: 1, 3: 1}), parts) == (Relation("instance", 2, 3),)


def test_reflected_copy_of_an_asymmetric_part_still_matches():
    # an L-shaped bracket and its mirror image across the yz plane through the parent's centre
    bracket = trimesh.util.concatenate([box((0.2, 0.05, 0.05), (0.1, 0, 0)), box((0.05, 0.05, 0.3), (0.0, 0, 0.15))])
    mirrored = bracket.copy()
    mirrored.apply_transform(np.diag([-1.0, 1, 1, 1]))
    bracket.apply_translation((0.3, 0, 0))
    mirrored.apply_translation((-0.3, 0, 0))
    parts = {1: box((1, 1, 0.2), (0, 0, 0)), 2: bracket, 3: mirrored}
    sig2, sig3 = shape_signature(parts[2]), shape_signature(parts[3])
    assert sig2.extents == pytest.approx(sig3.extents)
    assert extract_relations(flat({1: None, 2: 1, 3: 1}), parts) == (Relation("symmetric", 2, 3, "yz"),)


def test_four_equal_shelves_in_a_row_form_an_instance_star():
    # frame 1 centred at the origin; shelves 2..5 at heights not mirrored about its centre
    parts = {1: box((1.0, 0.4, 1.0), (0, 0, 0))}
    for k, z in enumerate((-0.4, -0.15, 0.1, 0.35)):
        parts[k + 2] = box((0.9, 0.35, 0.02), (0, 0, z))
    rels = extract_relations(flat({1: None, 2: 1, 3: 1, 4: 1, 5: 1}), parts)
    assert rels == (Relation("instance", 2, 3), Relation("instance", 2, 4), Relation("instance", 2, 5))


def test_shelves_placed_symmetrically_give_mirror_pairs_inside_the_star():
    parts = {1: box((1.0, 0.4, 1.0), (0, 0, 0))}
    for k, z in enumerate((-0.3, -0.1, 0.1, 0.3)):
        parts[k + 2] = box((0.9, 0.35, 0.02), (0, 0, z))
    rels = set(extract_relations(flat({1: None, 2: 1, 3: 1, 4: 1, 5: 1}), parts))
    assert rels == {Relation("instance", 2, 3), Relation("instance", 2, 4), Relation("instance", 2, 5),
                    Relation("symmetric", 2, 5, "xy"), Relation("symmetric", 3, 4, "xy")}


def test_different_parents_sizes_or_tessellations_do_not_match():
    parts = {1: box((1, 1, 1), (0, 0, 0)), 2: box((0.2, 0.2, 0.2), (0.3, 0, 0)),
             3: box((0.2, 0.2, 0.2), (-0.3, 0, 0)),  # same as 2, but child of 2
             4: box((0.2, 0.2, 0.25), (0.3, 0.3, 0)),  # same parent as 2, other size
             5: trimesh.creation.icosphere(subdivisions=1, radius=0.1).apply_translation((-0.3, 0.3, 0)),
             6: trimesh.creation.icosphere(subdivisions=2, radius=0.1).apply_translation((0.3, -0.3, 0))}
    assert extract_relations(flat({1: None, 2: 1, 3: 2, 4: 1, 5: 1, 6: 1}), parts) == ()


def test_rotated_copy_is_an_instance():
    angle = 0.7
    rotation = trimesh.transformations.rotation_matrix(angle, (0, 0, 1))
    parts = {1: box((1, 1, 0.1), (0, 0, 0)),
             2: box((0.3, 0.1, 0.05), (0.2, 0.1, 0.1)),
             3: box((0.3, 0.1, 0.05), (-0.25, 0.2, 0.1), rotation)}
    assert extract_relations(flat({1: None, 2: 1, 3: 1}), parts) == (Relation("instance", 2, 3),)


def test_roots_mirror_about_the_scene_centre():
    parts = {1: box((0.2, 0.2, 0.4), (-0.4, 0.1, 0)), 2: box((0.2, 0.2, 0.4), (0.4, 0.1, 0)),
             3: box((0.2, 0.2, 0.4), (0.0, -0.3, 0))}
    # 1 and 2 mirror across x = 0; the pairs 1-3 and 2-3 are instances, which join {1, 2, 3} into
    # one instance group written as a star at 1
    assert extract_relations(flat({1: None, 2: None, 3: None}), parts) == (
        Relation("instance", 1, 2), Relation("instance", 1, 3), Relation("symmetric", 1, 2, "yz"))


def test_mirror_tolerance_is_respected():
    offset = MIRROR_TOLERANCE * 1.5
    parts = {1: box((1, 1, 1), (0, 0, 0)), 2: box((0.1, 0.1, 0.1), (0.3, 0, 0)),
             3: box((0.1, 0.1, 0.1), (-0.3 + offset, 0, 0))}
    assert extract_relations(flat({1: None, 2: 1, 3: 1}), parts) == (Relation("instance", 2, 3),)
    parts[3] = box((0.1, 0.1, 0.1), (-0.3 + MIRROR_TOLERANCE * 0.5, 0, 0))
    assert extract_relations(flat({1: None, 2: 1, 3: 1}), parts) == (Relation("symmetric", 2, 3, "yz"),)


def test_principal_extents_ignore_rotation():
    rng = np.random.default_rng(0)
    points = rng.normal(size=(200, 3)) * [0.5, 0.2, 0.1]
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    np.testing.assert_allclose(principal_extents(points), principal_extents(points @ q.T + 3.0), atol=1e-9)


def test_with_extracted_relations_keeps_support_and_replaces_the_rest():
    parts = {1: box((1, 1, 1), (0, 0, 0)), 2: box((0.1, 0.1, 0.1), (0.3, 0, 0)),
             3: box((0.1, 0.1, 0.1), (-0.3, 0, 0)), 4: box((0.5, 0.5, 0.1), (0, 0, -0.6))}
    s = Structure({0: Material("Wood")}, {1: Node(None, 0), 2: Node(1, 0), 3: Node(1, 0), 4: Node(None, 0)},
                  (Relation("support", 1, 4), Relation("instance", 1, 4)))
    out = with_extracted_relations(s, parts)
    assert out.relations == (Relation("support", 1, 4), Relation("symmetric", 2, 3, "yz"))
    assert out.nodes == s.nodes


def test_translated_cubes_and_cylinders_always_match():
    # shapes with equal second moments: their principal axes must not be decided by float noise
    from jax3dc.relations import same_design

    rng = np.random.default_rng(1)
    for shape in (trimesh.creation.box(extents=(0.1, 0.1, 0.1)), trimesh.creation.cylinder(0.05, 0.3, sections=32)):
        base = shape_signature(shape)
        for offset in rng.uniform(-0.5, 0.5, size=(20, 3)):
            moved = shape.copy()
            moved.apply_translation(offset)
            assert same_design(base, shape_signature(moved)), offset
        mirrored = shape.copy()
        mirrored.apply_transform(np.diag([1.0, -1, 1, 1]))
        assert same_design(base, shape_signature(mirrored))
