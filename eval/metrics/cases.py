"""Reading reference and prediction JSONL files into canonical `Case`s.

Reference lines: ``{"key": ..., "structure": {...}, "boxes": {...}}``.
Prediction lines: ``{"key": ..., "text": "<raw model output>"}`` or ``{"key": ..., "structure": {...}}``.

A prediction is validated against the reference's part ids (they coincide because both sides read
the same segmentation map) and both sides are canonicalised with the reference boxes. A missing
prediction, or one that breaks a rule of SPEC §2, becomes a parse failure carrying the rule name;
a malformed *file* (bad JSON line, missing key, invalid reference) is an InputFileError.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping

from eval.limits import MAX_SCORED_PARTS
from eval.metrics.score import Case
from jax3dc.errors import InputFileError, StructureError
from jax3dc.structure import Box, Structure, boxes_from_dict, canonicalize, parse_structure
from jax3dc.structure.validate import json_text

MISSING_RULE = "missing"

@dataclass(frozen=True)
class Reference:
    key: str
    structure: Structure  # canonical
    boxes: dict[int, Box]


MAX_LINE_BYTES = 8 << 20
"""Longest line read: a reference holds a structure of at most 1 MB (MAX_DOCUMENT_BYTES) and boxes of
at most 4 MB (MAX_BOXES_BYTES)."""


def _unique_members(items: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in items:
        if k in out:
            raise ValueError(f"key {k!r} appears twice in one object")
        out[k] = v
    return out


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not a JSON number")


def _parse_line(raw: bytes) -> Any:
    """One JSON value of a line; any problem is a ValueError saying what it is."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"not UTF-8 text (byte {e.start})") from None
    try:
        return json.loads(text, object_pairs_hook=_unique_members, parse_constant=_no_constant)
    except json.JSONDecodeError as e:
        raise ValueError(f"not JSON ({e.msg})") from None
    except RecursionError:
        raise ValueError("not JSON (nested too deeply)") from None
    except ValueError as e:  # _unique_members, _no_constant, or an integer of more than 4300 digits
        raise ValueError(f"not JSON ({e})") from None


def read_jsonl(path: str | Path) -> Iterator[tuple[int, dict[str, Any]]]:
    """(line number, object) for every non-blank line; each must be a JSON object with a key."""
    path = Path(path)
    try:
        handle = path.open("rb")
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror or e}") from None
    with handle:
        for number, line in enumerate(iter(lambda: handle.readline(MAX_LINE_BYTES + 1), b""), start=1):
            if len(line) > MAX_LINE_BYTES:
                raise InputFileError(path, f"line {number} is over {MAX_LINE_BYTES} bytes (MAX_LINE_BYTES)")
            if not line.strip():
                continue
            try:
                item = _parse_line(line)
            except ValueError as e:
                raise InputFileError(path, f"line {number}: {e}") from None
            if not isinstance(item, dict) or not isinstance(item.get("key"), str):
                raise InputFileError(path, f'line {number}: expected an object with a string "key"')
            try:
                item["key"].encode("utf-8")
            except UnicodeEncodeError as e:  # JSON's "\ud800" escape decodes to a lone surrogate
                raise InputFileError(path, f'line {number}: "key" is not valid Unicode text (a lone surrogate at '
                                           f"character {e.start})") from None
            yield number, item


def load_references(path: str | Path, max_parts: int = MAX_SCORED_PARTS) -> list[Reference]:
    """Parse, validate and canonicalise every reference line (invalid references, or one of more than
    ``max_parts`` parts, are an error)."""
    refs: list[Reference] = []
    seen: set[str] = set()
    for number, item in read_jsonl(path):
        key = item["key"]
        where = f"line {number} (key {key!r})"
        if key in seen:
            raise InputFileError(path, f"{where}: duplicate key")
        seen.add(key)
        if not isinstance(item.get("structure"), dict) or not isinstance(item.get("boxes"), dict):
            raise InputFileError(path, f'{where}: a reference needs "structure" and "boxes" objects')
        try:
            boxes = boxes_from_dict(item["boxes"])
            structure = parse_structure(item["structure"])
        except StructureError as e:
            raise InputFileError(path, f"{where}: invalid reference: {e}") from None
        if len(structure.nodes) > max_parts:
            raise InputFileError(path, f"{where}: {len(structure.nodes)} parts; the metrics score at most "
                                       f"{max_parts} per object (raise it with --max-parts)")
        missing = sorted(set(structure.nodes) - set(boxes))
        if missing:
            raise InputFileError(path, f"{where}: no box for parts {missing}")
        refs.append(Reference(key, canonicalize(structure, boxes), boxes))
    if not refs:
        raise InputFileError(path, "no reference lines")
    return refs


def load_predictions(path: str | Path) -> dict[str, Any]:
    """Key -> raw text (str) or structure document (dict) of every prediction line."""
    preds: dict[str, Any] = {}
    for number, item in read_jsonl(path):
        key = item["key"]
        if key in preds:
            raise InputFileError(path, f"line {number} (key {key!r}): duplicate key")
        doc = item.get("structure", item.get("text"))
        if not isinstance(doc, (str, dict)):
            raise InputFileError(path, f'line {number} (key {key!r}): a prediction needs "text" or "structure"')
        preds[key] = doc
    return preds


def parse_prediction(doc: str | Mapping[str, Any], ref: Reference) -> Structure:
    """Validate a prediction against the reference part ids and canonicalise it (StructureError)."""
    source = json_text(doc) if isinstance(doc, str) else dict(doc)
    return canonicalize(parse_structure(source, ref.structure.nodes.keys()), ref.boxes)


def build_cases(refs: Iterable[Reference], preds: Mapping[str, Any]) -> list[Case]:
    """One case per reference, in reference order; predictions without a reference are ignored."""
    cases = []
    for ref in refs:
        centroids = {i: b.centroid for i, b in ref.boxes.items()}
        if ref.key not in preds:
            cases.append(Case(ref.key, ref.structure, centroids, None, MISSING_RULE, "no prediction"))
            continue
        try:
            pred = parse_prediction(preds[ref.key], ref)
        except StructureError as e:
            cases.append(Case(ref.key, ref.structure, centroids, None, e.rule, str(e)))
            continue
        cases.append(Case(ref.key, ref.structure, centroids, pred))
    return cases
