"""The stage-2 prompt: legend format, joint line, schema text and chat messages."""

import json
import re

import numpy as np

from jax3dc.palette import object_palette, part_colour
from jax3dc.prompt import LEGEND_HEADER, build_prompt, chat_messages
from jax3dc.structure import FAMILIES, JOINT_TYPES, PLANES, RELATION_TYPES, Box

LEGEND = re.compile(r"^(\d+): #([0-9a-f]{6}) \| (\S+) (\S+) (\S+) \| (\S+) (\S+) (\S+)$")

BOXES = {
    3: Box((0.25, -0.0001, 0.1234), (0.2, 0.05, 0.9)),
    1: Box((0.0, 0.0124, -0.1), (1.0, 0.6, 0.8)),
    2: Box((-0.4996, 0.3, 0.0), (0.001, 0.0004, 0.3333)),
}


def legend(text):
    return [LEGEND.match(line) for line in text.splitlines() if LEGEND.match(line)]


def test_legend_lines_colours_and_numbers():
    palette = object_palette("cabinet", "7")
    text = build_prompt(BOXES, palette, num_joints=2)
    lines = text.splitlines()
    start = lines.index(LEGEND_HEADER)
    rows = lines[start + 1: start + 4]
    assert [r.split(":")[0] for r in rows] == ["1", "2", "3"]  # ascending ids
    for row in rows:
        m = LEGEND.match(row)
        assert m, row
        pid = int(m.group(1))
        assert tuple(int(m.group(2)[k:k + 2], 16) for k in (0, 2, 4)) == part_colour(palette, pid)
        numbers = [m.group(k) for k in range(3, 9)]
        assert all(re.fullmatch(r"-?\d+\.\d{3}", v) for v in numbers)
        np.testing.assert_allclose([float(v) for v in numbers], [*BOXES[pid].centroid, *BOXES[pid].extent], atol=5e-4)
    assert rows[0].endswith("| 0.000 0.012 -0.100 | 1.000 0.600 0.800")
    assert "-0.000" not in text  # -0.0001 is written 0.000
    assert rows[1].endswith("| -0.500 0.300 0.000 | 0.001 0.000 0.333")


def test_joint_line_only_for_articulated_objects():
    palette = object_palette("cabinet", "7")
    assert "Joints: 3" in build_prompt(BOXES, palette, 3).splitlines()
    for n in (None, 0):
        assert not any(line.startswith("Joints") for line in build_prompt(BOXES, palette, n).splitlines())
    # the joint line sits after the legend and before the schema
    lines = build_prompt(BOXES, palette, 3).splitlines()
    assert lines.index("Joints: 3") == lines.index(LEGEND_HEADER) + len(BOXES) + 1


def test_schema_text_names_every_key_field_and_vocabulary():
    text = build_prompt(BOXES, object_palette("a", "b"), None)
    for word in ("materials", "nodes", "relations", "family", "desc", "parent", "material", "joint",
                 "axis", "pivot", "range", "plane", "null", *FAMILIES, *JOINT_TYPES, *PLANES, *RELATION_TYPES):
        assert f'"{word}"' in text or f" {word}" in text or f"{word}," in text, word
    assert "+Z up" in text and "-Y" in text and "3 decimals" in text


def test_same_object_same_prompt_other_object_other_colours():
    a = build_prompt(BOXES, object_palette("cabinet", "7"), 2)
    assert a == build_prompt(BOXES, object_palette("cabinet", "7"), 2)
    b = build_prompt(BOXES, object_palette("cabinet", "8"), 2)
    assert [m.group(2) for m in legend(a)] != [m.group(2) for m in legend(b)]
    assert [m.group(3) for m in legend(a)] == [m.group(3) for m in legend(b)]


def test_chat_messages_structure():
    msgs = chat_messages("PROMPT", '{"materials":{}}')
    assert msgs == [
        {"role": "user", "content": [{"type": "image"}, {"type": "image"}, {"type": "text", "text": "PROMPT"}]},
        {"role": "assistant", "content": [{"type": "text", "text": '{"materials":{}}'}]},
    ]
    assert chat_messages("PROMPT") == msgs[:1]
    json.dumps(msgs)  # plain JSON-able data


# A Qwen-VL style template written for this test (<|im_start|> turns, one vision block per image item).
QWEN_VL_STYLE = (
    "{% for m in messages %}<|im_start|>{{ m.role }}\n{% if m.content is string %}{{ m.content }}{% else %}"
    "{% for c in m.content %}{% if c.type == 'image' %}<|vision_start|><|image_pad|><|vision_end|>"
    "{% elif c.type == 'text' %}{{ c.text }}{% endif %}{% endfor %}{% endif %}<|im_end|>\n{% endfor %}"
    "{% if add_generation_prompt %}<|im_start|>assistant\n{% endif %}"
)


def test_messages_render_through_a_hugging_face_chat_template():
    from transformers import AutoTokenizer

    from jax3dc.processing.tokenizer import default_tokenizer_dir

    folder = default_tokenizer_dir()

    tok = AutoTokenizer.from_pretrained(str(folder))
    prompt = build_prompt(BOXES, object_palette("cabinet", "7"), 2)
    target = '{"materials":{"0":{"family":"Wood","desc":""}},"nodes":{"1":{"parent":null,"material":0}},"relations":[]}'
    text = tok.apply_chat_template(chat_messages(prompt, target), chat_template=QWEN_VL_STYLE, tokenize=False)
    vision = "<|vision_start|><|image_pad|><|vision_end|>"
    assert text == f"<|im_start|>user\n{vision}{vision}{prompt}<|im_end|>\n<|im_start|>assistant\n{target}<|im_end|>\n"
    ids = tok(text)["input_ids"]
    assert ids.count(tok.convert_tokens_to_ids("<|image_pad|>")) == 2
    gen = tok.apply_chat_template(chat_messages(prompt), chat_template=QWEN_VL_STYLE, tokenize=False,
                                  add_generation_prompt=True)
    assert gen.endswith("<|im_start|>assistant\n") and target not in gen
