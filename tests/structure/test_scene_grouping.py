"""Scene grouping: parent edges between separate objects are cut from the legend boxes, while a
single tree, parts without boxes and the model's joints inside an object are left alone, and a
valid structure never comes out invalid."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from data_pipeline.scenes import make_scene
from jax3dc.geometry.parts import part_boxes
from jax3dc.structure import Box, Joint, Material, Node, Relation, Structure, parse_structure, to_json, validate
from jax3dc.structure.scene_grouping import object_groups, regroup, regroup_text, stands_apart

HINGE = Joint("hinge", (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 1.0))


def box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> Box:
    return Box(tuple((a + b) / 2 for a, b in zip(lo, hi)), tuple(b - a for a, b in zip(lo, hi)))


def structure(parents: dict[int, int | None], joints: dict[int, Joint] | None = None) -> Structure:
    joints = joints or {}
    return Structure({0: Material("Wood")}, {p: Node(q, 0, joints.get(p)) for p, q in parents.items()})


def groups(s: Structure) -> list[list[int]]:
    return sorted(sorted(s.subtree(r)) for r in s.roots())


# A table (top 1 on legs 2, 3) with a kettle (body 4, lid 5) on its top, and a bucket 6 on the floor.
TABLE_SCENE = {
    1: box((-0.5, -0.2, 0.00), (0.2, 0.2, 0.05)),
    2: box((-0.5, -0.2, -0.5), (-0.45, 0.2, 0.00)),
    3: box((0.15, -0.2, -0.5), (0.2, 0.2, 0.00)),
    4: box((-0.3, -0.1, 0.05), (-0.1, 0.1, 0.30)),
    5: box((-0.25, -0.05, 0.30), (-0.15, 0.05, 0.33)),
    6: box((0.3, -0.1, -0.5), (0.5, 0.1, -0.2)),
}


def test_an_item_wired_to_the_table_it_stands_on_becomes_its_own_object_and_keeps_its_lid() -> None:
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4, 6: None}, {5: HINGE})
    out = regroup(s, TABLE_SCENE)
    assert groups(out) == [[1, 2, 3], [4, 5], [6]]
    assert out.nodes[4].parent is None and out.nodes[4].joint is None
    assert out.nodes[5] == s.nodes[5]  # the model's joint inside the kettle is kept


def test_a_rigid_lid_stays_with_its_item_and_a_cut_part_hangs_from_its_own_object() -> None:
    # The lid was wired, with its hinge, to the bucket on the floor: it is cut from there and hung,
    # joint and all, from the kettle (the nearest part of its own object).
    s = structure({1: None, 2: 1, 3: 1, 4: None, 5: 6, 6: None}, {5: HINGE})
    out = regroup(s, TABLE_SCENE)
    assert groups(out) == [[1, 2, 3], [4, 5], [6]]
    assert out.nodes[5] == Node(4, 0, HINGE)


def test_one_tree_is_left_as_written_even_when_the_geometry_shows_several_objects() -> None:
    # The table and the kettle on it: one body, nothing else on the floor. A single object looks
    # the same (a kettle's lid on its body, cushions on a sofa), so one tree stays one tree.
    boxes = {k: TABLE_SCENE[k] for k in (1, 2, 3, 4, 5)}
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4})
    assert len(object_groups(boxes)) == 2 and not stands_apart(boxes)
    assert regroup(s, boxes) is s
    text = to_json(s)
    assert regroup_text(text, boxes) == text


def test_one_tree_over_two_bodies_standing_on_the_floor_is_a_scene() -> None:
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4, 6: 5}, {5: HINGE})
    assert stands_apart(TABLE_SCENE)
    out = regroup(s, TABLE_SCENE)
    assert groups(out) == [[1, 2, 3], [4, 5], [6]]
    assert out.nodes[5] == s.nodes[5]


def test_a_single_object_with_a_lifted_lid_or_a_hanging_tray_is_never_split() -> None:
    # A box on the floor with its lid lifted clear above it, and a desk (top on two legs) with a
    # tray hanging clear under its top: separate bodies, but only one of them stands on the floor.
    lidded = {1: box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.3)), 2: box((-0.5, -0.5, 0.4), (0.5, 0.5, 0.45))}
    desk = {**{k: TABLE_SCENE[k] for k in (1, 2, 3)}, 4: box((-0.3, -0.2, -0.1), (0.0, 0.15, -0.03))}
    for boxes, parents in ((lidded, {1: None, 2: 1}), (desk, {1: None, 2: 1, 3: 1, 4: 1})):
        s = structure(parents)
        assert len(object_groups(boxes)) == 2 and not stands_apart(boxes)
        assert regroup(s, boxes) is s


def test_one_part_and_no_boxes() -> None:
    one = structure({1: None})
    assert regroup(one, {1: TABLE_SCENE[1]}) is one
    assert object_groups({}) == []
    two = structure({1: None, 2: None})
    assert regroup(two, {}) is two


def test_parts_that_all_touch_are_one_object_and_the_models_roots_are_joined() -> None:
    # A cabinet whose door the model wrote as a second object: the boxes touch, so it is one object.
    boxes = {1: box((-0.5, -0.3, -0.5), (0.5, 0.3, 0.5)), 2: box((-0.5, -0.32, -0.5), (0.0, -0.3, 0.5))}
    assert object_groups(boxes) == [[1, 2]]
    out = regroup(structure({1: None, 2: None}), boxes)
    assert groups(out) == [[1, 2]] and out.nodes[2] == Node(1, 0)


def test_identical_items_in_a_row_are_separate_objects() -> None:
    boxes = {i: box((0.3 * i, -0.1, -0.5), (0.3 * i + 0.2, 0.1, -0.2)) for i in range(1, 5)}
    s = structure({1: None, 2: 1, 3: 2, 4: None})
    assert groups(regroup(s, boxes)) == [[1], [2], [3], [4]]


def test_parts_without_boxes_follow_their_parent() -> None:
    boxes = {k: v for k, v in TABLE_SCENE.items() if k != 5}
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4, 6: None})
    out = regroup(s, boxes)
    assert groups(out) == [[1, 2, 3], [4, 5], [6]]
    # a box-less root is its own object, never attached anywhere
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: None, 6: 1})
    assert groups(regroup(s, boxes)) == [[1, 2, 3], [4], [5], [6]]


def test_a_knob_on_a_stove_top_is_not_an_item() -> None:
    boxes = {1: box((-0.5, -0.3, -0.5), (0.5, 0.3, 0.4)), 2: box((-0.1, -0.05, 0.4), (0.0, 0.05, 0.412)),
             3: box((0.6, -0.1, -0.5), (0.8, 0.1, -0.3))}
    assert object_groups(boxes) == [[1, 2], [3]]


@pytest.mark.parametrize("index", [0, 9, 12])
def test_a_built_scene_with_its_objects_wired_together_gets_them_back(index: int) -> None:
    scene = make_scene(0, index)[0]
    boxes = {p: Box(tuple(round(v, 3) for v in b.centroid), tuple(round(v, 3) for v in b.extent))
             for p, b in part_boxes(scene.parts).items()}
    ref = scene.structure
    roots = ref.roots()
    assert len(roots) >= 3
    # every object but the first two wired rigidly under the first one's root: the model's failure
    wired = replace(ref, nodes={p: replace(n, parent=roots[0]) if p in roots[2:] else n for p, n in ref.nodes.items()})
    assert groups(regroup(wired, boxes)) == groups(ref)
    assert regroup(ref, boxes) == ref


def test_a_valid_structure_never_becomes_invalid() -> None:
    rng = np.random.default_rng(7)
    for _ in range(200):
        n = int(rng.integers(1, 12))
        lo = rng.uniform(-0.5, 0.4, size=(n, 3)).round(3)
        hi = (lo + rng.uniform(0.0, 0.3, size=(n, 3))).round(3)
        boxes = {i + 1: box(tuple(lo[i]), tuple(hi[i])) for i in range(n) if rng.random() < 0.9}
        parents: dict[int, int | None] = {}
        for i in range(1, n + 1):
            parents[i] = int(rng.integers(1, i)) if i > 1 and rng.random() < 0.7 else None
        joints = {i: HINGE for i in parents if parents[i] is not None and rng.random() < 0.4}
        s = structure(parents, joints)
        if n > 1 and rng.random() < 0.5:  # the support cue opens one tree to regrouping too
            a, b = (int(v) for v in rng.choice(np.arange(1, n + 1), size=2, replace=False))
            s = replace(s, relations=(Relation("support", a, b),))
        out = regroup(s, boxes)
        assert validate(json.loads(to_json(out)), part_ids=range(1, n + 1)) == []
        assert regroup(out, boxes) == out  # applying it twice changes nothing more
        legend = {i: boxes.get(i, Box((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))) for i in range(1, n + 1)}
        assert parse_structure(regroup_text(to_json(s), legend), part_ids=range(1, n + 1))


def test_a_text_that_is_not_a_valid_document_passes_through() -> None:
    for text in ("", "not json", '{"nodes": {"1": {"parent": 2}}}', to_json(structure({1: None, 2: None}))[:-3]):
        assert regroup_text(text, TABLE_SCENE) == text


@pytest.mark.parametrize("grouping", [True, False])
def test_the_sampler_regroups_what_the_model_wrote_unless_told_not_to(monkeypatch, grouping: bool) -> None:
    """The one decode path of eval run and predict: a reply that wires the kettle to the table comes
    back with the kettle as its own object (and untouched with scene_grouping off)."""
    import io
    from types import SimpleNamespace

    from PIL import Image

    import jax3dc.sampler as sampler_module
    from jax3dc.prompt import LEGEND_HEADER, legend_line
    from jax3dc.sampler import DecodeOptions, Prompt, Sampler
    from jax3dc.structure.box_frame import PivotFrame

    reply = to_json(structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4, 6: None}, {5: HINGE}))
    png = io.BytesIO()
    Image.new("RGB", (32, 32)).save(png, format="PNG")
    prompt_text = "\n".join([LEGEND_HEADER] + [legend_line(p, (10, 20, 30), b) for p, b in TABLE_SCENE.items()])
    record = SimpleNamespace(key="scene", image_png=png.getvalue(), seg_png=png.getvalue(), prompt=prompt_text)
    special = SimpleNamespace(endoftext=0, stop_ids=(1,))
    tokenizer = SimpleNamespace(special=special, decode=lambda ids: reply + ("<stop>" if ids[-1:] == [1] else ""))
    config = SimpleNamespace(text=SimpleNamespace(max_position_embeddings=64, vocab_size=8))
    monkeypatch.setattr(sampler_module, "preprocess_images",
                        lambda images, processor: SimpleNamespace(pixel_values=np.zeros((1, 1)),
                                                                  image_grid_thw=np.ones((1, 3), dtype=np.int64)))
    monkeypatch.setattr(sampler_module, "prefill", lambda *args, **kwargs: None)
    monkeypatch.setattr(sampler_module, "decode", lambda *args, **kwargs: SimpleNamespace(
        tokens=np.array([[5, 1]]), lengths=np.array([2]), logprobs=np.array([0.0])))
    sampler = Sampler(None, config, tokenizer, None, PivotFrame())
    sample = sampler.generate_batch([Prompt("scene", np.array([3, 4]), record)], 1, 2, 1,
                                    DecodeOptions(constrained=False, scene_grouping=grouping))[0][0]
    written = parse_structure(sample.reply, part_ids=TABLE_SCENE)
    assert groups(written) == ([[1, 2, 3], [4, 5], [6]] if grouping else [[1, 2, 3, 4, 5], [6]])
    assert sample.text == sample.reply + "<stop>"


def test_a_fans_head_on_its_stand_beside_a_table_is_not_an_item() -> None:
    # Stand 7 and head 8 of a fan on the floor: the head stands inside the stand's top face as an
    # item would, but what holds it is far lower than the table a real item stands on.
    boxes = {**{k: TABLE_SCENE[k] for k in (1, 2, 3)}, 7: box((0.3, -0.1, -0.5), (0.5, 0.1, -0.4)),
             8: box((0.35, -0.05, -0.4), (0.45, 0.05, -0.3))}
    assert object_groups(boxes) == [[1, 2, 3], [7, 8]]
    s = structure({1: None, 2: 1, 3: 1, 7: 1, 8: None})
    assert groups(regroup(s, boxes)) == [[1, 2, 3], [7, 8]]


def test_an_item_whose_base_is_thinner_than_the_contact_tolerance_is_cut_at_its_base() -> None:
    # A stapler (base 4, arm 5, top 6) on the table top 1, its base 0.004 nu thick: the cut is at
    # the table top, not at the stapler's own base (which would leave the base on the table).
    boxes = {**{k: TABLE_SCENE[k] for k in (1, 2, 3)}, 4: box((-0.30, -0.02, 0.050), (-0.286, 0.02, 0.054)),
             5: box((-0.298, 0.014, 0.053), (-0.288, 0.02, 0.056)),
             6: box((-0.299, -0.02, 0.057), (-0.287, 0.02, 0.065))}
    assert object_groups(boxes) == [[1, 2, 3], [4, 5, 6]]
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4, 6: None})
    assert groups(regroup(s, boxes)) == [[1, 2, 3], [4, 5, 6]]


SLIDE = Joint("slide", (0.0, 1.0, 0.0), (0.0, 0.0, 0.0), (-0.2, 0.0))


def test_a_joint_keeps_a_tray_hanging_under_the_desk_top_but_not_a_cabinet_standing_beside_it() -> None:
    # Desk top 1 on legs 2, 3; tray 4 hangs 0.03 nu under the top; cabinet 5 stands 0.03 nu beside
    # the desk; a second tree (bucket 6) says the model read a scene.
    boxes = {**{k: TABLE_SCENE[k] for k in (1, 2, 3, 6)}, 4: box((-0.3, -0.2, -0.1), (0.0, 0.15, -0.03)),
             5: box((0.23, -0.2, -0.5), (0.28, 0.2, 0.05))}
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 1, 6: None}, {4: SLIDE, 5: SLIDE})
    out = regroup(s, boxes)
    assert groups(out) == [[1, 2, 3, 4], [5], [6]]
    assert out.nodes[4] == s.nodes[4] and out.nodes[5].parent is None


def test_one_tree_with_a_support_relation_between_two_objects_is_a_scene() -> None:
    # The table and the kettle on it (one body, nothing else on the floor): the model's own
    # "kettle rests on the table" says it read a scene; the same relation inside the table does not.
    boxes = {k: TABLE_SCENE[k] for k in (1, 2, 3, 4, 5)}
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4})
    rests = replace(s, relations=(Relation("support", 4, 1),))
    assert groups(regroup(rests, boxes)) == [[1, 2, 3], [4, 5]]
    inside = replace(s, relations=(Relation("support", 2, 1),))
    assert regroup(inside, boxes) is inside


def test_a_cut_joint_on_an_objects_largest_part_never_takes_the_joint_of_another_part() -> None:
    # A cabinet 7 beside the table, wired with a slide to the table top, and its drawer 8 with its
    # own slide on the cabinet: the cabinet heads its object, the drawer keeps its slide.
    drawer = Joint("slide", (0.0, 1.0, 0.0), (0.5, -0.2, -0.3), (-0.1, 0.0))
    boxes = {**{k: TABLE_SCENE[k] for k in (1, 2, 3)}, 7: box((0.3, -0.2, -0.5), (0.7, 0.2, 0.0)),
             8: box((0.35, -0.22, -0.4), (0.65, -0.2, -0.2))}
    s = structure({1: None, 2: 1, 3: 1, 7: 1, 8: 7}, {7: SLIDE, 8: drawer})
    out = regroup(s, boxes)
    assert groups(out) == [[1, 2, 3], [7, 8]]
    assert out.nodes[7] == Node(None, 0) and out.nodes[8] == s.nodes[8]


def test_no_procedural_single_object_is_ever_split() -> None:
    """Three objects of every factory, written as their own one tree: left exactly as written,
    though geometry alone cuts some of them (a kettle's lid, a fan's head, a desk's tray)."""
    from data_pipeline.samples import factory_source
    from jax3dc.factories import FACTORIES

    cut_by_geometry = 0
    for category in FACTORIES:
        for seed in range(3):
            source = factory_source(category, seed)
            boxes = {p: Box(tuple(round(v, 3) for v in b.centroid), tuple(round(v, 3) for v in b.extent))
                     for p, b in part_boxes(source.parts).items()}
            cut_by_geometry += len(object_groups(boxes)) > 1
            assert not stands_apart(boxes), (category, seed)
            assert regroup(source.structure, boxes) is source.structure, (category, seed)
    assert cut_by_geometry >= 10  # the case the gate is there for is really exercised


def test_one_tree_over_a_scene_with_a_part_missing_from_the_legend() -> None:
    boxes = {k: v for k, v in TABLE_SCENE.items() if k != 5}  # the kettle's lid has no box
    s = structure({1: None, 2: 1, 3: 1, 4: 1, 5: 4, 6: 5}, {5: HINGE})
    out = regroup(s, boxes)
    assert groups(out) == [[1, 2, 3], [4, 5], [6]]  # the lid follows its parent, the bucket is cut
    assert validate(json.loads(to_json(out)), part_ids=range(1, 7)) == []


def test_a_joint_keeps_a_lifted_lid_and_a_door_with_clearance_on_a_single_object_written_as_two_trees() -> None:
    # A chest 1 with its lid 2 lifted 0.03 above it and its door 3 hanging 0.008 in front of it,
    # both on hinges; the model wrote the handle 4 (touching the door) as a second tree.
    boxes = {1: box((-0.5, -0.3, -0.5), (0.5, 0.3, 0.3)), 2: box((-0.5, -0.3, 0.33), (0.5, 0.3, 0.36)),
             3: box((-0.4, -0.33, -0.4), (0.4, -0.308, 0.2)), 4: box((0.3, -0.36, -0.1), (0.35, -0.33, 0.0))}
    s = structure({1: None, 2: 1, 3: 1, 4: None}, {2: HINGE, 3: HINGE})
    out = regroup(s, boxes)
    assert groups(out) == [[1, 2, 3, 4]]
    assert out.nodes[2] == s.nodes[2] and out.nodes[3] == s.nodes[3] and out.nodes[4] == Node(3, 0)
