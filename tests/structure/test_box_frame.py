"""Joint pivots in the moving part's box frame: the round trip keeps every joint's line, hinges on a
box edge read ±0.5, and a generated text that is not a usable document passes through untouched."""

from __future__ import annotations

import json

import numpy as np
import pytest

from data_pipeline.examples import ExampleEncoder
from jax3dc.errors import InputFileError
from jax3dc.factories import FACTORIES
from jax3dc.factories import generate_object
from jax3dc.geometry.parts import part_boxes
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.prompt import build_prompt, legend_boxes
from jax3dc.palette import object_palette
from jax3dc.structure import Box, parse_structure, to_json
from jax3dc.structure.box_frame import (
    FORMAT_FILE,
    PivotFrame,
    pivot_from_box,
    pivot_to_box,
    target_in_frame,
    text_to_absolute,
)
from tests.loader.loader_fixtures import record, tiny_config, tiny_processor

BOX = PivotFrame("box")


def _line_distance(p: np.ndarray, q: np.ndarray, axis: np.ndarray) -> float:
    a = axis / np.linalg.norm(axis)
    return float(np.linalg.norm(np.cross(p - q, a)))


@pytest.mark.parametrize("category", sorted(FACTORIES))
def test_every_factory_joint_keeps_its_line_through_the_box_frame(category: str) -> None:
    obj = generate_object(category, 3)
    prompt = build_prompt(part_boxes(obj.parts), object_palette(category, obj.object_id), None)
    boxes = legend_boxes(prompt)  # what the model reads: 3-decimal boxes
    target = to_json(obj.structure)
    written = target_in_frame(target, boxes, BOX)
    back = parse_structure(text_to_absolute(written, boxes, BOX))
    for pid, joint in obj.structure.joints().items():
        got = back.nodes[pid].joint
        assert got.type == joint.type and got.range == pytest.approx(joint.range, abs=1e-3)
        # 3-decimal fractions of sides of at most 1 nu: the line moves by well under a millimetre-nu
        assert _line_distance(np.array(got.pivot), np.array(joint.pivot), np.array(joint.axis)) < 2e-3


def test_a_hinge_on_a_box_edge_is_written_as_half_sides() -> None:
    door = Box((0.2, -0.4, 0.0), (0.4, 0.02, 0.8))
    pivot = (0.0, -0.41, 0.3)  # the door's left edge, back face, at some height along the z axis
    f = pivot_to_box(pivot, (0.0, 0.0, 1.0), door, BOX.floor)
    assert f == pytest.approx((-0.5, -0.5, 0.0))
    # the component along the axis is dropped: the pivot comes back at the box centre's height
    assert pivot_from_box(f, door, BOX.floor) == pytest.approx((0.0, -0.41, 0.0))


def test_thin_sides_are_measured_against_the_floor() -> None:
    plate = Box((0.0, 0.0, 0.0), (0.5, 0.0, 0.5))  # a flat part: zero thickness
    f = pivot_to_box((0.0, 0.01, 0.0), (1.0, 0.0, 0.0), plate, BOX.floor)
    assert np.isfinite(f).all() and f[1] == pytest.approx(0.01 / BOX.floor)


def test_absolute_frame_changes_nothing() -> None:
    rec = record("cabinet", 0)
    assert target_in_frame(rec.target, legend_boxes(rec.prompt), PivotFrame()) == rec.target
    assert text_to_absolute("{not json", {}, PivotFrame()) == "{not json"


@pytest.mark.parametrize("text", [
    "", "{", "not json at all", "[1, 2, 3]", '{"nodes": 3}', '{"nodes": {"1": {"joint": {"pivot": [1, 2]}}}}',
    '{"nodes": {"9": {"joint": {"pivot": [0.5, 0.5, 0.0]}}}}',  # no box for part 9
    '{"nodes": {"1": {"joint": {"pivot": ["a", 0, 0]}}}}', '{"nodes": {"x": {"joint": {"pivot": [0, 0, 0]}}}}',
])
def test_unusable_texts_pass_through_unchanged(text: str) -> None:
    boxes = {1: Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))}
    assert text_to_absolute(text, boxes, BOX) == text


def test_a_fenced_document_is_rewritten_inside_its_fence() -> None:
    boxes = {2: Box((0.1, 0.0, 0.0), (0.2, 0.4, 0.6))}
    doc = {"nodes": {"2": {"parent": 1, "joint": {"type": "hinge", "pivot": [0.5, -0.5, 0.0]}}}}
    out = text_to_absolute("```json\n" + json.dumps(doc) + "\n```", boxes, BOX)
    assert out.startswith("```json\n") and out.endswith("\n```")
    assert json.loads(out[8:-4])["nodes"]["2"]["joint"]["pivot"] == pytest.approx([0.2, -0.2, 0.0])


def test_format_file_round_trip_and_bad_file(tmp_path) -> None:
    assert PivotFrame.load(tmp_path) == PivotFrame()  # no file: an older, absolute model
    PivotFrame("box", 0.03).save(tmp_path)
    assert PivotFrame.load(tmp_path) == PivotFrame("box", 0.03)
    (tmp_path / FORMAT_FILE).write_text('{"pivot_frame": "polar"}')
    with pytest.raises(InputFileError, match=FORMAT_FILE):
        PivotFrame.load(tmp_path)
    with pytest.raises(ValueError):
        PivotFrame("box", 0.0)


def test_training_examples_carry_box_frame_targets() -> None:
    cfg, tok = tiny_config(), load_tokenizer()
    rec = record("cabinet", 1)
    encoder = ExampleEncoder(tok, tiny_processor(), cfg.vision.spatial_merge_size, pivot_frame=BOX)
    answer = encoder.messages(rec)[-1]["content"][0]["text"]
    assert answer == target_in_frame(rec.target, legend_boxes(rec.prompt), BOX) != rec.target
    pivots = [n["joint"]["pivot"] for n in json.loads(answer)["nodes"].values() if "joint" in n]
    assert pivots and all(abs(v) <= 9.999 for p in pivots for v in p)
