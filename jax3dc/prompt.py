"""The stage-2 prompt (SPEC §3): colour legend, joint count and the target schema, as chat messages.

The legend ties each part id to its colour in the segmentation image S and to its box (centroid
and extent in the normalised frame), so the model can name parts by id; the schema text tells it
what to write. ``chat_messages`` gives the turns in the form that a Hugging Face Qwen3-VL
processor's ``apply_chat_template`` accepts (images I then S, then the text, in the user turn).
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import numpy as np

from jax3dc.palette import BACKGROUND_RGB, hex_colour, part_colour
from jax3dc.structure.schema import FAMILIES, JOINT_TYPES, PLANES, Box

IMAGES_PER_TASK = {"structure": 2, "code": 1, "parameters": 1}  # the images a task's prompt holds: I and S; I alone

LEGEND_HEADER = "Parts (id: colour | centroid | extent):"
_LEGEND_LINE = re.compile(r"^(\d+): #[0-9a-fA-F]{6} \| (\S+) (\S+) (\S+) \| (\S+) (\S+) (\S+)$", re.MULTILINE)

INTRO = (
    "The first image shows an object (or a scene). The second image is its part segmentation: "
    f"every part is one flat colour; the background is {hex_colour(BACKGROUND_RGB)}."
)

SCHEMA = (
    "Write the structure of the object as one JSON object with the keys \"materials\", \"nodes\" and \"relations\".\n"
    "- \"materials\": {\"<material id>\": {\"family\": F, \"desc\": short description}}, F one of: "
    + ", ".join(FAMILIES) + ".\n"
    "- \"nodes\": one entry per part id listed above: {\"<part id>\": {\"parent\": part id or null, "
    "\"material\": material id}}; a part that moves relative to its parent also has "
    "\"joint\": {\"type\": " + " or ".join(f'"{t}"' for t in JOINT_TYPES) + ", \"axis\": [x, y, z] unit vector, "
    "\"pivot\": [x, y, z] a point on the axis, \"range\": [lo, hi] from the pose shown "
    "(radians for hinge, units for slide)}. The parents form a tree per object; each object root has parent null.\n"
    "- \"relations\": a list of {\"type\": \"symmetric\", \"a\": id, \"b\": id, \"plane\": "
    + " or ".join(f'"{p}"' for p in PLANES) + "} (mirror pairs), "
    "{\"type\": \"instance\", \"a\": id, \"b\": id} (identical copies) and "
    "{\"type\": \"support\", \"a\": object root id, \"b\": id} (object a rests on part b).\n"
    "Frame: +Z up, the front faces -Y, the largest extent is 1. Write numbers with 3 decimals."
)


def _fixed3(v: float) -> str:
    text = f"{float(v):.3f}"
    return "0.000" if text == "-0.000" else text


def legend_line(part_id: int, colour: tuple[int, int, int], box: Box) -> str:
    """``id: #rrggbb | cx cy cz | ex ey ez`` with 3 decimals."""
    centroid = " ".join(_fixed3(v) for v in box.centroid)
    extent = " ".join(_fixed3(v) for v in box.extent)
    return f"{part_id}: {hex_colour(colour)} | {centroid} | {extent}"


def legend_boxes(prompt_text: str) -> dict[int, Box]:
    """The part boxes a prompt's legend states, by part id: what a model reads, to 3 decimals, and
    so what box-frame pivots are measured against both in training and at inference."""
    out: dict[int, Box] = {}
    for m in _LEGEND_LINE.finditer(prompt_text):
        try:
            values = [float(v) for v in m.groups()[1:]]
        except ValueError:
            continue
        out[int(m[1])] = Box(tuple(values[:3]), tuple(values[3:]))  # type: ignore[arg-type]
    return out


def build_prompt(boxes: Mapping[int, Box], palette: np.ndarray, num_joints: int | None) -> str:
    """The user text of SPEC §3 for parts ``boxes`` coloured by ``palette`` (an object_palette).

    ``num_joints``: the number of joints to predict for an articulated object; None or 0 leaves
    the ``Joints:`` line out (not articulated, or unknown at inference time).
    """
    lines = [INTRO, LEGEND_HEADER]
    lines += [legend_line(pid, part_colour(palette, pid), boxes[pid]) for pid in sorted(boxes)]
    if num_joints:
        lines.append(f"Joints: {int(num_joints)}")
    lines.append(SCHEMA)
    return "\n".join(lines)


def chat_messages(prompt_text: str, target_json: str | None = None) -> list[dict]:
    """User turn (image I, image S, prompt text) and, for training, the assistant turn (target JSON)."""
    messages: list[dict] = [{
        "role": "user",
        "content": [{"type": "image"}, {"type": "image"}, {"type": "text", "text": prompt_text}],
    }]
    if target_json is not None:
        messages.append({"role": "assistant", "content": [{"type": "text", "text": target_json}]})
    return messages


#: The stage-1 code backend's user text (SPEC §6): the model sees only the RGB image and writes a
#: part program, which the interpreter (jax3dc.program) runs into one mesh per part.
CODE_PROMPT = (
    "The image shows an object. Write a part program that rebuilds it: one statement per line, "
    "using only the predefined functions (box, cylinder, cone, sphere, torus, extrude, lathe, sweep, "
    "bevel, difference, combine, linear_array, grid_array, radial_array, mirror, translate, rotate, "
    "scale, material). End each part with part(<id>, '<name>', mesh, material=...), ids from 1. "
    "Frame: +Z up, the front faces -Y, the largest extent is 1."
)


#: The stage-1 parameter backend's user text (jax3dc.parameters): the model sees only the RGB
#: image and writes the category and parameters of the factory that rebuilds the object.
PARAMETERS_PROMPT = (
    "The image shows an object. Write its category and parameters, one line: "
    "category(name=value, ...) with every parameter of that category in order. "
    "Lengths in metres, angles in degrees, counts and option indices as integers, 0/1 for yes/no."
)


def parameters_messages(text: str | None = None) -> list[dict]:
    """User turn (image I, PARAMETERS_PROMPT) and, for training, the assistant turn (the record's text)."""
    messages: list[dict] = [{"role": "user", "content": [{"type": "image"}, {"type": "text", "text": PARAMETERS_PROMPT}]}]
    if text is not None:
        messages.append({"role": "assistant", "content": [{"type": "text", "text": text}]})
    return messages


def code_messages(program: str | None = None) -> list[dict]:
    """User turn (image I, CODE_PROMPT) and, for training, the assistant turn (the program)."""
    messages: list[dict] = [{"role": "user", "content": [{"type": "image"}, {"type": "text", "text": CODE_PROMPT}]}]
    if program is not None:
        messages.append({"role": "assistant", "content": [{"type": "text", "text": program}]})
    return messages
