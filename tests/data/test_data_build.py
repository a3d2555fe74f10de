"""Shards: split by object, resumable after a kill, byte-identical whatever the worker count."""


import numpy as np
import pytest

from data_pipeline.build import BuildConfig, factory_sources, plan_shards, run_build
from data_pipeline.record import CorruptRecordError, decode_record
from data_pipeline.samples import split_of
from data_pipeline.shards import load_manifest, read_dataset
from data_pipeline.views import move_joint
from jax3dc.errors import InputFileError
from jax3dc.factories import generate_object

CONFIG = BuildConfig(views=2, seed=5, size=48, objects_per_shard=2)


def shard_bytes(directory):
    return {p.name: p.read_bytes() for p in sorted(directory.glob("*.array_record"))}


def test_plan_splits_by_object_and_keeps_all_objects():
    sources = factory_sources(40, 0)
    tasks = plan_shards(sources, 3)
    seen = [s for t in tasks for s in t.sources]
    assert sorted(s.object_id for s in seen) == sorted(s.object_id for s in sources)
    for t in tasks:
        assert all(split_of(s.object_id) == t.split for s in t.sources)
        assert t.name.startswith(t.split + "-")


def test_build_resume_after_kill_is_complete_and_identical(tmp_path):
    sources = factory_sources(6, CONFIG.seed)
    full = tmp_path / "full"
    run_build(full, sources, CONFIG, workers=1, progress=False)
    records = list(read_dataset(full))
    assert len(records) == 6 * CONFIG.views
    assert len({r.key for r in records}) == len(records)
    by_object = {}
    for r in records:
        by_object.setdefault(r.meta["object_id"], set()).add(r.meta["split"])
    assert all(len(v) == 1 for v in by_object.values())

    class Killed(Exception):
        pass

    def kill_after_first(_name):
        raise Killed

    part = tmp_path / "part"
    with pytest.raises(Killed):
        run_build(part, sources, CONFIG, workers=1, progress=False, on_shard=kill_after_first)
    assert len(load_manifest(part)["shards"]) == 1 and not load_manifest(part)["complete"]
    # a half-written shard and a corrupted finished shard are both rebuilt
    (part / "train-00001.array_record.tmp").write_bytes(b"partial")
    first = next(iter(load_manifest(part)["shards"]))
    (part / first).write_bytes((part / first).read_bytes()[:-10])
    run_build(part, sources, CONFIG, workers=2, progress=False)
    assert shard_bytes(part) == shard_bytes(full)
    assert load_manifest(part)["complete"]


def test_other_settings_in_same_directory_refused(tmp_path):
    sources = factory_sources(1, 0)
    run_build(tmp_path, sources, BuildConfig(1, 0, 32, 1), workers=1, progress=False)
    with pytest.raises(InputFileError):
        run_build(tmp_path, sources, BuildConfig(1, 1, 32, 1), workers=1, progress=False)


def test_corrupt_record_detected():
    with pytest.raises(CorruptRecordError):
        decode_record(b"J3DR1\x05\x00\x00\x00{}")


def test_moved_joint_view_describes_the_pose():
    g = generate_object("cabinet", 0)
    pid, joint = next(iter(g.structure.joints().items()))
    theta = 0.5 * (joint.range[0] + joint.range[1])
    posed = move_joint(g.structure, g.parts, pid, theta)
    lo, hi = posed.structure.nodes[pid].joint.range
    assert (lo, hi) == pytest.approx((joint.range[0] - theta, joint.range[1] - theta))
    # a point of the moved part keeps its distance to the hinge axis; the part's vertices moved
    axis = np.asarray(joint.axis) / np.linalg.norm(joint.axis)
    pivot = np.asarray(joint.pivot)

    def radial(v):
        d = v - pivot
        return np.linalg.norm(d - np.outer(d @ axis, axis), axis=1)

    before, after = g.parts[pid].vertices, posed.parts[pid].vertices
    np.testing.assert_allclose(radial(after), radial(before), atol=1e-9)
    assert np.abs(after - before).max() > 0.05
    unmoved = [p for p in g.parts if p not in posed.poses]
    assert unmoved and all(np.array_equal(posed.parts[p].vertices, g.parts[p].vertices) for p in unmoved)


def test_build_cli_objects_and_scenes(tmp_path):
    from jax3dc.cli import main

    args = ["data", "build", "--out", str(tmp_path), "--objects", "2", "--scenes", "1", "--views", "2",
            "--size", "32", "--quiet"]
    assert main(args) == 0
    records = list(read_dataset(tmp_path))
    assert len(records) == 2 * 2 + 2 * 2  # objects x views + scene (part, object) x views
    assert main(args) == 0  # a finished build run again is a no-op
    assert [r.key for r in read_dataset(tmp_path)] == [r.key for r in records]


