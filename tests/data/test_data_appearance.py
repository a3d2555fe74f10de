"""The --appearance switch: "plain" renders exactly as before; "varied" changes I, never S."""

import hashlib
import json

import numpy as np
import pytest
import trimesh

from data_pipeline.build import BuildConfig, config_doc, factory_sources, run_build
from jax3dc.factories import generate_object
from jax3dc.render import (FOVY_RANGE, Camera, Lighting, PartRenderer, paint_segmentation,
                           part_rgba, png_array, png_bytes, sample_appearance, sample_camera, sample_lighting,
                           sample_view_lighting, scene_xml)
from data_pipeline.samples import SourceObject, derived_rng, object_records
from data_pipeline.shards import load_manifest, read_dataset
from tests.data.segmentation_ids import decode_segmentation
from data_pipeline.views import move_joint, sample_view_pose
from jax3dc.errors import InputFileError
from jax3dc.palette import BACKGROUND_RGB, object_palette

SIZE = 64
# sha256 of the plain scene_xml of two boxes, computed with the renderer before "varied" existed
PLAIN_XML_SHA256 = "6bf2f4e4528c7e10bc27dadf53bac8df4e48ceec65b13683f1a5194cb2cf8c10"


def source(category: str, seed: int = 0) -> SourceObject:
    g = generate_object(category, seed)
    return SourceObject(g.category, g.object_id, g.structure, g.parts, g.scale_m_per_nu, g.program_text)


def camera_of(record) -> Camera:
    doc = dict(record.meta["camera"])
    return Camera(lookat=tuple(doc.pop("lookat")), **doc)


def test_plain_scene_xml_is_unchanged():
    a = trimesh.creation.box(extents=(0.4, 0.3, 0.2))
    b = trimesh.creation.box(extents=(0.1, 0.1, 0.5))
    b.apply_translation((0.25, 0.0, 0.1))
    xml = scene_xml({1: a, 2: b}, {1: (0.6, 0.5, 0.4, 1.0), 2: (0.1, 0.2, 0.3, 0.35)},
                    Lighting(ambient=0.3, headlight=0.5, key_dir=(0.3, 0.4, -0.8), key_strength=0.4), SIZE)
    assert hashlib.sha256(xml.encode()).hexdigest() == PLAIN_XML_SHA256


def test_plain_records_are_the_pipeline_before_the_switch():
    """object_records(..., "plain") (and the default) draw and render exactly as the code before
    the switch did: this replays that code (one generator: colours, lighting, then per view pose
    and camera) and compares the PNG bytes."""
    obj = source("cabinet")
    records = object_records(obj, views=2, seed=3, size=SIZE)
    assert [r.image_png for r in records] == [r.image_png for r in
                                              object_records(obj, views=2, seed=3, size=SIZE, appearance="plain")]
    rng = derived_rng(3, obj.category, obj.object_id, "")
    palette = object_palette(obj.category, obj.object_id)
    renderer = PartRenderer(obj.parts, part_rgba(obj.structure, rng), sample_lighting(rng), SIZE)
    try:
        for view, record in enumerate(records):
            posed = sample_view_pose(obj.structure, obj.parts, view, rng)
            lo = np.min([m.bounds[0] for m in posed.parts.values()], axis=0)
            hi = np.max([m.bounds[1] for m in posed.parts.values()], axis=0)
            camera = sample_camera(rng, centre=(lo + hi) / 2.0, radius=float(np.linalg.norm(hi - lo)) / 2.0)
            rgb, ids = renderer.render(posed.poses, camera)
            assert png_bytes(rgb) == record.image_png
            assert png_bytes(paint_segmentation(ids, palette)) == record.seg_png
            assert record.meta["camera"] == camera.to_dict() and "fovy" not in record.meta["camera"]
            assert "appearance" not in record.meta
    finally:
        renderer.close()


