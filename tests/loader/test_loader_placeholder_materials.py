"""The material text an importer writes where its source names no material takes no loss: it marks
the real domain, not a fact about the object (data_pipeline.importers.material_guess)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from data_pipeline.examples import ExampleEncoder
from data_pipeline.importers.material_guess import GUESSED_DESC, UNKNOWN_DESC, placeholder_spans
from jax3dc.processing.chat import IGNORE_INDEX, encode_chat
from jax3dc.processing.tokenizer import load_tokenizer
from tests.loader.loader_fixtures import record, tiny_config, tiny_processor


def imported_like(rec):
    """``rec`` with the materials an importer writes for parts whose sources name none."""
    doc = json.loads(rec.target)
    doc["materials"] = {"0": {"family": "Other", "desc": UNKNOWN_DESC},
                        "1": {"family": "Metal", "desc": GUESSED_DESC.format("metal")}}
    for k, node in enumerate(doc["nodes"].values()):
        node["material"] = k % 2
    return dataclasses.replace(rec, target=json.dumps(doc, separators=(",", ":")))


@pytest.fixture(scope="module")
def encoders():
    tok, merge = load_tokenizer(), tiny_config().vision.spatial_merge_size
    return (tok, ExampleEncoder(tok, tiny_processor(), merge),
            ExampleEncoder(tok, tiny_processor(), merge, score_placeholder_materials=True))


def scored_text(tok, example) -> str:
    return tok.decode(example.labels[example.labels != IGNORE_INDEX].tolist(), skip_special_tokens=False)


def test_placeholder_text_is_unscored_and_everything_else_is(encoders):
    tok, default, scoring = encoders
    rec = imported_like(record("cabinet", 1))
    ours, everything = default.encode(rec), scoring.encode(rec)
    np.testing.assert_array_equal(ours.input_ids, everything.input_ids)  # the model still reads it
    text, full = scored_text(tok, ours), scored_text(tok, everything)
    assert UNKNOWN_DESC in full and "guessed from part names" in full and UNKNOWN_DESC not in text
    assert "guessed from part names" not in text and '"family":"Metal"' in text  # a named family stays scored
    assert '"family":"Other"' not in text and '"nodes"' in text and '"joint"' in text
    dropped = int((everything.labels != IGNORE_INDEX).sum() - (ours.labels != IGNORE_INDEX).sum())
    assert 0 < dropped < 40


def test_factory_records_are_scored_exactly_as_before(encoders):
    _, default, scoring = encoders
    rec = record("microwave", 2)
    assert placeholder_spans(rec.target) == []
    np.testing.assert_array_equal(default.encode(rec).labels, scoring.encode(rec).labels)


def test_spans_outside_the_answer_are_refused():
    tok = load_tokenizer()
    messages = [{"role": "user", "content": "hi"}, {"role": "assistant", "content": "abcdef"}]
    assert (encode_chat(tok, messages, unscored=[(0, 6)]).labels != IGNORE_INDEX).sum() == 1  # <|im_end|> only
    with pytest.raises(ValueError, match="outside the answer"):
        encode_chat(tok, messages, unscored=[(2, 9)])
    with pytest.raises(ValueError, match="without an assistant"):
        encode_chat(tok, messages[:1], unscored=[(0, 1)])
