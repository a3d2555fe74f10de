"""What a process's first accelerator launches are padded to: one table for every kind of launch.

Launches are padded to the largest shapes met so far (``mjx_batch.Shapes`` for interpenetration
sweeps, ``crossing_batch.CrossingShapes`` for board crossings), so they compile only when those
grow; starting from shapes that most batches fit, a run compiles once or twice. Each entry holds
the fields of one of those dataclasses, as plain values, so that the table loads without jax or
MJX (the CPU physics path reads it and imports neither). On a CPU launches start from the size
classes they need instead (``launcher.start_shapes``), since padding costs compute there.
"""

from __future__ import annotations

SWEEP_PENETRATION = dict(objects=16, bodies=32, geoms=96, pairs=1536, nq=32, items=2048, hulls=(64, 384),
                         hull_sizes=((8, 12, 12), (32, 64, 96)))
"""``mjx_batch.Shapes`` fields of ``physics sweep --backend mjx``'s first launch: most batches of
factory objects fit them (up to 26 bodies and 1,536 geom pairs an object)."""

CANDIDATE_PENETRATION = dict(objects=16, bodies=32, geoms=192, pairs=6144, nq=32, items=2048, hulls=(128, 1536),
                             hull_sizes=((8, 12, 24), (32, 64, 96)), capacity=65536)
"""``mjx_batch.Shapes`` fields of the first launch of candidate sets (verified decoding, a repair's
alternatives): the largest a device service's batches of 16 factory candidates reached over 200
objects, narrow-phase capacity aside; the narrow phase computes only the entries a launch holds, so
its capacity costs nothing."""

CROSSINGS = dict(items=32768, chunks=4096, tracks=1024, boards=2048, states=32, cells=(128, 128))
"""``crossing_batch.CrossingShapes`` fields of the first board-crossing launch (the candidate sets
of a batch of factory objects fit them)."""
