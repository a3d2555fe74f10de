"""One training record (SPEC §4) and its byte encoding inside an ArrayRecord shard.

Layout of an encoded record: the magic ``J3DR1``, a little-endian uint32 header length, a UTF-8
JSON header, then the two PNG blobs back to back. The header holds every text field plus the PNG
lengths, so a reader can check sizes before touching pixels. Decoding is strict: a truncated or
altered record raises ``CorruptRecordError`` naming what is wrong, never returns half a record.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from typing import Any

from jax3dc.errors import Jax3dcError

MAGIC = b"J3DR1"
_LEN = struct.Struct("<I")


class CorruptRecordError(Jax3dcError):
    """An encoded record cannot be decoded (wrong magic, bad header, wrong blob lengths)."""


@dataclass(frozen=True)
class Record:
    """Everything one sample needs: I and S as PNG bytes, prompt, target O, program, parameters, meta.

    ``key`` is unique in a dataset: ``<category>/<object_id>/<view>[/<augmentation>]``.
    ``meta`` holds category, object_id, seed, view, split, granularity, scale, camera,
    per-part boxes and the augmentation applied (SPEC §4). ``parameters`` is the factory's
    parameter text (jax3dc.parameters), the stage-1 target, when the parts are the factory's own.
    """

    key: str
    image_png: bytes
    seg_png: bytes
    prompt: str
    target: str
    program: str | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    parameters: str | None = None  # after meta: records built by position before it existed stay right


def encode_record(record: Record) -> bytes:
    header = {
        "key": record.key,
        "prompt": record.prompt,
        "target": record.target,
        "program": record.program,
        "meta": record.meta,
        "image_png_bytes": len(record.image_png),
        "seg_png_bytes": len(record.seg_png),
    }
    if record.parameters is not None:  # absent otherwise: records without it keep their bytes
        header["parameters"] = record.parameters
    head = json.dumps(header, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()
    return MAGIC + _LEN.pack(len(head)) + head + record.image_png + record.seg_png


def decode_record(blob: bytes) -> Record:
    if not blob.startswith(MAGIC):
        raise CorruptRecordError("record does not start with the J3DR1 magic")
    start = len(MAGIC) + _LEN.size
    if len(blob) < start:
        raise CorruptRecordError("record is shorter than its fixed header")
    (head_len,) = _LEN.unpack_from(blob, len(MAGIC))
    if start + head_len > len(blob):
        raise CorruptRecordError(f"header length {head_len} runs past the record end")
    try:
        header = json.loads(blob[start:start + head_len])
        n_img, n_seg = int(header["image_png_bytes"]), int(header["seg_png_bytes"])
        key, prompt, target = header["key"], header["prompt"], header["target"]
    except (ValueError, KeyError, TypeError) as e:
        raise CorruptRecordError(f"record header is not valid: {e}") from None
    body = blob[start + head_len:]
    if len(body) != n_img + n_seg:
        raise CorruptRecordError(
            f"record {key!r}: image blobs hold {len(body)} bytes, header says {n_img + n_seg}")
    return Record(key=key, image_png=body[:n_img], seg_png=body[n_img:], prompt=prompt,
                  target=target, program=header.get("program"),
                  parameters=header.get("parameters"), meta=header.get("meta") or {})
