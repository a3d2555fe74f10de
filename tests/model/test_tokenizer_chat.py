"""Chat formatting against transformers' Qwen3VLProcessor fed our Qwen3-VL template."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from transformers import AutoTokenizer, Qwen3VLProcessor
from transformers.models.qwen2_vl.image_processing_pil_qwen2_vl import Qwen2VLImageProcessorPil

from jax3dc.processing.chat import IGNORE_INDEX, VL_CHAT_TEMPLATE, encode_chat, render_chat
from jax3dc.processing.processor import ImageProcessorConfig, image_token_counts, preprocess_images
from jax3dc.processing.tokenizer import default_tokenizer_dir, load_tokenizer


class ImageOnlyQwen3VLProcessor(Qwen3VLProcessor):
    """Qwen3VLProcessor without its video processor, which needs torchvision (not installed)."""

    def check_argument_for_proper_class(self, argument_name, argument):
        if argument_name == "video_processor" and argument is None:
            return None
        return super().check_argument_for_proper_class(argument_name, argument)


@pytest.fixture(scope="module")
def hf_processor():
    config = ImageProcessorConfig.qwen3_vl()
    image_processor = Qwen2VLImageProcessorPil(
        patch_size=config.patch_size,
        merge_size=config.merge_size,
        temporal_patch_size=config.temporal_patch_size,
        image_mean=list(config.image_mean),
        image_std=list(config.image_std),
        size={"shortest_edge": config.min_pixels, "longest_edge": config.max_pixels},
    )
    tokenizer = AutoTokenizer.from_pretrained(default_tokenizer_dir())
    return ImageOnlyQwen3VLProcessor(
        image_processor=image_processor, tokenizer=tokenizer, video_processor=None, chat_template=VL_CHAT_TEMPLATE
    )


@pytest.fixture(scope="module")
def tokenizer():
    return load_tokenizer()


def images(seed: int = 0) -> list[Image.Image]:
    rng = np.random.default_rng(seed)
    return [
        Image.fromarray(rng.integers(0, 256, (300, 200, 3), dtype=np.uint8)),
        Image.fromarray(rng.integers(0, 256, (64, 500, 3), dtype=np.uint8)),
    ]


PROMPT = "Parts (id: colour | centroid | extent):\n1: #3a7bd5 | 0.000 0.012 -0.100 | 1.000 0.600 0.800\nJoints: 3"
ANSWER = '{"materials":{"1":"wood"},"nodes":{"1":{"parent":null,"name":"drawer é中"}}}'


def training_messages(pictures, system: bool = False) -> list[dict]:
    messages = [{"role": "system", "content": "You are a careful modeller."}] if system else []
    messages.append(
        {
            "role": "user",
            "content": [{"type": "image", "image": p} for p in pictures] + [{"type": "text", "text": PROMPT}],
        }
    )
    messages.append({"role": "assistant", "content": ANSWER})
    return messages


@pytest.mark.parametrize("system", [False, True])
def test_training_example_token_identical(hf_processor, tokenizer, system: bool) -> None:
    pictures = images()
    messages = training_messages(pictures, system)
    expected = hf_processor.apply_chat_template(messages, tokenize=True, return_dict=True, return_tensors="np")
    processed = preprocess_images(pictures)
    ours = encode_chat(tokenizer, messages, processed.image_grid_thw)
    np.testing.assert_array_equal(ours.input_ids, expected["input_ids"][0])
    np.testing.assert_array_equal(processed.pixel_values, expected["pixel_values"])
    image_positions = ours.input_ids == tokenizer.special.image_pad
    np.testing.assert_array_equal(image_positions, expected["mm_token_type_ids"][0] == 1)
    assert image_positions.sum() == sum(image_token_counts(processed.image_grid_thw, 2))


def test_generation_prompt_token_identical(hf_processor, tokenizer) -> None:
    pictures = images(1)
    messages = training_messages(pictures)[:1]
    expected = hf_processor.apply_chat_template(
        messages, tokenize=True, return_dict=True, return_tensors="np", add_generation_prompt=True
    )
    ours = encode_chat(tokenizer, messages, preprocess_images(pictures).image_grid_thw, add_generation_prompt=True)
    np.testing.assert_array_equal(ours.input_ids, expected["input_ids"][0])
    assert tokenizer.decode(ours.input_ids[-3:], skip_special_tokens=False) == "<|im_start|>assistant\n"
    assert (ours.labels == IGNORE_INDEX).all()


def test_labels_cover_exactly_the_answer_and_im_end(tokenizer) -> None:
    pictures = images()
    grid = preprocess_images(pictures).image_grid_thw
    encoded = encode_chat(tokenizer, training_messages(pictures, system=True), grid)
    carried = np.flatnonzero(encoded.labels != IGNORE_INDEX)
    assert (np.diff(carried) == 1).all()  # one contiguous run
    assert tokenizer.decode(encoded.labels[carried], skip_special_tokens=False) == ANSWER + "<|im_end|>"
    np.testing.assert_array_equal(encoded.labels[carried], encoded.input_ids[carried])
    assert carried[-1] == len(encoded) - 2  # only the trailing "\n" follows the <|im_end|>
    header = tokenizer.decode(encoded.input_ids[carried[0] - 3 : carried[0]], skip_special_tokens=False)
    assert header == "<|im_start|>assistant\n"


def test_multi_turn_labels_every_assistant_turn(tokenizer) -> None:
    messages = [
        {"role": "user", "content": "first"},
        {"role": "assistant", "content": "one"},
        {"role": "user", "content": "second"},
        {"role": "assistant", "content": "two two"},
    ]
    encoded = encode_chat(tokenizer, messages)
    text = tokenizer.decode(encoded.labels[encoded.labels != IGNORE_INDEX], skip_special_tokens=False)
    assert text == "one<|im_end|>two two<|im_end|>"


def test_pad_count_follows_grid(tokenizer) -> None:
    text, _ = render_chat([{"role": "user", "content": [{"type": "image"}, {"type": "text", "text": "x"}]}], [196])
    assert text.count("<|image_pad|>") == 196
    grid = np.array([[1, 28, 28]])
    encoded = encode_chat(tokenizer, [{"role": "user", "content": [{"type": "image"}]}], grid)
    assert (encoded.input_ids == tokenizer.special.image_pad).sum() == 196


def test_image_grid_count_mismatch_is_an_error(tokenizer) -> None:
    one_image = [{"role": "user", "content": [{"type": "image"}, {"type": "text", "text": "x"}]}]
    with pytest.raises(ValueError, match="more image items"):
        encode_chat(tokenizer, one_image, np.zeros((0, 3), dtype=int))
    with pytest.raises(ValueError, match="left over"):
        encode_chat(tokenizer, one_image, np.array([[1, 4, 4], [1, 4, 4]]))
    with pytest.raises(ValueError, match="role"):
        encode_chat(tokenizer, [{"role": "tool", "content": "x"}])


def test_stage2_messages_from_prompt_module(hf_processor, tokenizer) -> None:
    """The project's stage-2 messages (images I and S, prompt, target JSON) encode like transformers."""
    from jax3dc.prompt import chat_messages

    pictures = images(2)
    messages = chat_messages(PROMPT, ANSWER)
    processed = preprocess_images(pictures)
    ours = encode_chat(tokenizer, messages, processed.image_grid_thw)
    with_images = [dict(m) for m in messages]
    items = iter(pictures)
    with_images[0] = {"role": "user", "content": [
        {**item, "image": next(items)} if item.get("type") == "image" else item for item in messages[0]["content"]]}
    expected = hf_processor.apply_chat_template(with_images, tokenize=True, return_dict=True, return_tensors="np")
    np.testing.assert_array_equal(ours.input_ids, expected["input_ids"][0])
    carried = ours.labels[ours.labels != IGNORE_INDEX]
    assert tokenizer.decode(carried, skip_special_tokens=False) == ANSWER + "<|im_end|>"
