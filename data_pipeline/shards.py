"""ArrayRecord shards with a manifest, written so that a killed build can be resumed safely.

A shard is written under a temporary name and renamed into place only when complete; the
manifest (rewritten atomically after each shard) lists finished shards with their record count
and SHA-256. On restart a shard counts as done only if it is in the manifest and its bytes still
hash to the recorded value; anything else is rebuilt from scratch. Shard contents depend only on
the build configuration and the shard's own task, so a rebuilt shard is byte-identical.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Iterable, Iterator, Sequence

from array_record.python.array_record_module import ArrayRecordReader, ArrayRecordWriter

from data_pipeline.record import Record, decode_record, encode_record
from jax3dc.errors import InputFileError

SHARD_SUFFIX = ".array_record"
MANIFEST = "manifest.json"


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_shard(path: Path, records: Iterable[Record]) -> tuple[int, str]:
    """Write ``records`` to ``path`` atomically; returns (record count, SHA-256 of the file)."""
    tmp = path.with_name(path.name + ".tmp")
    writer = ArrayRecordWriter(str(tmp), "group_size:1")
    count = 0
    try:
        for record in records:
            writer.write(encode_record(record))
            count += 1
    finally:
        writer.close()
    os.replace(tmp, path)
    return count, file_sha256(path)


def write_dataset(directory: Path, records: Iterable[Record], name: str = "train-00000" + SHARD_SUFFIX) -> None:
    """One shard and its manifest, readable as ``jax3dc data build``'s output is, for records made
    elsewhere (benchmarks, tests): the manifest's layout stays known to this module alone."""
    directory.mkdir(parents=True, exist_ok=True)
    count, sha = write_shard(directory / name, records)
    save_manifest(directory, {"shards": {name: {"records": count, "sha256": sha}}})


def read_shard(path: Path) -> Iterator[Record]:
    """Every record of one shard, decoded (a corrupt record raises CorruptRecordError)."""
    reader = ArrayRecordReader(str(path))
    try:
        for i in range(reader.num_records()):
            yield decode_record(reader.read([i])[0])
    finally:
        reader.close()


def read_dataset(directory: Path) -> Iterator[Record]:
    """Records of every finished shard listed in ``directory``'s manifest, in shard-name order."""
    manifest = load_manifest(Path(directory))
    if manifest is None:
        raise InputFileError(Path(directory), f"no {MANIFEST}: not a dataset written by `jax3dc data build`")
    for name in sorted(manifest["shards"]):
        yield from read_shard(Path(directory) / name)


def load_manifest(directory: Path) -> dict | None:
    path = directory / MANIFEST
    if not path.exists():
        return None
    try:
        return json.loads(path.read_text())
    except ValueError as e:
        raise InputFileError(path, f"manifest is not valid JSON: {e}") from None


def save_manifest(directory: Path, manifest: dict) -> None:
    tmp = directory / (MANIFEST + ".tmp")
    tmp.write_text(json.dumps(manifest, indent=1, sort_keys=True))
    os.replace(tmp, directory / MANIFEST)


def finished(directory: Path, manifest: dict, name: str) -> bool:
    entry = manifest["shards"].get(name)
    path = directory / name
    return entry is not None and path.exists() and file_sha256(path) == entry["sha256"]


def shard_paths(sources: Sequence[str | Path], split: str | None) -> list[Path]:
    """ArrayRecord files named by ``sources`` (files, or folders searched recursively).

    In a folder, files whose name starts with ``split`` are taken when there are any (shards are
    named per split), else every ``*.array_record`` file (records are then filtered by meta.split).
    """
    paths: list[Path] = []
    for source in sources:
        source = Path(source)
        if source.is_file():
            paths.append(source)
        elif source.is_dir():
            found = sorted(p for p in source.rglob(f"*{SHARD_SUFFIX}") if p.is_file())
            named = [p for p in found if split and p.name.startswith(split)]
            paths.extend(named or found)
        else:
            raise InputFileError(source, "no such shard file or folder")
    if not paths:
        raise InputFileError(", ".join(map(str, sources)), f"no {SHARD_SUFFIX} files found")
    return paths
