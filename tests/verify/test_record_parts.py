"""record_parts rebuilds a record's meshes as its view shows them: boxes agree with the record's."""

from dataclasses import replace

import numpy as np
import pytest

from data_pipeline.record_parts import is_mounted, record_parts
from jax3dc.errors import Jax3dcError
from jax3dc.geometry.parts import part_boxes
from jax3dc.structure import boxes_from_dict
from tests.verify.verified_cases import IMPORTED
from tests.shared_fixtures import partnet_object


def assert_boxes_agree(parts, record, tol=1e-3):
    want = boxes_from_dict(record.meta["boxes"])
    have = part_boxes(parts)
    assert sorted(have) == sorted(want), record.key
    for part, box in want.items():
        np.testing.assert_allclose(have[part].centroid, box.centroid, atol=tol, err_msg=f"{record.key} part {part}")
        np.testing.assert_allclose(have[part].extent, box.extent, atol=tol, err_msg=f"{record.key} part {part}")


def test_factory_records_in_every_view_and_variant(posed_records):
    kinds = set()
    for record in posed_records.values():
        parts, scale, mounted = record_parts(record)
        assert_boxes_agree(parts, record)
        assert scale == record.meta["scale_m_per_nu"] and mounted is False  # cabinets and chests stand free
        kinds.add("moved" if record.meta["moved_joint"] is not None else
                  "augmented" if record.meta["augmentation"] else "rest")
    assert kinds == {"rest", "moved", "augmented"}


def test_a_moved_view_differs_from_rest(posed_records):
    """The pose matters: the rest meshes do not fit a moved view's boxes."""
    moved = next(r for r in posed_records.values() if r.meta["moved_joint"] is not None and abs(r.meta["theta"]) > 0.1)
    rest = posed_records[moved.key.rsplit("/", 1)[0] + "/0"]
    rest_parts, _, _ = record_parts(rest)
    with pytest.raises(AssertionError):
        assert_boxes_agree(rest_parts, moved)


def test_imported_records_from_their_source_folders(imported_records):
    sources = {name: partnet_object(name) for name in IMPORTED}
    seen = set()
    for record in imported_records.values():
        parts, scale, mounted = record_parts(record, sources)
        assert_boxes_agree(parts, record)
        assert scale == record.meta["scale_m_per_nu"]
        assert mounted == (record.meta["category"] == "Door")  # a door frame is set in a wall
        seen.add((record.meta["object_id"], record.meta["moved_joint"] is not None, bool(record.meta["augmentation"])))
    assert {(name, moved, False) for name in IMPORTED for moved in (False, True)} <= seen
    assert any(augmented for _, _, augmented in seen)


def test_imported_record_without_its_folder_names_the_record(imported_records):
    record = next(iter(imported_records.values()))
    with pytest.raises(Jax3dcError, match=f"record {record.key}: .*no source folder"):
        record_parts(record)
    with pytest.raises(Jax3dcError, match=f"record {record.key}: source folder .* does not exist"):
        record_parts(record, {record.meta["object_id"]: partnet_object(IMPORTED[0]) / "missing"})


def test_parts_that_do_not_match_the_record_are_refused(posed_records):
    moved = next(r for r in posed_records.values() if r.meta["moved_joint"] is not None and abs(r.meta["theta"]) > 0.1)
    wrong = replace(moved, meta=dict(moved.meta, theta=moved.meta["theta"] + 0.2))
    with pytest.raises(Jax3dcError, match=f"record {moved.key}: rebuilt part .* off the record's box"):
        record_parts(wrong)


def test_mounted_categories():
    assert is_mounted("faucet") and is_mounted("Door") and is_mounted("window")
    assert not is_mounted("cabinet") and not is_mounted("Microwave") and not is_mounted("")