def test_varied_changes_i_but_not_s_pose_or_legend():
    objects = [source("cabinet", 1), source("kettle", 2)]
    images = set()
    for obj in objects:
        plain = object_records(obj, views=2, seed=4, size=SIZE)
        varied = object_records(obj, views=2, seed=4, size=SIZE, appearance="varied")
        palette = object_palette(obj.category, obj.object_id)
        for p, v in zip(plain, varied):
            images.add(v.image_png)
            assert v.image_png != p.image_png
            image, seg = png_array(v.image_png), png_array(v.seg_png)
            ids = decode_segmentation(seg, palette)  # raises on any colour outside the palette
            assert (image[ids == 0] != BACKGROUND_RGB).any(), "the varied background is not the plain black"
            assert (ids > 0).mean() > 0.01
            border = np.concatenate([ids[0], ids[-1], ids[:, 0], ids[:, -1]])
            assert not border.any(), "the whole object stays in frame"
            # same pose, parts, legend and target; only the camera's distance / fovy and the look differ
            assert (v.key, v.prompt, v.target, v.program) == (p.key, p.prompt, p.target, p.program)
            pm, vm = dict(p.meta), dict(v.meta)
            assert vm.pop("appearance") == "varied"
            pc, vc = pm.pop("camera"), vm.pop("camera")
            pm.pop("hidden_parts"), vm.pop("hidden_parts")  # a zoomed camera may see other parts
            assert pm == vm
            assert (vc["azimuth"], vc["elevation"], vc["lookat"]) == (pc["azimuth"], pc["elevation"], pc["lookat"])
            assert FOVY_RANGE[0] <= vc["fovy"] <= FOVY_RANGE[1]
        # the camera in the meta is the camera S was rendered with: a plain renderer agrees exactly
        rest = varied[0]
        renderer = PartRenderer(obj.parts, part_rgba(obj.structure, derived_rng(0)), sample_lighting(derived_rng(0)), SIZE)
        try:
            ids = renderer.render({}, camera_of(rest))[1]
        finally:
            renderer.close()
        assert png_bytes(paint_segmentation(ids, palette)) == rest.seg_png
    assert len(images) == 4


def test_varied_renderer_gives_the_plain_part_ids_for_moved_joints_and_any_fovy():
    g = generate_object("drawer_chest", 3)
    rng = derived_rng("appearance-test")
    plain = PartRenderer(g.parts, {p: (0.5, 0.5, 0.5, 1.0) for p in g.parts}, sample_lighting(rng), SIZE)
    varied = PartRenderer(g.parts, {}, None, SIZE, sample_appearance(g.structure, rng))
    try:
        for k, (pid, joint) in enumerate(sorted(g.structure.joints().items())[:3]):
            posed = move_joint(g.structure, g.parts, pid, 0.7 * joint.range[1] + 0.3 * joint.range[0])
            camera = Camera((0.0, 0.0, 0.0), 2.2 + 0.3 * k, 60.0 + 25 * k, -12.0 - 9 * k, fovy=35.0 + 10 * k)
            rgb_p, ids_p = plain.render(posed.poses, camera)
            rgb_v, ids_v = varied.render(posed.poses, camera, sample_view_lighting(rng))
            np.testing.assert_array_equal(ids_v, ids_p)
            assert (ids_p > 0).any() and not np.array_equal(rgb_v, rgb_p)
    finally:
        plain.close()
        varied.close()


def test_varied_build_is_deterministic_whatever_the_workers(tmp_path):
    sources = factory_sources(4, 5)
    config = BuildConfig(views=1, seed=5, size=48, objects_per_shard=2, appearance="varied")
    run_build(tmp_path / "a", sources, config, workers=1, progress=False)
    run_build(tmp_path / "b", sources, config, workers=2, progress=False)
    shards = sorted(p.name for p in (tmp_path / "a").glob("*.array_record"))
    assert shards and shards == sorted(p.name for p in (tmp_path / "b").glob("*.array_record"))
    for name in shards:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert load_manifest(tmp_path / "a")["config"]["appearance"] == "varied"
    plain = BuildConfig(views=1, seed=5, size=48, objects_per_shard=2)
    run_build(tmp_path / "p", sources, plain, workers=1, progress=False)
    assert "appearance" not in load_manifest(tmp_path / "p")["config"]  # as written before the option
    varied_records, plain_records = list(read_dataset(tmp_path / "a")), list(read_dataset(tmp_path / "p"))
    assert [r.key for r in varied_records] == [r.key for r in plain_records]
    assert all(v.image_png != p.image_png for v, p in zip(varied_records, plain_records))
    assert [r.seg_png for r in object_records(source("cabinet"), 1, 6, 48, appearance="varied")] == \
        [r.seg_png for r in object_records(source("cabinet"), 1, 6, 48, appearance="varied")]
    with pytest.raises(InputFileError):  # another look in the same directory is refused
        run_build(tmp_path / "p", sources, config, workers=1, progress=False)


