"""Config overrides and the batch protocol (no device work)."""

import numpy as np
import pytest

from train.batch import BatchError, ImageLayout, SyntheticBatches, check_batch
from train.config import ConfigError, TrainConfig, apply_overrides, validate


def test_overrides_reach_nested_fields_and_parse_types():
    cfg = apply_overrides(TrainConfig(), ["lr=2e-5", "mesh.fsdp=4", "master_fp32=false", "freeze=a,b"])
    assert cfg.lr == 2e-5 and cfg.mesh.fsdp == 4 and cfg.master_fp32 is False and cfg.freeze == ("a", "b")


@pytest.mark.parametrize("item", ["nosuch=1", "lr=abc", "mesh=3", "lr"])
def test_bad_overrides_raise_config_error(item):
    with pytest.raises(ConfigError):
        apply_overrides(TrainConfig(), [item])


def test_validate_rejects_batch_not_divisible_by_accumulation():
    with pytest.raises(ConfigError, match="grad_accum"):
        validate(TrainConfig(data="synthetic", batch_size=6, grad_accum=4))


@pytest.mark.parametrize("data", ["", " ", ","])
def test_validate_requires_data(data):
    with pytest.raises(ConfigError, match="^no training data: pass --set data=DIR") as e:
        validate(TrainConfig(data=data))
    assert "\n" not in str(e.value) and "data=synthetic" in str(e.value)


def test_validate_accepts_synthetic_and_folders():
    validate(TrainConfig(data="synthetic"))
    validate(apply_overrides(TrainConfig(), ["data=runs/a,runs/b"]))


def test_validate_checks_one_task_per_data_folder():
    both = apply_overrides(TrainConfig(), ["data=runs/a,runs/a", "data_tasks=structure,code"])
    validate(both)
    assert both.data_tasks == ("structure", "code")
    with pytest.raises(ConfigError, match="1 tasks for 2 data folders"):
        validate(apply_overrides(TrainConfig(), ["data=runs/a,runs/b", "data_tasks=code"]))
    with pytest.raises(ConfigError, match="'program'"):
        validate(apply_overrides(TrainConfig(), ["data=runs/a", "data_tasks=program"]))


def _loader(**kw):
    image = ImageLayout(100, 101, 102, (4, 4), 2, 12)
    return SyntheticBatches(vocab=128, text_vocab=100, seq_len=32, global_rows=4, image=image, **kw)


def test_synthetic_batches_follow_protocol_and_resume_exactly():
    a = _loader()
    first = next(a)
    check_batch(first, 4, 32)
    state = a.get_state()
    expected = next(a)
    b = _loader()
    b.set_state(state)
    got = next(b)
    for k in expected:
        np.testing.assert_array_equal(got[k], expected[k])
    assert not np.array_equal(first["input_ids"], expected["input_ids"])


def test_process_shards_are_the_rows_of_the_global_batch():
    whole = next(_loader())
    parts = [next(_loader(process_index=p, process_count=2)) for p in range(2)]
    np.testing.assert_array_equal(np.concatenate([p["input_ids"] for p in parts]), whole["input_ids"])


def test_labels_are_next_tokens_where_scored():
    batch = next(_loader())
    scored = batch["loss_mask"][:, :-1] > 0
    assert scored.any()
    np.testing.assert_array_equal(batch["labels"][:, :-1][scored], batch["input_ids"][:, 1:][scored])
    assert not (batch["loss_mask"][batch["input_ids"] == 101] > 0).any()


def test_check_batch_names_the_bad_key():
    batch = next(_loader())
    batch["labels"] = batch["labels"][:, :5]
    with pytest.raises(BatchError, match="labels"):
        check_batch(batch, 4, 32)
