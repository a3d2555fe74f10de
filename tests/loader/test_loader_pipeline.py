"""The grain pipeline: resumable state, per-process shards, skipped records, mixtures, workers."""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from data_pipeline.loader import LoaderConfig, LoaderError, ShardLoader, _source
from data_pipeline.record import decode_record, encode_record
from data_pipeline.shards import shard_paths
from jax3dc.processing.tokenizer import load_tokenizer
from tests.loader.loader_fixtures import CATEGORIES, IMAGE, record, tiny_config, tiny_processor, write_dataset, write_shard

ROWS, SEQ = 2, 2400


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    records = [record(c, s) for s in range(2) for c in CATEGORIES]  # 16 records
    return write_dataset(tmp_path_factory.mktemp("ds"), records, shards=3)


def loader(sources, **kw) -> ShardLoader:
    cfg = LoaderConfig(sources=tuple(map(str, sources)), seq_len=SEQ, rows=ROWS, pack=2, image_size=IMAGE, **kw)
    return ShardLoader.create(cfg, tiny_config(), load_tokenizer(), tiny_processor())


def same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_batches_follow_the_protocol(dataset: Path) -> None:
    from train.batch import check_batch

    batch = next(loader([dataset]))
    check_batch(batch, ROWS, SEQ)
    assert batch["segment_ids"].max() >= 2  # two examples share a row
    assert batch["pixel_values"].shape == (ROWS, 2 * 2 * 64, 96)


def test_restored_state_gives_the_next_batches(dataset: Path) -> None:
    first = loader([dataset], seed=5)
    for _ in range(3):
        next(first)
    state = first.get_state()
    expected = [next(first) for _ in range(4)]  # crosses an epoch boundary (16 records, 2-4 per batch)
    second = loader([dataset], seed=5)
    second.set_state(state)
    for want in expected:
        assert same(next(second), want)
    other = loader([dataset], seed=6)
    assert not all(same(next(other), want) for want in expected[:2])


def test_process_slices_are_disjoint_and_cover(dataset: Path) -> None:
    paths = shard_paths([dataset], "train")
    everything = set()
    for index in range(3):
        cfg = LoaderConfig(sources=(str(dataset),), seq_len=SEQ, rows=ROWS, image_size=IMAGE,
                           process_index=index, process_count=3, shuffle=True)
        ds, _ = _source(paths, cfg)
        size = 6 if index == 0 else 5  # 16 records over 3 processes
        epoch = [decode_record(ds[i]).key for i in range(size)]
        assert len(set(epoch)) == size and set(epoch) == {decode_record(ds[size + i]).key for i in range(size)}
        assert not set(epoch) & everything
        everything |= set(epoch)
    assert len(everything) == 16


def test_corrupt_and_too_long_records_are_skipped_and_counted(tmp_path: Path) -> None:
    good = [record(c, 0) for c in CATEGORIES[:4]]
    broken_png = dataclasses.replace(record("door", 1), image_png=b"\x89PNG not really")
    blobs = [encode_record(r) for r in good[:2]] + [b"garbage bytes", encode_record(broken_png)] + \
            [encode_record(r) for r in good[2:]]
    huge = dataclasses.replace(record("faucet", 2), target="[" + "1," * 4000 + "1]")
    blobs.append(encode_record(huge))
    write_shard(tmp_path / "train-00000.array_record", blobs)
    it = loader([tmp_path], shuffle=False)
    for _ in range(3):
        next(it)
    assert it.skipped["corrupt"] >= 2 and it.skipped["too_long"] >= 1
    restored = loader([tmp_path], shuffle=False)
    restored.set_state(it.get_state())
    assert restored.skipped == it.skipped


def test_a_split_without_usable_records_is_an_error_not_a_hang(dataset: Path, tmp_path: Path) -> None:
    """The records repeat forever: a split that has none (all train here) or only broken ones
    must end with an error naming the split and what was skipped, not loop."""
    with pytest.raises(LoaderError, match=r"split 'val' .*\(16 records\): no usable record.*other_split"):
        next(loader([dataset], split="val"))
    write_shard(tmp_path / "train-00000.array_record", [b"garbage"] * 3)
    with pytest.raises(LoaderError, match=r"no usable record.*corrupt"):
        next(loader([tmp_path]))


def solid_png(value: int) -> bytes:
    buf = io.BytesIO()
    Image.new("RGB", (IMAGE, IMAGE), (value, value, value)).save(buf, format="PNG")
    return buf.getvalue()


@pytest.fixture(scope="module")
def two_sources(tmp_path_factory) -> tuple[Path, Path]:
    """Two datasets of different categories whose images tell them apart in a batch: all black in
    ``a`` (pixels normalise to about -1), all white in ``b`` (about +1)."""
    root = tmp_path_factory.mktemp("mix")

    def painted(categories, seed, value):
        return [dataclasses.replace(record(c, seed), image_png=solid_png(value), seg_png=solid_png(value))
                for c in categories]

    a = write_dataset(root / "a", painted(CATEGORIES[:4], 0, 0), shards=1)
    b = write_dataset(root / "b", painted(CATEGORIES[4:], 1, 255), shards=1)
    return a, b


