"""Our numpy Qwen3-VL image processor against transformers' PIL-backend processor."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image
from transformers.models.qwen2_vl.image_processing_pil_qwen2_vl import Qwen2VLImageProcessorPil
from transformers.models.qwen2_vl.image_processing_pil_qwen2_vl import smart_resize as hf_smart_resize

from jax3dc.errors import InputFileError
from jax3dc.processing.processor import (
    ImageProcessorConfig,
    image_token_counts,
    load_image,
    preprocess_image,
    preprocess_images,
    smart_resize,
)


def hf_processor(config: ImageProcessorConfig) -> Qwen2VLImageProcessorPil:
    return Qwen2VLImageProcessorPil(
        patch_size=config.patch_size,
        merge_size=config.merge_size,
        temporal_patch_size=config.temporal_patch_size,
        image_mean=list(config.image_mean),
        image_std=list(config.image_std),
        size={"shortest_edge": config.min_pixels, "longest_edge": config.max_pixels},
    )


def assert_same_as_hf(images, config: ImageProcessorConfig) -> None:
    expected = hf_processor(config)(images=list(images), return_tensors="np")
    ours = preprocess_images(images, config)
    np.testing.assert_array_equal(ours.image_grid_thw, expected["image_grid_thw"])
    assert ours.pixel_values.dtype == np.float32
    np.testing.assert_allclose(ours.pixel_values, expected["pixel_values"], rtol=0, atol=1e-6)


def random_image(height: int, width: int, mode: str = "RGB", seed: int = 0) -> Image.Image:
    rng = np.random.default_rng(seed)
    channels = {"RGB": 3, "RGBA": 4, "L": 1, "LA": 2}[mode]
    data = rng.integers(0, 256, (height, width, channels), dtype=np.uint8)
    if channels == 4:  # a real alpha ramp, some fully transparent pixels
        data[..., 3] = np.linspace(0, 255, width, dtype=np.uint8)[None, :]
    return Image.fromarray(data[..., 0] if channels == 1 else data, mode=mode)


@pytest.mark.parametrize(
    "height,width",
    [(448, 448), (37, 511), (255, 129), (1, 64), (640, 480), (1000, 333)],
)
def test_rgb_sizes_match_hf(height: int, width: int) -> None:
    assert_same_as_hf([random_image(height, width, seed=height * width)], ImageProcessorConfig.qwen3_vl())


def test_max_pixels_budget_matches_hf() -> None:
    config = ImageProcessorConfig(min_pixels=32 * 32, max_pixels=192 * 192)
    image = random_image(700, 1013)
    assert_same_as_hf([image], config)
    grid = preprocess_image(image, config).image_grid_thw[0]
    assert grid[1] * grid[2] * config.patch_size**2 <= config.max_pixels


def test_448_image_gives_196_tokens() -> None:
    processed = preprocess_image(random_image(448, 448))
    assert processed.image_grid_thw.tolist() == [[1, 28, 28]]
    assert image_token_counts(processed.image_grid_thw, 2) == [196]
    assert processed.pixel_values.shape == (784, 3 * 2 * 16 * 16)


@pytest.mark.parametrize("mode", ["RGBA", "L", "LA"])
def test_png_modes_match_hf(tmp_path, mode: str) -> None:
    path = tmp_path / f"image_{mode}.png"
    random_image(301, 157, mode=mode, seed=3).save(path)
    with Image.open(path) as reference:
        reference.load()
        assert_same_as_hf([reference], ImageProcessorConfig.qwen3_vl())
    from_path = preprocess_image(str(path))  # our own loader gives the same patches
    expected = hf_processor(ImageProcessorConfig.qwen3_vl())(images=[load_image(path)], return_tensors="np")
    np.testing.assert_allclose(from_path.pixel_values, expected["pixel_values"], rtol=0, atol=1e-6)


def test_palette_png_with_transparency_matches_hf(tmp_path) -> None:
    image = random_image(90, 120).convert("P", palette=Image.Palette.ADAPTIVE, colors=16)
    image.info["transparency"] = 0
    path = tmp_path / "palette.png"
    image.save(path, transparency=0)
    assert_same_as_hf([load_image(path)], ImageProcessorConfig.qwen3_vl())


def test_several_images_concatenate_in_order() -> None:
    images = [random_image(100, 200, seed=1), random_image(333, 90, seed=2)]
    assert_same_as_hf(images, ImageProcessorConfig.qwen3_vl())


def test_uint8_array_input_equals_pil_input() -> None:
    image = random_image(77, 91, seed=5)
    np.testing.assert_array_equal(
        preprocess_image(np.asarray(image)).pixel_values, preprocess_image(image).pixel_values
    )


def test_config_from_checkpoint_dir(tmp_path) -> None:
    (tmp_path / "preprocessor_config.json").write_text(
        json.dumps(
            {
                "size": {"longest_edge": 1000000, "shortest_edge": 4096},
                "patch_size": 14,
                "temporal_patch_size": 2,
                "merge_size": 2,
                "image_mean": [0.4, 0.5, 0.6],
                "image_std": [0.2, 0.3, 0.4],
            }
        )
    )
    config = ImageProcessorConfig.from_pretrained(tmp_path)
    assert (config.patch_size, config.min_pixels, config.max_pixels) == (14, 4096, 1000000)
    assert config.image_mean == (0.4, 0.5, 0.6)
    assert_same_as_hf([random_image(123, 321, seed=9)], config)


@settings(max_examples=200, deadline=None)
@given(
    height=st.integers(1, 6000),
    width=st.integers(1, 6000),
    min_side=st.sampled_from([32, 64, 256]),
    max_side=st.sampled_from([256, 512, 4096]),
)
def test_smart_resize_matches_hf(height: int, width: int, min_side: int, max_side: int) -> None:
    if max(height, width) / min(height, width) > 200:
        with pytest.raises(ValueError):
            smart_resize(height, width, 32, min_side**2, max_side**2)
        return
    ours = smart_resize(height, width, 32, min_side**2, max_side**2)
    assert ours == hf_smart_resize(height, width, 32, min_side**2, max_side**2)
    assert ours[0] % 32 == 0 and ours[1] % 32 == 0


def test_corrupt_png_is_input_file_error(tmp_path) -> None:
    good = tmp_path / "good.png"
    random_image(64, 64).save(good)
    corrupt = tmp_path / "corrupt.png"
    corrupt.write_bytes(good.read_bytes()[: len(good.read_bytes()) // 2])
    with pytest.raises(InputFileError) as info:
        preprocess_image(str(corrupt))
    assert info.value.path == str(corrupt)


def test_not_an_image_is_input_file_error(tmp_path) -> None:
    text = tmp_path / "notes.png"
    text.write_text("this is not a PNG")
    with pytest.raises(InputFileError, match="not an image"):
        preprocess_image(text)
    with pytest.raises(InputFileError, match="not found"):
        preprocess_image(tmp_path / "missing.png")


def test_extreme_aspect_ratio_is_input_file_error() -> None:
    with pytest.raises(InputFileError, match="aspect ratio"):
        preprocess_image(random_image(2, 500))


def test_saved_config_round_trips_and_loads_in_transformers(tmp_path) -> None:
    config = ImageProcessorConfig(min_pixels=64 * 64, max_pixels=320 * 320)
    config.save_pretrained(tmp_path)
    assert ImageProcessorConfig.from_pretrained(tmp_path) == config
    hf = Qwen2VLImageProcessorPil.from_pretrained(tmp_path)
    image = random_image(500, 410, seed=11)
    expected = hf(images=[image], return_tensors="np")
    ours = preprocess_image(image, config)
    np.testing.assert_array_equal(ours.image_grid_thw, expected["image_grid_thw"])
    np.testing.assert_allclose(ours.pixel_values, expected["pixel_values"], rtol=0, atol=1e-6)


def test_load_image_refuses_too_many_pixels_before_decoding(tmp_path):
    from PIL import Image as PILImage

    from jax3dc.errors import InputFileError
    from jax3dc.processing.processor import load_image

    path = tmp_path / "wide.png"
    PILImage.new("L", (3000, 2000)).save(path)
    with pytest.raises(InputFileError, match="3000 x 2000 pixels; the cap is 5000000"):
        load_image(path, max_pixels=5_000_000)
    assert load_image(path, max_pixels=6_000_000).size == (3000, 2000)
