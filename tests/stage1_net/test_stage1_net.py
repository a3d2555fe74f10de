"""The stage-1 image network: shapes, decoding that always yields a record the factory runs, the
folder round trip, and clear errors for a wrong folder or an unreadable image."""

from __future__ import annotations

import json

import numpy as np
import pytest
import safetensors.numpy
from flax import nnx

from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.errors import InputFileError
from jax3dc.parameters import parse_parameters
from jax3dc.processing.processor import MIN_IMAGE_SIDE
from jax3dc.stage1_net import (
    MARKER, ImageInputError, OutputLayout, Stage1Net, Stage1NetConfig, decode_text, forward, load_network, load_reader,
    network_image, save_network, schemas_from_json, schemas_to_json,
)
from train.stage1_net import targets

LAYOUT = OutputLayout.of(SCHEMAS)
TINY = dict(image_size=32, widths=(8, 8, 16, 16), reduced=8, hidden=16)


def tiny_model(seed: int = 0) -> Stage1Net:
    return Stage1Net(Stage1NetConfig.for_layout(LAYOUT, **TINY), nnx.Rngs(seed))


def test_output_shapes_follow_the_layout():
    category, numbers, discrete = forward(tiny_model(), np.zeros((3, 32, 32, 3), np.float32))
    assert category.shape == (3, len(SCHEMAS))
    assert numbers.shape == (3, len(LAYOUT.numbers))
    assert discrete.shape == (3, len(LAYOUT.discrete), LAYOUT.max_classes)


def test_every_value_has_one_head_index_of_its_category():
    numbers, discrete = LAYOUT.category_masks()
    assert numbers.sum(0).tolist() == [1] * len(LAYOUT.numbers)
    assert discrete.sum(0).tolist() == [1] * len(LAYOUT.discrete)
    assert LAYOUT.class_mask().sum() == sum(int(row.sum()) for row in LAYOUT.class_mask())


@pytest.mark.parametrize("category", sorted(SCHEMAS))
def test_random_and_hostile_outputs_decode_into_a_record_that_runs(category):
    rng = np.random.default_rng(len(category))
    logits = rng.normal(size=len(LAYOUT.categories))
    logits[LAYOUT.categories.index(category)] = 50.0
    numbers = rng.normal(0.5, 3.0, len(LAYOUT.numbers))  # far outside [0, 1] too
    numbers[::7] = np.nan
    discrete = rng.normal(size=(len(LAYOUT.discrete), LAYOUT.max_classes)) * 10
    discrete[:, -1] = 1e6  # a padded class beyond an entry's real ones must never be chosen
    discrete[::5] = np.nan
    text = decode_text(LAYOUT, SCHEMAS, logits, numbers, discrete)
    params = parse_parameters(text, SCHEMAS)
    assert params.category == category
    assert run_parameters(params).parts


def test_targets_decode_back_to_the_records_own_text():
    texts = ["cabinet(width=0.812, depth=0.4, height=1.1, wood=2, handle_metal=0, bar_handles=1, drawer_row=0, "
             "drawer_height=0.12, shelves=3, door_opening=1.75, two_doors=1, hinge_left=0)",
             "simple_bookcase(width=0.7, depth=0.3, height=1.5, wood=1, shelf_spacing=0.33, book_height=0.2, "
             "book_width=0.03, books=(2, 6, 3, 4, 5), book_offset=(0, 0.2, 0.1, 0.05, 0.111))"]
    t = targets([np.zeros((4, 4, 3), np.uint8)] * 2, texts, LAYOUT, SCHEMAS)
    for i, text in enumerate(texts):
        logits = np.eye(len(LAYOUT.categories))[t.category[i]]
        discrete = np.eye(LAYOUT.max_classes)[t.discrete[i]]
        assert decode_text(LAYOUT, SCHEMAS, logits, t.numbers[i], discrete) == text


def test_schemas_survive_their_json():
    assert schemas_from_json(json.loads(json.dumps(schemas_to_json(SCHEMAS)))) == SCHEMAS


def test_folder_round_trip_and_an_untrained_reader_always_answers(tmp_path):
    model = tiny_model()
    save_network(tmp_path / "a", model, SCHEMAS)
    network = load_network(tmp_path / "a")
    images = np.random.default_rng(0).random((2, 32, 32, 3), dtype=np.float32)
    for ours, theirs in zip(forward(model, images), forward(network.model, images)):
        np.testing.assert_allclose(np.asarray(ours), np.asarray(theirs), atol=2e-2)
    save_network(tmp_path / "b", network.model, network.schemas)
    a = safetensors.numpy.load_file(str(tmp_path / "a" / "model.safetensors"))
    b = safetensors.numpy.load_file(str(tmp_path / "b" / "model.safetensors"))
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    read = load_reader(tmp_path / "a")
    for shape in [(32, 32, 3), (MIN_IMAGE_SIDE, 300, 3), (480, 640, 3)]:  # the floor, elongated
        text = read(np.random.default_rng(1).integers(0, 256, shape, dtype=np.uint8))
        assert run_parameters(parse_parameters(text, SCHEMAS)).parts


def test_a_wrong_folder_names_the_file(tmp_path):
    with pytest.raises(InputFileError, match=MARKER):
        load_reader(tmp_path)
    save_network(tmp_path, tiny_model(), SCHEMAS)
    (tmp_path / "model.safetensors").unlink()
    with pytest.raises(InputFileError, match="model.safetensors: missing"):
        load_reader(tmp_path)
    (tmp_path / "model.safetensors").write_bytes(b"not safetensors")
    with pytest.raises(InputFileError, match="model.safetensors: not a readable"):
        load_reader(tmp_path)
    (tmp_path / MARKER).write_text("{")
    with pytest.raises(InputFileError, match=f"{MARKER}: not valid JSON"):
        load_reader(tmp_path)


def test_weights_of_another_shape_name_the_tensor(tmp_path):
    save_network(tmp_path, Stage1Net(Stage1NetConfig.for_layout(LAYOUT, **{**TINY, "hidden": 12}), nnx.Rngs(0)),
                 SCHEMAS)
    marker = json.loads((tmp_path / MARKER).read_text())
    marker["config"]["hidden"] = 16
    (tmp_path / MARKER).write_text(json.dumps(marker))
    with pytest.raises(InputFileError, match="tensor 'category.kernel' has shape"):
        load_network(tmp_path)


@pytest.mark.parametrize("image, problem", [
    (np.zeros((32, 32), np.uint8), "shape"),
    (np.zeros((32, 32, 4), np.uint8), "shape"),
    (np.zeros((32, 32, 3), np.float32), "uint8"),
    (np.zeros((8, 300, 3), np.uint8), "too small"),
    (np.zeros((MIN_IMAGE_SIDE - 1, 300, 3), np.uint8), "too small"),  # the floor predict's image check holds to
    ([[0, 0, 0]], "numpy array"),
    (np.full((64, 64, 3), 128, np.uint8), "no object"),
])
def test_an_unreadable_image_is_a_clear_error(image, problem):
    with pytest.raises(ImageInputError, match=problem):
        network_image(image, 32)


def test_a_non_square_image_is_padded_with_its_border_colour():
    image = np.full((40, 80, 3), 200, np.uint8)
    image[10:30, 30:50] = 10
    out = network_image(image, 80)
    assert out.shape == (80, 80, 3)
    assert np.allclose(out[0], 200 / 255) and np.allclose(out[-1], 200 / 255)
    assert out[40, 40, 0] < 0.1
