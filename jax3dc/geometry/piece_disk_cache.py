"""Convex collision pieces on disk, under ``convex_pieces``' in-process cache: a later process (a
repeated ``predict``, ``eval run --candidates/--repair``, ``physics sweep``, or another worker of the
same sweep) reads a part's pieces instead of decomposing the mesh again.

Folder: ``$JAX3DC_PIECE_CACHE``, else ``~/.cache/jax3dc/pieces`` (beside the XLA cache of
``jax3dc.compilation``); the variable set to "" turns the disk off for a run. It is read at each
call, so spawned workers inherit it and a test points it at its own folder. One file per mesh and
arguments, ``<2 hex>/<40 hex>.npz``: the pieces' vertices stacked [n, 3] float64 and each piece's
vertex count, the very arrays the decomposition gave. Nothing is evicted (an entry is a few kB, at
most ~100 kB); deleting the folder is always safe.

The name is a digest of the in-process key (vertices, faces, arguments, decomposition constants)
and of a code version: the source of ``convex_pieces.py`` and of this module, and the versions of
numpy, scipy and trimesh. The decomposition and every helper it calls live in that one file, so
its digest cannot miss a changed helper the way a list of chosen functions could (a docstring edit
costs one cold run, an acceptable price); this module's source covers the file format; numpy,
scipy (qhull's hulls, the voxel fill, connected components) and trimesh (voxelisation, volumes,
surface samples) compute the pieces. manifold3d, trimesh's boolean engine, is never on this path.

The crossing check's boards and surface points (``jax3dc.physics.crossing``) live in the same
folder as entries of their own code version (``load_arrays``, ``save_arrays``): they too are found
from a part's mesh alone, and were a fifth of a first verdict. A write goes to a temporary file in
the entry's folder and is renamed into place, so a reader (a concurrent worker) sees a whole entry
or none. An entry that cannot be read or does not hold
pieces is a miss, and the decomposition's answer replaces it; a folder that cannot be written
warns once and the run goes on without the disk.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import os
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

ENV = "JAX3DC_PIECE_CACHE"
DEFAULT_DIR = "~/.cache/jax3dc/pieces"
VERSIONED_PACKAGES = ("numpy", "scipy", "trimesh")

_unwritable: set[Path] = set()  # folders already warned about


def cache_dir() -> Path | None:
    """The folder of the entries, or None when the disk is off (the variable set to "")."""
    directory = os.environ.get(ENV, DEFAULT_DIR)
    return Path(directory).expanduser() if directory else None


@functools.cache
def code_version() -> bytes:
    """Digest of what computes and stores the pieces (see the module docstring)."""
    digest = hashlib.blake2b(digest_size=32)
    here = Path(__file__).resolve().parent
    for source in ("convex_pieces.py", "piece_disk_cache.py"):
        digest.update((here / source).read_bytes())
    for package in VERSIONED_PACKAGES:
        digest.update(f"{package}=={importlib.metadata.version(package)};".encode())
    return digest.digest()


def entry_path(directory: Path, key: bytes, version: bytes | None = None) -> Path:
    """Where the entry of in-process ``key`` lives under ``directory`` for a code version (default:
    the pieces', ``code_version``)."""
    name = hashlib.blake2b((code_version() if version is None else version) + key, digest_size=20).hexdigest()
    return directory / name[:2] / f"{name}.npz"


def load(key: bytes) -> list[np.ndarray] | None:
    """The stored pieces of ``key``, or None: disk off, no entry, or one that is unreadable or
    not pieces (torn by a crash, corrupted, another format)."""
    entry = load_arrays(key, code_version(), ("vertices", "counts"))
    if entry is None:
        return None
    vertices, counts = entry["vertices"], entry["counts"]
    if (vertices.dtype != np.float64 or vertices.ndim != 2 or vertices.shape[1] != 3 or counts.dtype != np.int64
            or counts.ndim != 1 or np.any(counts <= 0) or counts.sum() != len(vertices)):
        return None
    return np.split(vertices, np.cumsum(counts)[:-1]) if len(counts) else []


def save(key: bytes, pieces: Sequence[np.ndarray]) -> None:
    """Store ``pieces`` for ``key`` atomically (temporary file, then rename); a folder that cannot
    be written warns once per process and is skipped."""
    vertices = np.concatenate(pieces) if pieces else np.zeros((0, 3))
    save_arrays(key, code_version(), {"vertices": vertices, "counts": np.asarray([len(p) for p in pieces], dtype=np.int64)})


def load_arrays(key: bytes, version: bytes, names: Sequence[str]) -> dict[str, np.ndarray] | None:
    """The arrays ``names`` of the entry of ``key`` under ``version`` (another geometry cache's own
    code version: the crossing check's boards), or None: disk off, no entry, or an unreadable one."""
    directory = cache_dir()
    if directory is None:
        return None
    try:
        with np.load(entry_path(directory, key, version), allow_pickle=False) as entry:
            return {name: entry[name] for name in names}
    except Exception:  # noqa: BLE001 - absent, or unreadable in any way (zip, CRC, header, name): a miss
        return None


def save_arrays(key: bytes, version: bytes, arrays: dict[str, np.ndarray]) -> None:
    """Store ``arrays`` as the entry of ``key`` under ``version`` (atomically, as ``save``)."""
    directory = cache_dir()
    if directory is None:
        return
    path = entry_path(directory, key, version)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp", delete=False) as f:
            tmp = Path(f.name)
            np.savez(f, **arrays)
        os.replace(tmp, path)
    except OSError as e:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        if directory not in _unwritable:
            _unwritable.add(directory)
            warnings.warn(f"convex pieces are not cached on disk: cannot write {directory} ({e}); "
                          f"set {ENV} to another folder, or to '' to turn the disk cache off", stacklevel=3)
