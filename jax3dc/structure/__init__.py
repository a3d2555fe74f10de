"""The structure O (SPEC §2): typed values, parsing with validation, canonical JSON and canonical form."""

from jax3dc.structure.boxes import BOX_DECIMALS, boxes_from_dict, boxes_to_dict, load_boxes, save_boxes
from jax3dc.structure.canonical import canonicalize
from jax3dc.structure.schema import (
    FAMILIES,
    JOINT_TYPES,
    PLANES,
    RELATION_TYPES,
    Box,
    Joint,
    Material,
    Node,
    Relation,
    Structure,
)
from jax3dc.structure.serialize import DECIMALS, to_dict, to_json
from jax3dc.structure.validate import MAX_DOCUMENT_BYTES, parse_structure, validate

__all__ = [
    "BOX_DECIMALS", "DECIMALS", "FAMILIES", "JOINT_TYPES", "MAX_DOCUMENT_BYTES", "PLANES", "RELATION_TYPES",
    "Box", "Joint", "Material", "Node", "Relation", "Structure",
    "boxes_from_dict", "boxes_to_dict", "canonicalize", "load_boxes", "parse_structure", "save_boxes",
    "to_dict", "to_json", "validate",
]
