"""The convex pieces on disk: a new process (or a cleared cache) reads them back exactly instead of
decomposing again; a changed argument, constant, source or library version misses; an entry that
is torn or foreign is a miss and is rewritten; concurrent writers (a sweep's workers) never leave
a reader a torn entry; an unwritable folder warns and the pieces still come."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import jax3dc.geometry.convex_pieces as cp
from jax3dc.geometry import piece_disk_cache as disk

REPO = Path(__file__).resolve().parents[2]
MESH = trimesh.creation.annulus(0.1, 0.3, 0.1)  # closed and concave: several voxel pieces


@pytest.fixture
def counted(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> list[int]:
    """An empty disk cache in tmp_path/pieces, an empty memory, and the decompositions run since."""
    monkeypatch.setenv(disk.ENV, str(tmp_path / "pieces"))
    cp.clear_cache()
    calls: list[int] = []
    fresh = cp.decompose

    def counting(*args, **kwargs):
        calls.append(1)
        return fresh(*args, **kwargs)

    monkeypatch.setattr(cp, "decompose", counting)
    yield calls
    cp.clear_cache()


def _equal(a: list[np.ndarray], b: list[np.ndarray]) -> bool:
    return len(a) == len(b) and all(x.dtype == y.dtype and np.array_equal(x, y) for x, y in zip(a, b))


def _entries(tmp_path: Path) -> list[Path]:
    return sorted((tmp_path / "pieces").rglob("*.npz"))


def test_a_cleared_cache_reads_the_disk_and_gets_the_fresh_pieces(counted: list[int], tmp_path: Path) -> None:
    first = cp.convex_pieces(MESH, 1e-3)
    cp.clear_cache()
    again = cp.convex_pieces(trimesh.Trimesh(MESH.vertices.copy(), MESH.faces.copy(), process=False), 1e-3)
    assert len(counted) == 1 and len(_entries(tmp_path)) == 1
    assert len(again) > 1 and _equal(again, first) and _equal(again, cp.decompose(MESH, 1e-3))
    with pytest.raises(ValueError):
        again[0][0, 0] = 1.0  # shared through the memory cache, hence read-only as before


def test_a_fresh_process_never_decomposes(counted: list[int], tmp_path: Path) -> None:
    """What a repeated command or another worker of a sweep does: a new interpreter reads the
    entry, with the decomposition replaced by one that fails."""
    np.savez(tmp_path / "mesh.npz", vertices=MESH.vertices, faces=MESH.faces)
    computed = cp.convex_pieces(trimesh.Trimesh(MESH.vertices, MESH.faces, process=False), 2e-3, 0.5)
    script = (
        "import sys, numpy as np, trimesh\n"
        "import jax3dc.geometry.convex_pieces as cp\n"
        "def refuse(*_): raise SystemExit('decomposed again')\n"
        "cp.decompose = refuse\n"
        "m = np.load(sys.argv[1])\n"
        "pieces = cp.convex_pieces(trimesh.Trimesh(m['vertices'], m['faces'], process=False), 2e-3, 0.5)\n"
        "np.savez(sys.argv[2], *pieces)\n")
    subprocess.run([sys.executable, "-c", script, tmp_path / "mesh.npz", tmp_path / "read.npz"], cwd=REPO,
                   env={**os.environ, "PYTHONPATH": str(REPO)}, check=True, timeout=120)
    with np.load(tmp_path / "read.npz") as read:
        assert _equal([read[f"arr_{i}"] for i in range(len(read.files))], computed)
    assert len(counted) == 1


def test_a_changed_argument_or_constant_misses(counted: list[int], monkeypatch: pytest.MonkeyPatch) -> None:
    cp.convex_pieces(MESH, 1e-3)
    for min_size, scale in ((2e-3, 1.0), (1e-3, 2.0)):
        cp.clear_cache()
        cp.convex_pieces(MESH, min_size, scale)
    cp.clear_cache()
    with monkeypatch.context() as patched:
        patched.setattr(cp, "HULL_MAX_VERTICES", 8)
        cp.convex_pieces(MESH, 1e-3)
    assert len(counted) == 4
    cp.clear_cache()
    cp.convex_pieces(MESH, 1e-3)  # the first call's entry is still there
    assert len(counted) == 4


@pytest.mark.parametrize("change", ["source", "library"])
def test_the_code_version_follows_the_source_and_the_libraries(change: str, monkeypatch: pytest.MonkeyPatch) -> None:
    before = disk.code_version.__wrapped__()
    if change == "source":
        read = pathlib.Path.read_bytes
        monkeypatch.setattr(pathlib.Path, "read_bytes",
                            lambda p: read(p) + b"\n# edited" if p.name == "convex_pieces.py" else read(p))
    else:
        version = disk.importlib.metadata.version
        monkeypatch.setattr(disk.importlib.metadata, "version",
                            lambda n: version(n) + ".post1" if n == "scipy" else version(n))
    assert disk.code_version.__wrapped__() != before


def test_a_changed_code_version_misses(counted: list[int], monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    cp.convex_pieces(MESH, 1e-3)
    cp.clear_cache()
    monkeypatch.setattr(disk, "code_version", lambda: b"the next version")
    cp.convex_pieces(MESH, 1e-3)
    assert len(counted) == 2 and len(_entries(tmp_path)) == 2


def _truncated(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _bit_flipped(path: Path) -> None:  # inside the stored vertices: only the zip's CRC notices
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))


def _foreign(path: Path) -> None:  # a well-formed npz that is not pieces: counts do not add up
    with path.open("wb") as f:
        np.savez(f, vertices=np.zeros((5, 3)), counts=np.asarray([4], dtype=np.int64))


def _pickled(path: Path) -> None:
    with path.open("wb") as f:
        np.savez(f, vertices=np.asarray([object()], dtype=object), counts=np.asarray([1]))


@pytest.mark.parametrize("corrupt", [_truncated, _bit_flipped, _foreign, _pickled, lambda p: p.write_bytes(b"")],
                         ids=["truncated", "bit-flipped", "foreign", "pickled", "empty"])
def test_a_corrupt_entry_is_a_miss_and_is_rewritten(counted: list[int], tmp_path: Path, corrupt) -> None:
    computed = cp.convex_pieces(MESH, 1e-3)
    (entry,) = _entries(tmp_path)
    corrupt(entry)
    cp.clear_cache()
    assert _equal(cp.convex_pieces(MESH, 1e-3), computed) and len(counted) == 2
    cp.clear_cache()
    assert _equal(cp.convex_pieces(MESH, 1e-3), computed) and len(counted) == 2  # rewritten whole


def test_concurrent_writers_never_show_a_reader_a_torn_entry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Four processes rewrite an entry while this one reads it, as a sweep's workers do: every read
    is the whole pieces (a torn file would read as a miss, and the reader would decompose again),
    and no temporary file is left."""
    monkeypatch.setenv(disk.ENV, str(tmp_path / "pieces"))
    pieces = cp.decompose(MESH, 1e-3)
    np.savez(tmp_path / "pieces.npz", *pieces)
    key = b"one mesh"
    disk.save(key, pieces)
    script = (
        "import sys, numpy as np\n"
        "from jax3dc.geometry import piece_disk_cache as disk\n"
        "with np.load(sys.argv[1]) as f: pieces = [f[f'arr_{i}'] for i in range(len(f.files))]\n"
        "for _ in range(100): disk.save(b'one mesh', pieces)\n")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    writers = [subprocess.Popen([sys.executable, "-c", script, tmp_path / "pieces.npz"], cwd=REPO, env=env)
               for _ in range(4)]
    reads = []
    while any(w.poll() is None for w in writers):
        reads.append(disk.load(key))
    assert all(w.wait() == 0 for w in writers)
    assert reads and all(r is not None and _equal(r, pieces) for r in reads)
    files = [p for p in (tmp_path / "pieces").rglob("*") if p.is_file()]
    assert files == [disk.entry_path(tmp_path / "pieces", key)]


