"""Procedural object factories (SPEC §4): each writes a part program, a structure and materials.

`generate_object(category, seed)` is the entry point; `FACTORIES` lists the categories
(36 categories: the 27 of SPEC §4 and more, and the 4 instance-heavy shelves of the paper).

What every object satisfies (tests/factories check it for several seeds):
  * the program text is the single source of geometry: `parts` are the meshes of running it;
  * SPEC §2 frame: +Z up, front towards -Y, bounding-box centre at the origin, largest extent 1
    (`scale_m_per_nu` metres per unit); part ids 1..N, one tree, per-part materials;
  * joints where the real object has them (door hinges on the door's edge, drawers sliding along
    -Y, drop-down oven doors, lids hinged at the back, ...), pivots on the moving part, and each
    joint reaches both ends of its range without running into another part;
  * at rest, parts meet without intersecting;
  * symmetric / instance relations extracted from the meshes (jax3dc.relations) agree with the
    copies the factory built;
  * the same (category, seed) gives byte-identical program text and structure JSON.
"""

from jax3dc.factories.registry import FACTORIES, Factory, GeneratedObject, generate_object, object_id

__all__ = ["FACTORIES", "Factory", "GeneratedObject", "generate_object", "object_id"]