def test_unknown_appearance_refused():
    with pytest.raises(ValueError, match="appearance"):
        object_records(source("cabinet"), 1, 0, 32, appearance="fancy")
    with pytest.raises(ValueError, match="appearance"):
        config_doc(BuildConfig(1, 0, 32, 1, appearance="fancy"))


def test_cli_appearance_option(tmp_path):
    from jax3dc.cli import build_parser, main

    args = build_parser().parse_args(["data", "import", "a.urdf", "--out", str(tmp_path), "--appearance", "varied"])
    assert args.appearance == "varied"
    assert build_parser().parse_args(["data", "build", "--out", str(tmp_path), "--objects", "1"]).appearance == "plain"
    assert main(["data", "build", "--out", str(tmp_path), "--objects", "2", "--views", "1", "--size", "32",
                 "--appearance", "varied", "--quiet"]) == 0
    records = list(read_dataset(tmp_path))
    assert len(records) == 2 and {r.meta["appearance"] for r in records} == {"varied"}
    assert json.loads((tmp_path / "manifest.json").read_text())["config"]["appearance"] == "varied"


def test_mixed_views_are_each_the_plain_or_the_varied_view():
    """A mixed build shows every source in both looks: each view is byte for byte the plain or the
    varied build's view (a varied camera frames S differently), its meta says which, and the pose
    and target are the same in both."""
    obj = source("cabinet")
    looks = {name: object_records(obj, views=6, seed=3, size=SIZE, appearance=name)
             for name in ("plain", "varied", "mixed")}
    seen = set()
    for view, record in enumerate(looks["mixed"]):
        look = record.meta["appearance"]
        seen.add(look)
        assert (record.image_png, record.seg_png) == (looks[look][view].image_png, looks[look][view].seg_png)
        assert record.target == looks["plain"][view].target  # the same pose in either look
    assert seen == {"plain", "varied"}


def test_the_command_offers_every_build_look():
    """`data build/import --appearance` lists its choices without importing the renderer (fast --help)."""
    from data_pipeline.build_cli import APPEARANCE_CHOICES
    from data_pipeline.samples import BUILD_APPEARANCES
    assert APPEARANCE_CHOICES == BUILD_APPEARANCES


def test_photo_views_are_the_varied_views_degraded_and_all_mixes_three_looks():
    """A photo view is the varied view (same camera, same S, same target) with only I degraded;
    "all" shows each view in one of the three looks, each byte for byte that look's build's view."""
    obj = source("cabinet")
    looks = {name: object_records(obj, views=6, seed=5, size=SIZE, appearance=name)  # seed 5: all three looks
             for name in ("plain", "varied", "photo", "all")}
    for v, ph in zip(looks["varied"], looks["photo"]):
        assert ph.meta["appearance"] == "photo" and ph.meta["camera"] == v.meta["camera"]
        assert (ph.seg_png, ph.target, ph.prompt) == (v.seg_png, v.target, v.prompt)
        assert ph.image_png != v.image_png
    seen = set()
    for view, record in enumerate(looks["all"]):
        look = record.meta["appearance"]
        seen.add(look)
        assert (record.image_png, record.seg_png) == (looks[look][view].image_png, looks[look][view].seg_png)
    assert seen == {"plain", "varied", "photo"}


def test_degrade_is_deterministic_keeps_the_frame_and_refuses_other_images():
    from data_pipeline.photo import degrade

    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (SIZE, SIZE + 8, 3), dtype=np.uint8)
    outs = [degrade(rgb, derived_rng("photo-test", k)) for k in range(12)]
    assert all(o.shape == rgb.shape and o.dtype == np.uint8 for o in outs)
    np.testing.assert_array_equal(outs[0], degrade(rgb, derived_rng("photo-test", 0)))
    assert sum(not np.array_equal(o, rgb) for o in outs) == len(outs)
    assert len({o.tobytes() for o in outs}) == len(outs)
    flat = np.full((SIZE, SIZE, 3), 128, np.uint8)  # a mid-grey stays a picture of mid-grey, not of noise
    assert all(abs(float(degrade(flat, derived_rng("flat", k)).mean()) - 128) < 70 for k in range(8))
    for bad in (rgb[..., 0], rgb.astype(np.float32), rgb[..., :2]):
        with pytest.raises(ValueError, match="uint8"):
            degrade(bad, rng)