def test_an_unwritable_folder_warns_once_and_the_pieces_still_come(counted: list[int], tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "a file"
    blocker.write_text("not a folder")
    monkeypatch.setenv(disk.ENV, str(blocker))
    monkeypatch.setattr(disk, "_unwritable", set())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = cp.convex_pieces(MESH, 1e-3)
        cp.clear_cache()
        second = cp.convex_pieces(MESH, 1e-3)
    assert _equal(first, second) and len(counted) == 2
    assert len(caught) == 1 and str(blocker) in str(caught[0].message) and disk.ENV in str(caught[0].message)


def test_an_empty_variable_turns_the_disk_off(counted: list[int], tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(disk.ENV, "")
    cp.convex_pieces(MESH, 1e-3)
    cp.clear_cache()
    cp.convex_pieces(MESH, 1e-3)
    assert len(counted) == 2 and disk.cache_dir() is None and not (tmp_path / "pieces").exists()


def test_the_default_folder_is_beside_the_xla_cache(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(disk.ENV)
    monkeypatch.setenv("HOME", "/home/someone")
    assert disk.cache_dir() == Path("/home/someone/.cache/jax3dc/pieces")


def test_a_second_sweep_of_a_build_never_decomposes(counted: list[int], tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """`jax3dc physics sweep` run again on the same build: the part programs give the same meshes,
    so every piece comes from the disk, and the verdicts are the first run's."""
    from jax3dc.factories import generate_object
    from data_pipeline.record import Record
    from data_pipeline.shards import write_dataset
    from jax3dc.cli import main
    from jax3dc.structure import to_json

    obj = generate_object("cabinet", 0)  # a carcass of boards: a piece per board
    meta = {"category": "cabinet", "object_id": obj.object_id, "view": 0, "scale_m_per_nu": obj.scale_m_per_nu}
    records = [Record("cabinet/0", b"", b"", "", to_json(obj.structure), obj.program_text, meta)]
    write_dataset(tmp_path / "build", records)
    assert main(["physics", "sweep", str(tmp_path / "build"), "--out", str(tmp_path / "first")]) == 0
    assert counted

    def refuse(*_):
        raise AssertionError("decomposed again")

    monkeypatch.setattr(cp, "decompose", refuse)
    cp.clear_cache()  # as a new process starts
    assert main(["physics", "sweep", str(tmp_path / "build"), "--out", str(tmp_path / "again")]) == 0
    verdicts = [(tmp_path / run / "verdicts.jsonl").read_text() for run in ("first", "again")]
    assert verdicts[0] == verdicts[1] and '"skipped"' not in verdicts[0]
