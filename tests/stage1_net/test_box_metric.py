"""The stage-1 box metric: dᵀ M d must predict how far the factory's boxes really move, ignore what
moves nothing, survive a cache round trip, and drive the loss only through records that have one."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from jax3dc.factories.registry import SCHEMAS, generate_object, run_parameters
from jax3dc.parameters import format_parameters, parse_parameters
from jax3dc.parameters.schema import DECIMALS
from jax3dc.stage1_net import OutputLayout
from train import stage1_box_metric
from train.stage1_box_metric import MIN_EXTENT, box_metric, box_metrics
from train.stage1_net import box_loss, targets

LAYOUT = OutputLayout.of(SCHEMAS)


def _text(category: str, seed: int) -> str:
    return format_parameters(generate_object(category, seed).parameters, SCHEMAS[category])


def _relative_box_error(a: dict, b: dict) -> float:
    """The metric's own measure, computed from two factory runs: mean over parts of the squared
    corner moves divided by the first run's extents."""
    total = 0.0
    for pid, mesh in a.items():
        lo, hi = np.asarray(mesh.bounds)
        weight = 1.0 / np.maximum(hi - lo, MIN_EXTENT)
        total += float((((np.asarray(b[pid].bounds) - mesh.bounds) * weight) ** 2).sum())
    return total / len(a)


@pytest.mark.parametrize("category", ["cabinet", "drawer_chest", "table"])
def test_quadratic_form_predicts_the_factory_s_own_box_move(category):
    text = _text(category, 3)
    index, metric = box_metric(text, LAYOUT, SCHEMAS)
    params = parse_parameters(text, SCHEMAS)
    slots = {s.index: s for s in LAYOUT.numbers}
    # nudge the number the metric says matters most by 2 % of its range, the others untouched
    k = int(np.argmax(np.diag(metric)))
    slot = slots[int(index[k])]
    value = params[slot.spec.name] if slot.slot is None else params[slot.spec.name][slot.slot]
    span = slot.spec.hi - slot.spec.lo
    step = 0.02 if value + 0.02 * span <= slot.spec.hi else -0.02
    moved = round(value + step * span, DECIMALS)
    values = dict(params.values)
    values[slot.spec.name] = moved if slot.slot is None else tuple(
        moved if j == slot.slot else v for j, v in enumerate(values[slot.spec.name]))
    nudged = type(params)(params.category, values)
    actual = _relative_box_error(run_parameters(params).parts, run_parameters(nudged).parts)
    d = np.zeros(len(index))
    d[k] = (moved - value) / span
    predicted = float(d @ metric @ d)
    assert actual > 0
    assert predicted == pytest.approx(actual, rel=0.35)


def test_a_number_the_factory_never_reads_costs_nothing():
    """Every row is finite and symmetric; some category leaves one of its numbers unread, and the
    metric's row for it is zero."""
    zero_rows = 0
    for category in ("cabinet", "refrigerator", "washing_machine"):
        index, metric = box_metric(_text(category, 7), LAYOUT, SCHEMAS)
        assert len(index) == sum(1 for s in LAYOUT.numbers if s.category == category)
        assert np.isfinite(metric).all() and np.allclose(metric, metric.T, atol=1e-5)
        assert np.linalg.eigvalsh(metric).min() > -1e-4  # JᵀJ: never negative
        zero_rows += int((np.abs(metric).sum(axis=1) == 0).sum())
    assert zero_rows >= 1


def test_cache_round_trip_computes_each_text_once(tmp_path, monkeypatch):
    texts = [_text("bucket", 1), _text("globe", 2), _text("bucket", 1)]
    cache = tmp_path / "metric.jsonl"
    index, metric = box_metrics(texts, LAYOUT, SCHEMAS, 11, cache=cache)
    assert index.shape == (3, 11) and metric.shape == (3, 11, 11)
    assert (index[0] == index[2]).all() and len(cache.read_text().splitlines()) == 2
    assert (index[0, 3:] == -1).all() and not metric[0, 3:].any()

    def refuse(*args):
        raise AssertionError("a cached text was computed again")

    monkeypatch.setattr(stage1_box_metric, "box_metric", refuse)
    again_index, again_metric = box_metrics(texts, LAYOUT, SCHEMAS, 11, cache=cache)
    assert (again_index == index).all() and np.allclose(again_metric, metric, atol=1e-4)
    with pytest.raises(ValueError, match="more than the metric's width"):
        box_metrics(texts, LAYOUT, SCHEMAS, 1, cache=cache)


def test_box_loss_is_the_metric_s_norm_and_skips_records_without_one():
    texts = [_text("cabinet", 5), _text("table", 6)]
    index, metric = box_metrics(texts, LAYOUT, SCHEMAS, 11)
    data = targets([np.zeros((8, 8, 3), np.uint8)] * 2, texts, LAYOUT, SCHEMAS, (index, metric))
    batch = {f: jnp.asarray(getattr(data, f)) for f in ("numbers", "metric_index", "metric")}
    exact = jnp.asarray(data.numbers)
    assert float(box_loss(exact, batch)) == pytest.approx(0.0, abs=1e-6)
    rng = np.random.default_rng(0)
    wrong = data.numbers + rng.normal(0, 0.1, data.numbers.shape).astype(np.float32)
    expect = []
    for i in range(2):
        d = (wrong[i] - data.numbers[i])[index[i][index[i] >= 0]]
        k = len(d)
        expect.append(np.sqrt(d @ metric[i, :k, :k] @ d + 1e-4) - 1e-2)
    assert float(box_loss(jnp.asarray(wrong), batch)) == pytest.approx(np.mean(expect), rel=1e-4)
    # the second record without a metric: only the first counts
    batch["metric_index"] = batch["metric_index"].at[1].set(-1)
    assert float(box_loss(jnp.asarray(wrong), batch)) == pytest.approx(expect[0], rel=1e-4)
    with pytest.raises(ValueError, match="box metrics for 1 records"):
        targets([np.zeros((8, 8, 3), np.uint8)] * 2, texts, LAYOUT, SCHEMAS, (index[:1], metric[:1]))


def test_training_with_the_box_loss_logs_and_lowers_it():
    from flax import nnx

    from jax3dc.stage1_net import Stage1Net, Stage1NetConfig
    from train.stage1_net import TrainConfig, train

    texts = [_text("cabinet", i) for i in range(16)]
    images = [np.full((32, 32, 3), 40 + 10 * i, np.uint8) for i in range(16)]
    data = targets(images, texts, LAYOUT, SCHEMAS, box_metrics(texts, LAYOUT, SCHEMAS, 11))
    model = Stage1Net(Stage1NetConfig.for_layout(LAYOUT, image_size=32, widths=(8, 16), reduced=4, hidden=16),
                      nnx.Rngs(0))
    rows = train(model, data, LAYOUT, TrainConfig(steps=60, batch=16, lr=3e-3, warmup=5, shift=2, log_every=20,
                                                  box_weight=4.0, number_weight=1.0), on_log=lambda row: None)
    assert all("box" in r for r in rows)
    assert rows[-1]["box"] < rows[0]["box"]
