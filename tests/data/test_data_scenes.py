"""Scenes: several objects, items resting on furniture tops (support), repeated items as instances,
part- and object-level granularity of the same scene."""

import json

import numpy as np

from data_pipeline.build import BuildConfig, run_build, scene_sources
from jax3dc.render import png_array
from tests.data.segmentation_ids import decode_segmentation
from data_pipeline.samples import object_records, split_of
from data_pipeline.scenes import make_scene
from data_pipeline.shards import read_dataset
from jax3dc.palette import object_palette
from jax3dc.structure import parse_structure


def test_scene_structure_and_support_geometry():
    for index in range(3):
        part_scene, object_scene = make_scene(0, index)
        s = part_scene.structure
        roots = s.roots()
        assert len(roots) >= 2 and len(object_scene.parts) == len(roots)
        assert object_scene.structure.roots() == sorted(object_scene.parts)
        for r in s.relations:
            assert r.type == "support" and r.a in roots
            item_bottom = min(part_scene.parts[p].bounds[0, 2] for p in part_scene.parts
                              if _root(s, p) == r.a)
            assert abs(item_bottom - part_scene.parts[r.b].bounds[1, 2]) < 1e-6, "item rests on the part's top"
        # object level keeps the same support pairs, by object
        assert len(object_scene.structure.relations) == len(s.relations)
        lo = np.vstack([m.bounds for m in part_scene.parts.values()])
        assert np.isclose((lo.max(0) - lo.min(0)).max(), 1.0)


def _root(s, p):
    while s.nodes[p].parent is not None:
        p = s.nodes[p].parent
    return p


def test_repeated_items_are_instances_and_scene_renders():
    found_instance = False
    for index in range(6):
        part_scene, object_scene = make_scene(1, index)
        for obj in (part_scene, object_scene):
            (record,) = object_records(obj, 1, 0, 64)
            doc = parse_structure(record.target, part_ids=obj.parts)
            ids = decode_segmentation(png_array(record.seg_png), object_palette("scene", obj.object_id))
            assert set(np.unique(ids).tolist()) - {0} == set(obj.parts) - set(record.meta["hidden_parts"])
            if obj.granularity == "object":
                found_instance |= any(r.type == "instance" for r in doc.relations)
    assert found_instance, "copies of an item should be extracted as instances"


def test_scene_records_in_build_share_split(tmp_path):
    run_build(tmp_path, scene_sources(2, 3), BuildConfig(1, 3, 32, 1), workers=1, progress=False)
    records = list(read_dataset(tmp_path))
    assert sorted(r.meta["granularity"] for r in records) == ["object", "object", "part", "part"]
    assert all(r.meta["split"] == split_of(r.meta["object_id"]) for r in records)
    assert all(json.loads(r.target)["relations"] is not None for r in records)
