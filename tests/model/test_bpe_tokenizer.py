"""Byte-level BPE learned on our texts: Qwen3's added tokens and layout, exact round trip, chat
labels, determinism, files that jax3dc and transformers both load, the model config and the CLI."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from transformers import AutoTokenizer

from data_pipeline.record import Record
from data_pipeline.shards import write_dataset
from jax3dc.cli import main as cli_main
from jax3dc.errors import InputFileError
from jax3dc.factories import generate_object
from jax3dc.geometry.parts import part_boxes
from jax3dc.processing.bpe import QWEN_ADDED_TOKENS, chat_segments, config_for_tokenizer, train_bpe
from jax3dc.processing.chat import IGNORE_INDEX, VL_CHAT_TEMPLATE, encode_chat
from jax3dc.model.config import Qwen3VLConfig
from jax3dc.processing.tokenizer import load_tokenizer
from jax3dc.palette import object_palette
from jax3dc.prompt import build_prompt, chat_messages, code_messages
from jax3dc.structure import to_json

CATEGORIES = ("cabinet", "laptop", "door", "faucet", "chair", "kettle")
VOCAB = 700

UNICODE_JSON = ('{"materials":{"0":{"family":"Wood","desc":"chêne massif – 橡木 🙂"}},'
                '"nodes":{"1":{"parent":null,"material":0}},"relations":[]}')
UNICODE_PROGRAM = ("mat1 = material('Metal', 'Edelstahl gebürstet ✓')\n"
                   "box1 = box((0.9925, 0.8161, 1), center=(0, -0.0821, 0))\r\n\tpart(1, 'Körper', box1, material=mat1)")
ODD_TEXTS = [UNICODE_JSON, UNICODE_PROGRAM, "e\u0301 vs \u00e9 (not NFC-normalised)", "  two  spaces\n\n\nand tabs\t\t",
             "<|im_start|>user\nhi<|im_end|>\n", "a<|image_pad|><|image_pad|>b<think>c</think>"]


def _object_texts(category: str, seed: int) -> tuple[str, str, str]:
    obj = generate_object(category, seed)
    boxes = part_boxes(obj.parts)
    prompt = build_prompt(boxes, object_palette(category, obj.object_id), len(obj.structure.joints()) or None)
    return prompt, to_json(obj.structure), obj.program_text


@pytest.fixture(scope="module")
def samples() -> list[tuple[str, str, str]]:
    return [_object_texts(c, seed) for c in CATEGORIES for seed in (0, 1)]


@pytest.fixture(scope="module")
def corpus(samples) -> list[str]:
    texts = []
    for prompt, target, program in samples[:-2]:  # the last object is held out
        texts += chat_segments(chat_messages(prompt, target)) + chat_segments(code_messages(program))
    return texts


@pytest.fixture(scope="module")
def bpe(corpus):
    return train_bpe(corpus, VOCAB)


@pytest.fixture(scope="module")
def qwen():
    return load_tokenizer()


def test_added_tokens_follow_learned_vocab_as_in_qwen3(bpe, qwen) -> None:
    learned = bpe._backend.get_vocab_size(with_added_tokens=False)
    assert 256 < learned <= VOCAB - len(QWEN_ADDED_TOKENS)
    assert bpe.vocab_size == learned + len(QWEN_ADDED_TOKENS)
    ours, theirs = bpe._backend.get_added_tokens_decoder(), qwen._backend.get_added_tokens_decoder()
    assert [(i - learned, t.content, t.special) for i, t in sorted(ours.items())] == \
           [(i - 151643, t.content, t.special) for i, t in sorted(theirs.items())]
    assert bpe.special.image_pad == learned + (qwen.special.image_pad - 151643)
    assert bpe.special.stop_ids == (learned + 2, learned)


@pytest.mark.parametrize("content", [content for content, _ in QWEN_ADDED_TOKENS])
def test_added_tokens_are_never_split(bpe, content: str) -> None:
    token = bpe.token_id(content)
    assert bpe.encode(content) == [token]
    ids = bpe.encode(f"x{content}{content}y {content}\n")
    assert ids.count(token) == 3
    assert bpe.decode(ids, skip_special_tokens=False) == f"x{content}{content}y {content}\n"


@pytest.mark.parametrize("index", range(len(ODD_TEXTS)))
def test_round_trip_is_exact(bpe, index: int) -> None:
    text = ODD_TEXTS[index]
    assert bpe.decode(bpe.encode(text), skip_special_tokens=False) == text


def test_round_trip_on_held_out_object(bpe, samples) -> None:
    for text in samples[-1]:
        assert bpe.decode(bpe.encode(text)) == text


@settings(max_examples=60, deadline=None)
@given(st.text(max_size=80))
def test_round_trip_of_any_text(bpe, text: str) -> None:
    assert bpe.decode(bpe.encode(text), skip_special_tokens=False) == text


def test_learned_merges_shorten_our_texts(bpe, samples) -> None:
    prompt, target, program = samples[-1]
    for text in (prompt, target, program):
        assert len(bpe.encode(text)) < 0.6 * len(text.encode("utf-8"))


def test_encode_chat_labels_cover_exactly_the_assistant_span(bpe, samples) -> None:
    prompt, target, _ = samples[-1]
    grid = np.array([[1, 4, 6], [1, 4, 4]])
    chat = encode_chat(bpe, chat_messages(prompt, target), grid, merge_size=2)
    labelled = chat.labels != IGNORE_INDEX
    kept = chat.input_ids[labelled].tolist()
    assert bpe.decode(kept, skip_special_tokens=False) == target + "<|im_end|>"
    assert kept == bpe.encode(target) + [bpe.special.im_end]
    first = int(np.argmax(labelled))
    assert np.all(labelled[first:first + len(kept)])  # one contiguous span
    assert chat.input_ids[first - 1] != bpe.special.im_end and np.sum(labelled) == len(kept)
    assert np.sum(chat.input_ids == bpe.special.image_pad) == (6 + 4) * 4 // 4


def test_training_is_deterministic(bpe, corpus, tmp_path) -> None:
    assert train_bpe(corpus, VOCAB)._backend.to_str() == bpe._backend.to_str()
    # A fresh process gets fresh hash seeds (Rust and Python): the same file must come out.
    (tmp_path / "corpus.json").write_text(json.dumps(corpus))
    script = ("import json, sys; from jax3dc.processing.bpe import train_bpe; "
              f"t = train_bpe(json.load(open(sys.argv[1])), {VOCAB}); print(t._backend.to_str())")
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", script, str(tmp_path / "corpus.json")], cwd=root, check=True,
                         capture_output=True, text=True, env={**os.environ, "PYTHONHASHSEED": "12345"}).stdout
    assert out.strip() == bpe._backend.to_str()


def test_digit_runs_shorten_numbers(corpus) -> None:
    grouped, single = train_bpe(corpus, VOCAB, digits=3), train_bpe(corpus, VOCAB)
    multi_digit = lambda t: {k for k in t._backend.get_vocab(with_added_tokens=False) if k.isdigit() and len(k) > 1}
    assert not multi_digit(single)
    assert multi_digit(grouped) and max(map(len, multi_digit(grouped))) == 3
    text = "0.000 -0.500 1.000"  # frequent in prompts and targets
    assert len(grouped.encode(text)) < len(single.encode(text)) == 17
    assert grouped.decode(grouped.encode(text)) == text


def test_bad_sizes_are_rejected(corpus) -> None:
    with pytest.raises(ValueError, match="256 byte symbols"):
        train_bpe(corpus, 200)
    with pytest.raises(ValueError, match="digits"):
        train_bpe(corpus, VOCAB, digits=0)


def test_save_load_round_trip(bpe, samples, tmp_path) -> None:
    bpe.save_pretrained(tmp_path / "a")
    loaded = load_tokenizer(tmp_path / "a")  # special ids checked against Qwen3's layout
    assert loaded._backend.to_str() == bpe._backend.to_str()
    assert loaded.special == bpe.special and loaded.vocab_size == bpe.vocab_size
    for text in [*samples[-1], *ODD_TEXTS]:
        assert loaded.encode(text) == bpe.encode(text)
    loaded.save_pretrained(tmp_path / "b")  # copied from the files this time
    for name in ("tokenizer.json", "tokenizer_config.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_misplaced_special_token_is_rejected(bpe, tmp_path) -> None:
    bpe.save_pretrained(tmp_path)
    path = tmp_path / "tokenizer.json"
    doc = json.loads(path.read_text())
    for added in doc["added_tokens"]:  # swap the strings of two ids
        added["content"] = {"<|image_pad|>": "<|video_pad|>", "<|video_pad|>": "<|image_pad|>"}.get(
            added["content"], added["content"])
    path.write_text(json.dumps(doc))
    with pytest.raises(InputFileError, match=r"<\|image_pad\|> has id"):
        load_tokenizer(tmp_path)
    assert load_tokenizer(tmp_path, check_special_ids=False).special.image_pad == bpe.special.image_pad + 1


def test_config_for_tokenizer_matches_ids(bpe, qwen) -> None:
    config = config_for_tokenizer(Qwen3VLConfig.small(), bpe)
    assert config.text.vocab_size % 128 == 0 and bpe.vocab_size <= config.text.vocab_size < bpe.vocab_size + 128
    assert (config.image_token_id, config.video_token_id, config.vision_start_token_id,
            config.vision_end_token_id) == (bpe.token_id("<|image_pad|>"), bpe.token_id("<|video_pad|>"),
                                            bpe.token_id("<|vision_start|>"), bpe.token_id("<|vision_end|>"))
    assert config.text.hidden_size == Qwen3VLConfig.small().text.hidden_size
    q = config_for_tokenizer(Qwen3VLConfig.small(), qwen)
    assert (q.text.vocab_size, q.image_token_id, q.vision_start_token_id) == (151680, 151655, 151652)


def test_transformers_loads_the_same_tokenizer(bpe, samples, tmp_path) -> None:
    bpe.save_pretrained(tmp_path, chat_template=VL_CHAT_TEMPLATE)
    hf = AutoTokenizer.from_pretrained(tmp_path)
    assert len(hf) == bpe.vocab_size
    assert (hf.eos_token_id, hf.pad_token_id) == (bpe.special.im_end, bpe.special.endoftext)
    for text in [*samples[-1], *ODD_TEXTS]:
        ids = hf(text, add_special_tokens=False)["input_ids"]
        assert ids == bpe.encode(text)
        assert hf.decode(ids) == bpe.decode(ids, skip_special_tokens=False)
    prompt, target, _ = samples[-1]
    messages = chat_messages(prompt, target)
    rendered = hf.apply_chat_template(messages, tokenize=False)
    hf_ids = hf(rendered, add_special_tokens=False)["input_ids"]
    ours = encode_chat(bpe, messages, np.array([[1, 2, 2], [1, 2, 2]]), merge_size=2)  # one pad per image
    assert hf_ids == ours.input_ids.tolist()


def test_cli_trains_on_the_train_split(samples, tmp_path) -> None:
    records = [Record(key=f"o/{i}/0", image_png=b"", seg_png=b"", prompt=p, target=t, program=g,
                      meta={"split": "train"}) for i, (p, t, g) in enumerate(samples[:4])]
    secret = " zyzzyvaquux" * 5  # only in a val record: must not be learned from the train split
    records.append(Record(key="o/9/0", image_png=b"", seg_png=b"", prompt=samples[4][0] + secret,
                          target=samples[4][1], meta={"split": "val"}))
    write_dataset(tmp_path / "data", records)
    for split in ("train", "all"):
        out = tmp_path / split
        argv = ["data", "tokenizer", "--data", str(tmp_path / "data"), "--vocab-size", "2048", "--out", str(out),
                "--split", split, "--quiet"]
        assert cli_main(argv) == 0
        tokenizer = load_tokenizer(out)
        assert tokenizer.vocab_size <= 2048
        assert (tokenizer._backend.token_to_id("Ġzyzzyvaquux") is not None) == (split == "all")
        assert AutoTokenizer.from_pretrained(out)(samples[5][1], add_special_tokens=False)["input_ids"] == \
            tokenizer.encode(samples[5][1])


def test_cli_reports_a_folder_without_manifest(tmp_path, capsys) -> None:
    assert cli_main(["data", "tokenizer", "--data", str(tmp_path), "--vocab-size", "1024",
                     "--out", str(tmp_path / "out")]) == 1
    assert "manifest.json" in capsys.readouterr().err
