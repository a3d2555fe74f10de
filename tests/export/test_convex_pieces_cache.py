"""The convex pieces are decomposed once per mesh and shared by the exports and the physics checks:
a cached answer is exactly a fresh decomposition, nobody can change it in place, and anything the
pieces depend on (the mesh, the arguments, a decomposition constant) asks for a new one."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from jax3dc.factories.registry import generate_object
import jax3dc.geometry.convex_pieces as cp
from jax3dc.physics.verdict import check_object
from jax3dc.export.mjcf import mjcf_model
from jax3dc.export.simulation import MIN_PIECE_M


@pytest.fixture
def counted(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """An empty cache in memory and none on disk (this file is about the process's own), and the
    number of decompositions run since (one entry per call)."""
    monkeypatch.setenv("JAX3DC_PIECE_CACHE", "")
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
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b))


def test_a_cached_answer_is_the_fresh_decomposition_and_read_only(counted: list[int]) -> None:
    bucket = generate_object("bucket", 0)  # a concave part: many voxel pieces
    for mesh in bucket.parts.values():
        first = cp.convex_pieces(mesh, MIN_PIECE_M, 0.4)
        again = cp.convex_pieces(trimesh.Trimesh(mesh.vertices.copy(), mesh.faces.copy(), process=False), MIN_PIECE_M, 0.4)
        assert _equal(again, first) and _equal(first, cp.decompose(mesh, MIN_PIECE_M, 0.4))
        assert all(not v.flags.writeable for v in again)
        with pytest.raises(ValueError):
            again[0][0, 0] = 1.0
    assert len(counted) == 2 * len(bucket.parts)  # the copies hit the cache; the direct calls above count too
    assert max(len(cp.convex_pieces(m, MIN_PIECE_M, 0.4)) for m in bucket.parts.values()) > 1


def test_the_mesh_the_arguments_and_the_constants_are_in_the_key(counted: list[int],
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    mesh = trimesh.creation.annulus(0.1, 0.3, 0.1)  # closed and concave
    base = cp.convex_pieces(mesh, 1e-3)
    moved = trimesh.Trimesh(mesh.vertices + [0.0, 0.0, 1e-12], mesh.faces, process=False)
    cp.convex_pieces(moved, 1e-3)
    cp.convex_pieces(mesh, 2e-3)
    cp.convex_pieces(mesh, 1e-3, 2.0)
    assert len(counted) == 4
    monkeypatch.setattr(cp, "HULL_MAX_VERTICES", 8)
    capped = cp.convex_pieces(mesh, 1e-3)
    assert len(counted) == 5 and max(len(v) for v in capped) <= 8 < max(len(v) for v in base)


def test_the_cache_holds_at_most_its_entries(counted: list[int], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(cp, "CACHE_ENTRIES", 2)
    boxes = [trimesh.creation.box([0.1 * (i + 1)] * 3) for i in range(3)]
    for mesh in boxes:
        cp.convex_pieces(mesh, 1e-3)
    cp.convex_pieces(boxes[2], 1e-3)  # the newest stays
    cp.convex_pieces(boxes[0], 1e-3)  # the oldest was dropped
    assert len(counted) == 4 and len(cp._cache) == 2


def test_export_and_physics_check_decompose_each_part_once_and_match_an_uncached_run(counted: list[int]) -> None:
    """The MJCF export and the check of the same parts (predict's sequence) share one decomposition,
    and the XML and verdict equal those of a cold cache."""
    obj = generate_object("cabinet", 0)
    args = obj.structure, obj.parts, obj.scale_m_per_nu
    xml, files = mjcf_model(*args)
    verdict = check_object(*args, dynamics=False)
    assert len(counted) == len(obj.parts)
    cp.clear_cache()
    assert check_object(*args, dynamics=False) == verdict
    assert mjcf_model(*args) == (xml, files)
    assert len(counted) == 2 * len(obj.parts)
