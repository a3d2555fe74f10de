"""The mirror augmentation and per-view palettes: the mirrored answer is the mirrored motion."""

import numpy as np
import pytest

from data_pipeline.build import BuildConfig, SourceSpec, config_doc, spec_records
from data_pipeline.mirror import mirrored
from data_pipeline.record_parts import record_parts
from data_pipeline.samples import SourceObject, object_records
from data_pipeline.views import joint_transform
from jax3dc.factories import generate_object
from jax3dc.render import png_array
from jax3dc.structure import parse_structure
from tests.data.segmentation_ids import decode_segmentation
from jax3dc.palette import object_palette

FLIP = np.diag([-1.0, 1.0, 1.0, 1.0])


def source(category: str) -> SourceObject:
    g = generate_object(category, 0)
    return SourceObject(g.category, g.object_id, g.structure, g.parts, g.scale_m_per_nu, g.program_text)


@pytest.mark.parametrize("category", ["microwave", "drawer_chest", "faucet"])
def test_every_joint_moves_the_mirrored_part_as_the_mirror_of_the_original_motion(category):
    obj = source(category)
    out = mirrored(obj)
    assert out.augmentation == "mirror" and out.program is None
    joints = obj.structure.joints()
    assert joints
    for pid, joint in joints.items():
        mj = out.structure.nodes[pid].joint
        assert mj.type == joint.type and mj.range == joint.range
        theta = 0.5 * (joint.range[0] + joint.range[1]) or 0.3
        points = np.c_[np.asarray(obj.parts[pid].vertices[:50]), np.ones(min(50, len(obj.parts[pid].vertices)))]
        original_then_flip = (FLIP @ joint_transform(joint, theta) @ points.T).T
        flip_then_mirrored = (joint_transform(mj, theta) @ FLIP @ points.T).T
        np.testing.assert_allclose(flip_then_mirrored, original_then_flip, atol=1e-9)


def test_mirrored_meshes_keep_outward_faces_and_swap_sides():
    obj = source("cabinet")
    out = mirrored(obj)
    for pid, mesh in obj.parts.items():
        np.testing.assert_allclose(out.parts[pid].bounds[:, 0], -mesh.bounds[::-1, 0])
        if mesh.is_volume:
            assert out.parts[pid].volume == pytest.approx(mesh.volume)  # not negative: faces reversed


def test_palette_per_view_changes_colours_between_views_and_stays_consistent_within_one():
    obj = source("microwave")
    plain = object_records(obj, 2, 0, 48)
    varied = object_records(obj, 2, 0, 48, palette_per_view=True)
    assert [r.target for r in plain] == [r.target for r in varied]  # colours change, the answer does not
    assert plain[0].prompt != varied[0].prompt
    assert varied[0].prompt != varied[1].prompt  # the legend's colours differ between views
    for record in varied:
        palette = object_palette(obj.category, record.meta["palette_key"])
        ids = decode_segmentation(png_array(record.seg_png), palette)
        assert set(np.unique(ids)) - {0} <= set(obj.parts)  # S is painted with the legend's palette


def test_a_mirrored_record_rebuilds_its_parts_and_parses():
    config = BuildConfig(views=2, seed=0, size=32, objects_per_shard=1, mirror=True)
    spec = SourceSpec("factory", "microwave_000000", category="microwave", seed=0)
    records = list(spec_records(spec, "train", config))
    mirrors = [r for r in records if r.meta["augmentation"] == "mirror"]
    assert len(mirrors) == 2 and len(records) == 4
    for record in mirrors:
        parse_structure(record.target, part_ids=record_parts(record)[0])


def test_manifest_leaves_out_flags_that_are_off():
    doc = config_doc(BuildConfig(views=1, seed=0, size=32, objects_per_shard=1))
    assert "mirror" not in doc and "palette_per_view" not in doc
    assert config_doc(BuildConfig(views=1, seed=0, size=32, objects_per_shard=1, mirror=True))["mirror"] is True
