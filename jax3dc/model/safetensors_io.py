"""Minimal safetensors reading (memory-mapped, lazy per tensor) and writing.

Own reader because checkpoints are bfloat16, which the ``safetensors`` numpy backend cannot
return, and because loading must stream one tensor at a time without materialising a file.
Format: 8-byte little-endian header length, a JSON header ``{name: {dtype, shape,
data_offsets}}``, then the raw little-endian bytes.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Iterator
from pathlib import Path

import ml_dtypes
import numpy as np

from jax3dc.errors import InputFileError

DTYPES = {
    "F64": np.dtype(np.float64), "F32": np.dtype(np.float32), "F16": np.dtype(np.float16),
    "BF16": np.dtype(ml_dtypes.bfloat16), "I64": np.dtype(np.int64), "I32": np.dtype(np.int32),
    "I16": np.dtype(np.int16), "I8": np.dtype(np.int8), "U8": np.dtype(np.uint8), "BOOL": np.dtype(bool),
}
NAMES = {v: k for k, v in DTYPES.items()}


class SafetensorsFile:
    """``names()`` and ``get(name) -> np.ndarray`` (a read-only memory map, no copy)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        try:
            with open(self.path, "rb") as f:
                (n,) = struct.unpack("<Q", f.read(8))
                header = json.loads(f.read(n))
        except (OSError, struct.error, json.JSONDecodeError, UnicodeDecodeError) as e:
            raise InputFileError(str(path), f"not a readable safetensors file ({e})") from None
        header.pop("__metadata__", None)
        self.header = header
        self.data_start = 8 + n

    def names(self) -> list[str]:
        return list(self.header)

    def get(self, name: str) -> np.ndarray:
        entry = self.header[name]
        if entry["dtype"] not in DTYPES:
            raise InputFileError(str(self.path), f"tensor {name}: unsupported dtype {entry['dtype']}")
        dtype = DTYPES[entry["dtype"]]
        begin, end = entry["data_offsets"]
        shape = tuple(entry["shape"])
        if end - begin != dtype.itemsize * int(np.prod(shape)):
            raise InputFileError(str(self.path), f"tensor {name}: byte size does not match its shape")
        if end == begin:
            return np.zeros(shape, dtype)
        raw = np.memmap(self.path, dtype=np.uint8, mode="r", offset=self.data_start + begin, shape=(end - begin,))
        return raw.view(dtype).reshape(shape)


def checkpoint_files(directory: str | Path) -> list[Path]:
    """The safetensors files of a Hugging Face checkpoint directory (sharded via its index or one file)."""
    directory = Path(directory)
    index = directory / "model.safetensors.index.json"
    if index.exists():
        try:
            weight_map = json.loads(index.read_text())["weight_map"]
        except (json.JSONDecodeError, KeyError) as e:
            raise InputFileError(str(index), f"bad index file ({e})") from None
        files = [directory / f for f in dict.fromkeys(weight_map.values())]
    else:
        files = sorted(directory.glob("*.safetensors"))
    if not files:
        raise InputFileError(str(directory), "no *.safetensors files")
    for f in files:
        if not f.exists():
            raise InputFileError(str(f), "listed in the index but missing")
    return files


def iter_tensors(directory: str | Path) -> Iterator[tuple[str, np.ndarray]]:
    for f in checkpoint_files(directory):
        st = SafetensorsFile(f)
        for name in st.names():
            yield name, st.get(name)


def write_safetensors(path: str | Path, tensors: dict[str, np.ndarray]) -> None:
    header: dict = {"__metadata__": {"format": "pt"}}
    offset = 0
    for name, arr in tensors.items():
        if arr.dtype not in NAMES:
            raise ValueError(f"{name}: dtype {arr.dtype} cannot be written to safetensors")
        header[name] = {"dtype": NAMES[arr.dtype], "shape": list(arr.shape),
                        "data_offsets": [offset, offset + arr.nbytes]}
        offset += arr.nbytes
    blob = json.dumps(header, separators=(",", ":")).encode()
    blob += b" " * (-len(blob) % 8)
    with open(path, "wb") as f:
        f.write(struct.pack("<Q", len(blob)))
        f.write(blob)
        for arr in tensors.values():
            f.write(np.ascontiguousarray(arr).tobytes())
