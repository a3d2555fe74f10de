"""Per-part bounding boxes (``boxes.json``) beside a structure: centroid and extent in nu.

File format: ``{"1": {"centroid": [x, y, z], "extent": [x, y, z]}, ...}``, keys in ascending
integer order, numbers rounded to BOX_DECIMALS (finer than the prompt's 3 decimals, so the
prompt legend and re-rooting by volume read the same values whether boxes come from memory or disk).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path

from jax3dc.errors import InputFileError, StructureError
from jax3dc.structure.schema import Box

BOX_DECIMALS = 6
MAX_BOXES_BYTES = 4 << 20
"""A boxes.json of 10,000 parts is about 1 MB; a larger file is refused before it is parsed."""


def _clean(x: float) -> float:
    r = round(float(x), BOX_DECIMALS)
    return 0.0 if r == 0 else r


def boxes_to_dict(boxes: Mapping[int, Box]) -> dict[str, dict[str, list[float]]]:
    """JSON-ready boxes; values rounded to BOX_DECIMALS."""
    out = {}
    for pid, box in sorted(boxes.items()):
        where = f"box {pid}"
        for name, vec in (("centroid", box.centroid), ("extent", box.extent)):
            if len(vec) != 3 or not all(math.isfinite(float(v)) for v in vec):
                raise StructureError("box_value", f"{where} {name}", f"{name} {list(vec)} is not a finite 3-vector")
        out[str(pid)] = {"centroid": [_clean(v) for v in box.centroid], "extent": [_clean(v) for v in box.extent]}
    return out


def _vec3(value: object, where: str) -> tuple[float, float, float]:
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise StructureError("box_value", where, f"must be a list of 3 numbers, got {value!r:.60}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(float(v)):
            raise StructureError("box_value", where, f"must hold finite numbers, got {v!r:.30}")
        out.append(float(v))
    return (out[0], out[1], out[2])


def boxes_from_dict(doc: object) -> dict[int, Box]:
    """Boxes from their JSON dictionary; a bad entry raises StructureError naming the part."""
    if not isinstance(doc, Mapping):
        raise StructureError("box_value", "boxes", "boxes must be a JSON object of part id -> box")
    boxes: dict[int, Box] = {}
    for key, value in doc.items():
        if isinstance(key, int) and not isinstance(key, bool):
            pid = key
        elif isinstance(key, str) and key.isdigit() and key.isascii():
            pid = int(key)
        else:
            raise StructureError("box_value", f"box {key!r:.30}", "box keys are integer part ids")
        where = f"box {pid}"
        if not isinstance(value, Mapping) or set(value) != {"centroid", "extent"}:
            raise StructureError("box_value", where, "a box is an object with exactly 'centroid' and 'extent'")
        extent = _vec3(value["extent"], f"{where} extent")
        if min(extent) < 0:
            raise StructureError("box_value", f"{where} extent", f"extent {list(extent)} has a negative side")
        boxes[pid] = Box(_vec3(value["centroid"], f"{where} centroid"), extent)
    return dict(sorted(boxes.items()))


def save_boxes(boxes: Mapping[int, Box], path: str | Path) -> None:
    path = Path(path)
    try:
        path.write_text(json.dumps(boxes_to_dict(boxes), separators=(",", ":")) + "\n")
    except OSError as e:
        raise InputFileError(path, f"cannot write boxes: {e.strerror or e}") from None


def load_boxes(path: str | Path) -> dict[int, Box]:
    """Boxes from a ``boxes.json`` file; any problem is an InputFileError naming the file."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = f.read(MAX_BOXES_BYTES + 1)
        if len(data) > MAX_BOXES_BYTES:
            raise InputFileError(path, f"the file is over {MAX_BOXES_BYTES} bytes, far above any real boxes.json "
                                       "[boxes_size]")
        text = data.decode("utf-8")
    except FileNotFoundError:
        raise InputFileError(path, "no such file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputFileError(path, f"cannot read boxes: {getattr(e, 'strerror', None) or e}") from None
    try:
        return boxes_from_dict(json.loads(text))
    except json.JSONDecodeError as e:
        raise InputFileError(path, f"invalid JSON at line {e.lineno} column {e.colno}: {e.msg}") from None
    except RecursionError:
        raise InputFileError(path, "invalid JSON: nested too deeply") from None
    except ValueError as e:  # an integer literal longer than Python's digit limit
        raise InputFileError(path, f"invalid JSON: {e}") from None
    except StructureError as e:
        raise InputFileError(path, str(e)) from None
