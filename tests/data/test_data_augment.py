"""Split and merge augmentations: structure stays valid, S re-rendered with the new part set."""

import pytest

from data_pipeline.augment import fuse_handles, joints_match, merge_parts, split_part
from data_pipeline.build import BuildConfig, factory_sources, run_build
from jax3dc.factories import generate_object
from jax3dc.render import png_array
from tests.data.segmentation_ids import decode_segmentation
from data_pipeline.samples import SourceObject, derived_rng, factory_source, object_records
from data_pipeline.shards import read_dataset
from jax3dc.palette import object_palette
from jax3dc.structure import parse_structure


def source(category):
    g = generate_object(category, 0)
    return SourceObject(g.category, g.object_id, g.structure, g.parts, g.scale_m_per_nu, g.program_text)


def test_split_makes_sibling_with_same_joint_and_same_surface():
    obj = source("microwave")
    out = split_part(obj, derived_rng(0))
    pid = int(out.augmentation.split("-")[1])
    new = max(out.parts)
    assert new == max(obj.parts) + 1
    assert out.structure.nodes[new].parent == obj.structure.nodes[pid].parent
    assert out.structure.nodes[new].joint == obj.structure.nodes[pid].joint is not None
    area = out.parts[pid].area + out.parts[new].area
    assert area == pytest.approx(obj.parts[pid].area, rel=1e-6)
    (record,) = object_records(out, 1, 0, 64)
    parse_structure(record.target, part_ids=out.parts)
    ids = decode_segmentation(png_array(record.seg_png), object_palette(obj.category, obj.object_id))
    assert ids.max() <= new


def test_merge_joins_compatible_leaves_and_keeps_ids_dense():
    obj = source("drawer_chest")
    out = merge_parts(obj, derived_rng(0))
    assert sorted(out.parts) == list(range(1, len(obj.parts)))
    keep, gone = (int(v) for v in out.augmentation.split("-")[1:])
    assert joints_match(obj.structure.nodes[keep].joint, obj.structure.nodes[gone].joint)
    merged = out.parts[keep - (keep > gone)]
    assert len(merged.faces) == len(obj.parts[keep].faces) + len(obj.parts[gone].faces)
    (record,) = object_records(out, 1, 0, 64)
    parse_structure(record.target, part_ids=out.parts)


def test_joints_match_tolerates_only_small_differences():
    g = generate_object("cabinet", 0)
    a, b = list(g.structure.joints().values())
    assert joints_match(a, a) and joints_match(None, None)
    assert not joints_match(a, None) and not joints_match(a, b)


def test_build_with_augment_adds_variant_records(tmp_path):
    run_build(tmp_path, factory_sources(2, 9), BuildConfig(1, 9, 32, 2, augment=True), workers=1, progress=False)
    records = list(read_dataset(tmp_path))
    augs = [r.meta["augmentation"] for r in records if r.meta["augmentation"]]
    assert augs and len({r.key for r in records}) == len(records)
    for r in records:
        base = next(x for x in records if x.meta["object_id"] == r.meta["object_id"])
        assert r.meta["split"] == base.meta["split"]


def test_fuse_puts_handles_into_the_parts_they_sit_on():
    """A cabinet's handles (rigid leaves of its doors and drawer) become part of those meshes: the
    surface is kept, ids stay 1..N and every joint still moves the same geometry."""
    obj = factory_source("cabinet", 3)
    fused = fuse_handles(obj)
    s, f = obj.structure, fused.structure
    handles = [p for p, n in s.nodes.items() if n.name == "handle"]
    assert handles and sorted(f.nodes) == list(range(1, len(s.nodes) - len(handles) + 1))
    assert not any(n.name == "handle" for n in f.nodes.values())
    assert sum(len(m.faces) for m in fused.parts.values()) == sum(len(m.faces) for m in obj.parts.values())
    assert sorted(j.pivot for j in f.joints().values()) == sorted(j.pivot for j in s.joints().values())
    for pid, node in f.nodes.items():
        if node.name in ("door", "drawer"):
            old = next(p for p, n in s.nodes.items() if n.joint == node.joint)
            expected = len(obj.parts[old].faces) + sum(len(obj.parts[c].faces) for c in s.children(old))
            assert len(fused.parts[pid].faces) == expected
    assert fused.augmentation == "fuse" and fused.program is None
    assert fuse_handles(fused) is None  # nothing left to fuse