def test_named_categories_cycle_and_unknown_ones_are_refused(tmp_path, capsys):
    from jax3dc.cli import main

    sources = factory_sources(5, 3, ["laptop", "safe"])
    assert [s.category for s in sources] == ["laptop", "safe", "laptop", "safe", "laptop"]
    assert [s.seed for s in sources] == [3_000_000 + k for k in range(5)]  # as in a build of every category
    with pytest.raises(SystemExit, match="'toaster_oven'"):
        main(["data", "build", "--out", str(tmp_path / "x"), "--objects", "2", "--categories", "laptop,toaster_oven"])
    assert not (tmp_path / "x").exists()  # refused before anything is written
    with pytest.raises(SystemExit, match="no categories"):
        main(["data", "build", "--out", str(tmp_path / "y"), "--objects", "2", "--categories", " , "])
    assert main(["data", "build", "--out", str(tmp_path / "z"), "--objects", "2", "--categories", "laptop",
                 "--views", "1", "--size", "32", "--quiet"]) == 0
    assert [r.key.split("/")[0] for r in read_dataset(tmp_path / "z")] == ["laptop", "laptop"]


def test_plan_with_a_fixed_split_puts_every_object_there():
    sources = factory_sources(12, 0)
    assert {split_of(s.object_id) for s in sources} != {"val"}  # hashing alone would spread them
    tasks = plan_shards(sources, 5, "val")
    assert [t.name for t in tasks] == ["val-00000.array_record", "val-00001.array_record", "val-00002.array_record"]
    assert [s.object_id for t in tasks for s in t.sources] == [s.object_id for s in sources]
    assert plan_shards(sources, 5) == plan_shards(sources, 5, "hash")
    with pytest.raises(ValueError):
        plan_shards(sources, 5, "everything")


def _write_urdf(folder, length: float) -> None:
    """A two-link URDF object (box base, hinged box lid) in ``folder``."""
    folder.mkdir(parents=True)
    (folder / "object.urdf").write_text(f"""<robot name="{folder.name}">
  <link name="base"><visual><geometry><box size="{length} 0.4 0.3"/></geometry></visual></link>
  <link name="lid"><visual><origin xyz="0 0.2 0.02"/><geometry><box size="{length} 0.4 0.04"/></geometry></visual></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="lid"/>
    <origin xyz="0 -0.2 0.15"/><axis xyz="1 0 0"/><limit lower="0" upper="1.5"/></joint>
</robot>
""")


def test_import_cli_split_names_shards_meta_and_manifest(tmp_path):
    from jax3dc.cli import main

    folders = [tmp_path / "src" / f"box_{k}" for k in range(4)]
    for k, folder in enumerate(folders):
        _write_urdf(folder, 0.5 + 0.1 * k)
    assert {split_of(f.name) for f in folders} != {"test"}  # the default would not put them all in test
    common = ["--views", "1", "--size", "32", "--objects-per-shard", "3", "--quiet"]
    out = tmp_path / "test_split"
    assert main(["data", "import", *map(str, folders), "--out", str(out), "--split", "test", *common]) == 0
    manifest = load_manifest(out)
    assert manifest["config"]["split"] == "test"
    assert sorted(manifest["shards"]) == ["test-00000.array_record", "test-00001.array_record"]
    assert {s["split"] for s in manifest["shards"].values()} == {"test"}
    assert sorted(p.name for p in out.glob("*.array_record")) == sorted(manifest["shards"])
    records = list(read_dataset(out))
    assert sorted(r.meta["object_id"] for r in records) == [f.name for f in folders]
    assert {r.meta["split"] for r in records} == {"test"}
    # the same build again is a no-op; another --split in the same folder is refused
    assert main(["data", "import", *map(str, folders), "--out", str(out), "--split", "test", *common]) == 0
    assert main(["data", "import", *map(str, folders), "--out", str(out), *common]) == 1
    assert main(["data", "import", *map(str, folders), "--out", str(out), "--split", "train", *common]) == 1

    # default: the hash split, recorded as such
    hashed = tmp_path / "hash_split"
    assert main(["data", "import", *map(str, folders), "--out", str(hashed), *common]) == 0
    assert load_manifest(hashed)["config"]["split"] == "hash"
    assert all(r.meta["split"] == split_of(r.meta["object_id"]) for r in read_dataset(hashed))


def test_manifest_from_before_the_split_setting_resumes_as_hash(tmp_path):
    import json

    sources = factory_sources(1, 0)
    run_build(tmp_path, sources, BuildConfig(1, 0, 32, 1), workers=1, progress=False)
    path = tmp_path / "manifest.json"
    manifest = json.loads(path.read_text())
    del manifest["config"]["split"]
    manifest["complete"] = False
    path.write_text(json.dumps(manifest))
    run_build(tmp_path, sources, BuildConfig(1, 0, 32, 1), workers=1, progress=False)
    with pytest.raises(InputFileError):
        run_build(tmp_path, sources, BuildConfig(1, 0, 32, 1, split="test"), workers=1, progress=False)
