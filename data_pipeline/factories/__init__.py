"""Procedural object factories (SPEC §4): each writes a part program, a structure and materials.

`generate_object(category, seed)` is the entry point; `FACTORIES` lists the categories.
"""

from data_pipeline.factories.registry import FACTORIES, Factory, GeneratedObject, generate_object, object_id

__all__ = ["FACTORIES", "Factory", "GeneratedObject", "generate_object", "object_id"]
