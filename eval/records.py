"""Evaluation's records: a split read from ArrayRecord shards and each record's scoring reference
(its target, canonical, with its part boxes). ``jax3dc.sampler`` generates for them."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Iterator

from data_pipeline.record import CorruptRecordError, Record
from data_pipeline.shards import read_shard
from eval.metrics.cases import Reference
from jax3dc.errors import InputFileError, StructureError
from jax3dc.prompt import legend_boxes
from jax3dc.structure import Box, boxes_from_dict, canonicalize, parse_structure


def read_records(paths: Iterable[Path], split: str | None = None) -> Iterator[Record]:
    """Every record of the shards in order; with ``split``, only records whose meta.split matches
    (records without a split field are kept). A corrupt record raises CorruptRecordError."""
    for path in paths:
        try:
            records = read_shard(path)
            for record in records:
                if split is None or record.meta.get("split", split) == split:
                    yield record
        except CorruptRecordError as e:
            raise InputFileError(path, str(e)) from None
        except (RuntimeError, ValueError) as e:  # the C++ reader's errors for a non-ArrayRecord file
            raise InputFileError(path, f"not a readable ArrayRecord file: {e}") from None


def record_boxes(record: Record) -> dict[int, Box]:
    """Per-part boxes from meta["boxes"], else from the prompt's legend (the same numbers)."""
    if "boxes" in record.meta:
        return boxes_from_dict(record.meta["boxes"])
    boxes = legend_boxes(record.prompt)
    if not boxes:
        raise StructureError("box_value", record.key, "record has no meta.boxes and no part legend in its prompt")
    return boxes


def reference_of(record: Record) -> Reference:
    """The record's target as a canonical scoring reference (an invalid target is an input error)."""
    try:
        boxes = record_boxes(record)
        structure = parse_structure(record.target)
    except StructureError as e:
        raise InputFileError(record.key, f"invalid reference target or boxes: {e}") from None
    missing = sorted(set(structure.nodes) - set(boxes))
    if missing:
        raise InputFileError(record.key, f"no box for parts {missing}")
    return Reference(record.key, canonicalize(structure, boxes), boxes)
