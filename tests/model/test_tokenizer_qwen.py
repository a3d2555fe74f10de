"""Tokenizer loading: real Qwen3 vocabulary, special ids, parity with transformers, bad folders."""

from __future__ import annotations

import json
import os

import pytest
from transformers import AutoTokenizer

from jax3dc.errors import InputFileError
from jax3dc.processing.tokenizer import QWEN_VL_SPECIAL_IDS, default_tokenizer_dir, load_tokenizer

SAMPLES = [
    "Parts (id: colour | centroid | extent):\n1: #3a7bd5 | 0.000 0.012 -0.100 | 1.000 0.600 0.800",
    '{"materials":{"1":"wood","2":"metal"},"nodes":{"1":{"parent":null}}}',
    "  leading spaces, tabs\tand\n\nblank lines  ",
    "Unicode: é, ß, 中文, 日本語, emoji 🙂",
    "<|im_start|>user\nhello<|im_end|>\n<|im_start|>assistant\n",
    "<|vision_start|><|image_pad|><|image_pad|><|vision_end|>after",
]


@pytest.fixture(scope="module")
def tokenizer():
    return load_tokenizer()


@pytest.fixture(scope="module")
def hf_tokenizer():
    return AutoTokenizer.from_pretrained(default_tokenizer_dir())


def test_special_ids_are_qwen3_vl(tokenizer) -> None:
    special = tokenizer.special
    assert special.vision_start == 151652
    assert special.image_pad == 151655
    assert (special.im_start, special.im_end, special.endoftext) == (151644, 151645, 151643)
    assert special.stop_ids == (151645, 151643)
    for token, expected in QWEN_VL_SPECIAL_IDS.items():
        assert tokenizer.token_id(token) == expected
    assert tokenizer.vocab_size <= 151936  # fits the model's embedding table


@pytest.mark.parametrize("text", SAMPLES)
def test_encode_decode_match_transformers(tokenizer, hf_tokenizer, text: str) -> None:
    ids = tokenizer.encode(text)
    assert ids == hf_tokenizer(text, add_special_tokens=False)["input_ids"]
    assert tokenizer.decode(ids, skip_special_tokens=False) == text
    assert tokenizer.decode(ids) == hf_tokenizer.decode(ids, skip_special_tokens=True)


def test_offsets_cover_text(tokenizer) -> None:
    text = SAMPLES[4]
    ids, offsets = tokenizer.encode_with_offsets(text)
    assert len(ids) == len(offsets)
    assert offsets[0] == (0, len("<|im_start|>"))
    assert text[offsets[-1][0]:offsets[-1][1]] == "\n"


def test_missing_tokenizer_json_is_input_file_error(tmp_path) -> None:
    with pytest.raises(InputFileError, match="tokenizer.json not found"):
        load_tokenizer(tmp_path)


def test_malformed_tokenizer_json_is_input_file_error(tmp_path) -> None:
    (tmp_path / "tokenizer.json").write_text("{not json")
    with pytest.raises(InputFileError, match="cannot parse"):
        load_tokenizer(tmp_path)


def test_wrong_special_id_is_rejected(tmp_path) -> None:
    with open(os.path.join(default_tokenizer_dir(), "tokenizer.json"), encoding="utf-8") as f:
        doc = json.load(f)
    for added in doc["added_tokens"]:
        if added["content"] == "<|image_pad|>":
            added["content"] = "<|image_pad_renamed|>"
    (tmp_path / "tokenizer.json").write_text(json.dumps(doc))
    with pytest.raises(InputFileError, match=r"<\|image_pad\|>"):
        load_tokenizer(tmp_path)


def test_saved_tokenizer_carries_the_vl_template(tmp_path, tokenizer) -> None:
    from jax3dc.processing.chat import VL_CHAT_TEMPLATE, render_chat

    tokenizer.save_pretrained(tmp_path, chat_template=VL_CHAT_TEMPLATE)
    reloaded = load_tokenizer(tmp_path)
    assert reloaded.encode(SAMPLES[3]) == tokenizer.encode(SAMPLES[3])
    hf = AutoTokenizer.from_pretrained(tmp_path)
    messages = [
        {"role": "user", "content": [{"type": "image"}, {"type": "text", "text": "describe"}]},
        {"role": "assistant", "content": "a drawer"},
    ]
    assert hf.apply_chat_template(messages, tokenize=False) == render_chat(messages, [1])[0]
    # the packaged tokenizer's own template is the plain Qwen3 one: it adds a <think> block
    text_only = [{"role": "user", "content": "describe"}, {"role": "assistant", "content": "a drawer"}]
    plain = AutoTokenizer.from_pretrained(default_tokenizer_dir()).apply_chat_template(text_only, tokenize=False)
    assert "<think>" in plain
    assert hf.apply_chat_template(text_only, tokenize=False) == render_chat(text_only)[0]
