"""The slots network: output shapes and ranges, the folder round trip (float16) and its strict
loading, and decoding any outputs into a forest of kept slots."""

from __future__ import annotations

import json

import numpy as np
import pytest
import safetensors.numpy
from flax import nnx

from jax3dc.errors import InputFileError
from jax3dc.stage1_slots import KINDS, SlotsNet, SlotsNetConfig, decode_slots, forward, load_slots, save_slots


@pytest.fixture(scope="module")
def model() -> SlotsNet:
    return SlotsNet(SlotsNetConfig.tiny(slots=5), nnx.Rngs(0))


def test_outputs_have_the_slot_shapes_and_boxes_lie_in_the_frame(model):
    images = np.random.default_rng(0).random((2, 32, 32, 3)).astype(np.float32)
    exists, boxes, kinds, parents = (np.asarray(x) for x in forward(model, images))
    assert exists.shape == (2, 5) and boxes.shape == (2, 5, 6) and kinds.shape == (2, 5, len(KINDS))
    assert parents.shape == (2, 5, 6)
    assert np.abs(boxes[..., :3]).max() <= 0.5 and (boxes[..., 3:] >= 0).all() and (boxes[..., 3:] <= 1).all()
    assert (np.diagonal(parents[..., :5], axis1=1, axis2=2) < -1e8).all()  # never its own parent


def test_the_folder_round_trips_and_refuses_a_wrong_tensor(model, tmp_path):
    folder = save_slots(tmp_path / "net", model, notes={"recipe": "test"})
    assert {p.name for p in folder.iterdir()} == {"slots_net.json", "model.safetensors", "MODEL_CARD.md"}
    images = np.random.default_rng(1).random((1, 32, 32, 3)).astype(np.float32)
    want = forward(model, images)
    got = forward(load_slots(folder).model, images)
    for a, b in zip(want, got):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), atol=0.05)
    tensors = safetensors.numpy.load_file(str(folder / "model.safetensors"))
    tensors.pop(sorted(tensors)[0])
    safetensors.numpy.save_file(tensors, str(folder / "model.safetensors"))
    with pytest.raises(InputFileError, match="missing tensor"):
        load_slots(folder)
    marker = json.loads((folder / "slots_net.json").read_text())
    (folder / "slots_net.json").write_text(json.dumps({**marker, "kinds": ["body"]}))
    with pytest.raises(InputFileError, match="kinds"):
        load_slots(folder)


def _parents(k: int, pointers: dict[int, int | None]) -> np.ndarray:
    """Parent logits [k, k + 1] pointing slot i at pointers[i] (None: root)."""
    logits = np.zeros((k, k + 1))
    for i, j in pointers.items():
        logits[i, k if j is None else j] = 5.0
    return logits


def test_decoding_keeps_existing_slots_and_points_parents_among_them():
    k = 4
    exists = np.array([3.0, -3.0, 3.0, 3.0])  # slot 1 is dropped
    boxes = np.tile([0.0, 0.0, 0.0, 0.5, 0.5, 0.5], (k, 1))
    kinds = np.eye(k, len(KINDS)) * 5
    parents = _parents(k, {0: None, 1: 0, 2: 1, 3: 0})  # slot 2 points at the dropped slot 1
    slots = decode_slots(exists, boxes, kinds, parents)
    assert [s.kind for s in slots] == [KINDS[0], KINDS[2], KINDS[3]]
    assert slots[0].parent is None and slots[2].parent == 0
    assert slots[1].parent in (None, 0, 2) and slots[1].parent != 1


def test_a_cycle_is_broken_at_its_likeliest_root_and_nans_decode():
    k = 3
    parents = _parents(k, {0: 1, 1: 2, 2: 0})
    parents[1, k] = 4.0  # slot 1 would rather be a root than anything but its pointer
    slots = decode_slots(np.full(k, 3.0), np.zeros((k, 6)), np.zeros((k, len(KINDS))), parents)
    assert [s.parent for s in slots] == [1, None, 0]
    nan = decode_slots(np.full(k, np.nan), np.full((k, 6), np.nan), np.full((k, len(KINDS)), np.nan),
                       np.full((k, k + 1), np.nan))
    assert nan == []
    kept = decode_slots(np.full(k, 3.0), np.full((k, 6), np.nan), np.full((k, len(KINDS)), np.nan),
                        np.full((k, k + 1), np.nan))
    assert all(s.parent is None and s.kind == "other" and min(s.extent) > 0 for s in kept)
