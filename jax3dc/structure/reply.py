"""A model's reply -> the structure JSON document it holds: the text step between generation and
``parse_structure``, shared by ``predict``, the verified choice and evaluation's scoring."""

from __future__ import annotations

import re

# Chat-template end markers a generation may still carry, and a Markdown code fence around JSON.
_END_MARKERS = re.compile(r"(<\|im_end\|>|<\|endoftext\|>)\s*$")
_FENCE = re.compile(r"^```(?:json)?\s*\n?(.*?)\n?```$", re.DOTALL)


def json_text(raw: str) -> str:
    """The JSON document in a raw generation: end-of-turn markers and a code fence removed."""
    text = _END_MARKERS.sub("", raw.strip()).strip()
    fenced = _FENCE.match(text)
    return fenced.group(1).strip() if fenced else text
