"""Kind targets: the one table from part names to kinds, the names a record builder now keeps in
meta, and records without them (built before) whose parts are all kind ``other``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from data_pipeline.record import Record
from data_pipeline.samples import factory_source, object_records
from jax3dc.stage1_slots.kinds import KINDS, kind_index, kind_of
from train.stage1_slots import ROOT, UNKNOWN, slot_targets


@pytest.mark.parametrize("name, kind", [
    ("freezer_door", "door"), ("lever_handle", "handle"), ("tap_lever", "lever"), ("laptop_base", "body"),
    ("seat_cushion_2", "seat"), ("rotation_door", "door"), ("furniture_body", "body"), ("toggle_button", "button"),
    ("translation_tray", "drawer"), ("caster", "wheel"), ("chair_leg", "leg"), ("Shelf-3", "shelf"),
    ("rotation_blade", "blade"), ("display", "screen"), ("pump_lid", "lid"), ("cap", "cap"), ("knob", "knob"),
    ("book", "other"), ("", "other"), (None, "other"),
])
def test_names_map_to_kinds_by_their_last_known_word(name, kind):
    assert kind_of(name) == kind and KINDS[kind_index(name)] == kind


@pytest.fixture(scope="module")
def cabinet_record() -> Record:
    return object_records(factory_source("cabinet", 0), 1, 0, 32)[0]


def test_records_keep_the_parts_semantic_names(cabinet_record):
    names = cabinet_record.meta["part_names"]
    assert sorted(names, key=int) == sorted(cabinet_record.meta["boxes"], key=int)
    assert {kind_of(n) for n in names.values()} >= {"body", "door", "handle"}


def test_slot_targets_read_boxes_kinds_and_parents(cabinet_record):
    boxes, kinds, parents, valid, dropped = slot_targets(cabinet_record, 8)
    meta, nodes = cabinet_record.meta, json.loads(cabinet_record.target)["nodes"]
    ids = sorted(meta["boxes"], key=int)
    assert valid.sum() == len(ids) and dropped == 0 and not valid[len(ids):].any()
    for row, pid in enumerate(ids):
        np.testing.assert_allclose(boxes[row], meta["boxes"][pid]["centroid"] + meta["boxes"][pid]["extent"], atol=1e-6)
        assert KINDS[kinds[row]] == kind_of(meta["part_names"][pid])
        parent = nodes[pid]["parent"]
        assert parents[row] == (ROOT if parent is None else ids.index(str(parent)))


def test_a_record_without_names_gives_kind_other_and_too_many_parts_keep_the_largest(cabinet_record):
    meta = {k: v for k, v in cabinet_record.meta.items() if k != "part_names"}
    old = Record(cabinet_record.key, b"", b"", "", cabinet_record.target, meta=meta)
    _, kinds, parents, valid, dropped = slot_targets(old, 2)
    assert valid.all() and dropped == len(meta["boxes"]) - 2
    assert [KINDS[k] for k in kinds] == ["other", "other"]
    volume = {p: np.prod(b["extent"]) for p, b in meta["boxes"].items()}
    assert set(parents) <= {ROOT, UNKNOWN, 0, 1} and ROOT in parents  # the body (largest) is kept, a root
    assert max(volume.values()) == pytest.approx(np.prod(slot_targets(old, 2)[0][:, 3:], axis=1).max(), rel=1e-5)
