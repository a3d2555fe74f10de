"""Training the stage-1 image network: the device-side augmentation, the learning rate that a time
limit decays, more blocks per width, and a few steps that learn a set the network can tell apart."""

from __future__ import annotations

import jax
import numpy as np
import pytest
from flax import nnx

from jax3dc.factories.registry import SCHEMAS, generate_object
from jax3dc.parameters import format_parameters
from jax3dc.stage1_net import OutputLayout, Stage1Net, Stage1NetConfig, load_network, save_network
from train.stage1_net import TrainConfig, accuracy, augment, learning_rate, targets, train

LAYOUT = OutputLayout.of(SCHEMAS)


def test_augment_keeps_shape_and_range_and_depends_only_on_its_key():
    images = np.random.default_rng(0).integers(0, 256, (4, 20, 20, 3), dtype=np.uint8)
    a = np.asarray(augment(images, jax.random.key(1), 3))
    b = np.asarray(augment(images, jax.random.key(1), 3))
    c = np.asarray(augment(images, jax.random.key(2), 3))
    assert a.shape == (4, 20, 20, 3) and a.dtype == np.float32
    assert a.min() >= 0.0 and a.max() <= 1.0
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_augment_of_a_flat_image_stays_flat_per_channel():
    """A shift with repeated edges and a contrast change about the mean leave one colour one colour."""
    images = np.full((2, 16, 16, 3), 120, np.uint8)
    out = np.asarray(augment(images, jax.random.key(0), 4))
    np.testing.assert_allclose(out.std(axis=(1, 2)), 0.0, atol=1e-6)


def test_learning_rate_warms_up_then_decays_with_steps_or_time():
    config = TrainConfig(steps=1000, lr=1e-3, warmup=100)
    assert learning_rate(config, 50, 0.05) == pytest.approx(5e-4)
    assert learning_rate(config, 101, 0.101) < 1e-3
    assert learning_rate(config, 1000, 1.0) == pytest.approx(2e-5)
    # the time limit three quarters used at step 200: the rate is that of three quarters of the run
    assert learning_rate(config, 200, 0.75) == pytest.approx(learning_rate(config, 750, 0.75))
    assert learning_rate(config, 200, 0.75) < learning_rate(config, 200, 0.2)


def test_more_blocks_per_width_round_trip_and_old_markers_read_as_one(tmp_path):
    config = Stage1NetConfig.for_layout(LAYOUT, image_size=32, widths=(8, 16), reduced=4, hidden=8, blocks=2)
    model = Stage1Net(config, nnx.Rngs(0))
    assert len(model.blocks) == 4
    save_network(tmp_path, model, SCHEMAS)
    assert load_network(tmp_path).model.config == config
    data = config.to_json()
    del data["blocks"]
    assert Stage1NetConfig.from_json(data).blocks == 1
    with pytest.raises(ValueError, match="at least one block"):
        Stage1NetConfig.for_layout(LAYOUT, blocks=0)


def test_a_few_steps_learn_categories_told_apart_by_colour():
    """Two categories drawn as two flat colours: the category head must learn them in 60 steps."""
    names = ["bucket", "globe"]
    texts, images = [], []
    for i in range(32):
        name = names[i % 2]
        texts.append(format_parameters(generate_object(name, i).parameters, SCHEMAS[name]))
        image = np.zeros((32, 32, 3), np.uint8)
        image[8:24, 8:24] = (220, 40, 40) if name == "bucket" else (40, 40, 220)
        images.append(image)
    data = targets(images, texts, LAYOUT, SCHEMAS)
    model = Stage1Net(Stage1NetConfig.for_layout(LAYOUT, image_size=32, widths=(8, 16), reduced=4, hidden=16),
                      nnx.Rngs(0))
    rows = train(model, data, LAYOUT, TrainConfig(steps=60, batch=16, lr=3e-3, warmup=5, shift=2, log_every=20,
                                                  time_limit_s=600.0), on_log=lambda row: None)
    assert [r["step"] for r in rows] == [20, 40, 60]
    assert rows[-1]["category_ce"] < rows[0]["category_ce"]
    assert accuracy(model, data, LAYOUT)["category"] == 1.0
