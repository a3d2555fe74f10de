"""A generated structure document rewritten where it stands in the model's text.

The decode-time steps (``box_frame.text_to_absolute``, ``scene_grouping.regroup_text``,
``grounding.ground_text``) each find the JSON object a model wrote, change it, and put it back:
this module is that one rule. The object runs from the first ``{`` to the last ``}`` of the text,
since an unconstrained model may fence its JSON and a tokenizer may spell out the stop token after
it; what surrounds the object is kept as written, and a rewritten object is written compactly
(``,`` and ``:`` separators, non-ASCII kept), as the training targets are. A text the step cannot
read comes back unchanged, so that what the validator and the metrics judge is the model's own
document.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from typing import Any

from jax3dc.errors import StructureError
from jax3dc.structure.schema import Structure
from jax3dc.structure.validate import parse_structure


def rewrite_json(text: str, rewrite: Callable[[Any], Any | None]) -> str:
    """``text`` with its JSON object replaced by ``rewrite(document)`` (the object as parsed JSON,
    before validation; None: keep the text as it is). A text without an object, or whose object is
    not JSON, comes back unchanged. A non-finite number the model wrote is written back as it was
    (``NaN``), for the validator to refuse."""
    span = _span(text)
    if span is None:
        return text
    try:
        document = json.loads(text[span[0]:span[1]])
    except (ValueError, RecursionError):
        return text
    return _splice(text, span, rewrite(document), allow_nan=True)


def rewrite_structure(text: str, part_ids: Iterable[int], rewrite: Callable[[Structure, str], Any | None]) -> str:
    """``text`` with its structure document replaced by ``rewrite(structure, written)``: the
    document parsed and validated against ``part_ids``, and its JSON as written (for a step that
    changes only some of its nodes); None keeps the text as it is. A text whose object does not
    parse and validate comes back unchanged."""
    span = _span(text)
    if span is None:
        return text
    written = text[span[0]:span[1]]
    try:
        structure = parse_structure(written, part_ids=part_ids)
    except StructureError:
        return text
    # a validated document holds finite numbers only, so a non-finite one here is a bug of the step
    return _splice(text, span, rewrite(structure, written), allow_nan=False)


def _span(text: str) -> tuple[int, int] | None:
    """Where the JSON object stands in ``text`` (first ``{`` to last ``}``), or None."""
    start, end = text.find("{"), text.rfind("}") + 1
    return (start, end) if 0 <= start < end else None


def _splice(text: str, span: tuple[int, int], document: Any | None, allow_nan: bool) -> str:
    if document is None:
        return text
    written = json.dumps(document, separators=(",", ":"), ensure_ascii=False, allow_nan=allow_nan)
    return text[:span[0]] + written + text[span[1]:]