MIX_DRAWS = 200  # examples drawn through the loader per weighting


def drawn_sources(sources, weights, seed: int = 0, n: int = MIX_DRAWS) -> list[str]:
    """Which source ("a" or "b") each of the first ``n`` examples our loader packs came from."""
    it = loader(sources, weights=weights, seed=seed)
    per_image = 64  # patches of one 32 x 32 image (patch 4)
    out: list[str] = []
    while len(out) < n:
        batch = next(it)
        for row in range(ROWS):
            for slot in range(int(batch["segment_ids"][row].max())):
                first = slot * 2 * per_image  # two images (I and S) per example
                mean = float(batch["pixel_values"][row, first:first + per_image].mean())
                assert abs(abs(mean) - 1) < 0.1, mean
                out.append("a" if mean < 0 else "b")
    assert not it.skipped, it.skipped  # every record was used: the shares are the mixture's
    return out[:n]


def test_mixture_follows_the_weights(two_sources) -> None:
    """Our loader (LoaderConfig.weights) mixes its sources in the configured proportion."""
    a, b = two_sources
    tol = 0.05
    drawn = drawn_sources([a, b], (0.8, 0.2))
    share = drawn.count("a") / len(drawn)
    assert abs(share - 0.8) < tol, f"share of source a {share:.3f} with weights 0.8/0.2"
    assert drawn == drawn_sources([a, b], (0.8, 0.2)), "same seed, same mixture order"
    swapped = drawn_sources([a, b], (0.2, 0.8))
    share = swapped.count("a") / len(swapped)
    assert abs(share - 0.2) < tol, f"share of source a {share:.3f} with weights 0.2/0.8"
    scaled = drawn_sources([a, b], (4.0, 1.0))  # weights are relative
    assert abs(scaled.count("a") / len(scaled) - 0.8) < tol
    nearly_a = drawn_sources([a, b], (1.0, 0.01), n=100)  # grain refuses a weight of exactly 0
    assert nearly_a.count("b") <= 2, f"weight 0.01 for b, yet {nearly_a.count('b')} of 100 examples came from b"
    even = drawn_sources([a, b], ())  # no weights: equal shares
    assert abs(even.count("a") / len(even) - 0.5) < tol


def test_mixture_weights_are_checked(two_sources) -> None:
    a, b = two_sources
    with pytest.raises(LoaderError, match="weights"):
        loader([a, b], weights=(1.0,))
    with pytest.raises(LoaderError, match="weights"):
        loader([a, b], weights=(1.0, -0.5))
    with pytest.raises(LoaderError, match="leave a source out"):
        loader([a, b], weights=(1.0, 0.0))


def test_one_folder_feeds_both_tasks(dataset: Path) -> None:
    """The same folder under two tasks: rows carry structure examples (I, S, prompt) and code
    examples (I alone) in the configured proportion, each example's images in order."""
    merged = 64 // 4  # image tokens of one 32 x 32 image (patch 4, merge 2)
    it = loader([dataset, dataset], tasks=("structure", "code"), weights=(0.5, 0.5))
    images = []
    for _ in range(12):
        batch = next(it)
        for row in range(ROWS):
            ids, seg = batch["input_ids"][row], batch["segment_ids"][row]
            for s in range(1, int(seg.max()) + 1):
                images.append(int((ids[seg == s] == tiny_config().image_token_id).sum()) // merged)
    assert set(images) == {1, 2}, images
    assert 0.25 < images.count(1) / len(images) < 0.75
    with pytest.raises(LoaderError, match="2 sources"):
        loader([dataset, dataset], tasks=("code",))
    with pytest.raises(LoaderError, match="'codes'"):
        loader([dataset], tasks=("codes",))


def test_wrong_tokenizer_for_the_model_is_refused(dataset: Path) -> None:
    from jax3dc.model.config import Qwen3VLConfig

    cfg = LoaderConfig(sources=(str(dataset),), seq_len=SEQ, rows=ROWS, image_size=IMAGE)
    with pytest.raises(LoaderError, match="image_pad"):
        ShardLoader.create(cfg, Qwen3VLConfig.tiny(), load_tokenizer(), tiny_processor())


@pytest.mark.slow
def test_worker_processes_give_the_same_resumable_stream(dataset: Path) -> None:
    """With 2 grain workers the stream is deterministic and its state restores exactly."""
    first = loader([dataset], seed=1, workers=2)
    batches = [next(first) for _ in range(2)]
    state = first.get_state()
    expected = [next(first) for _ in range(2)]
    again = loader([dataset], seed=1, workers=2)
    assert all(same(next(again), want) for want in batches)
    resumed = loader([dataset], seed=1, workers=2)
    resumed.set_state(state)
    for want in expected:
        assert same(next(resumed), want)
