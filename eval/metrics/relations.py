"""Symmetric and instance relation counts of one object, for split-level (micro) F1.

After canonicalisation an instance group is a star anchored at its smallest id and a symmetric
pair is written a < b, so both are compared as unordered pairs. `support` relations are not scored
(SPEC §5 names only symmetric and instance).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from jax3dc.structure.schema import Structure


@dataclass(frozen=True)
class RelationCounts:
    sym_tp: int
    sym_pred: int
    sym_ref: int
    inst_tp: int
    inst_pred: int
    inst_ref: int
    plane_correct: int  # of the sym_tp pairs found on both sides, those with the same plane


RELATION_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(RelationCounts))


def _pairs(s: Structure) -> tuple[dict[tuple[int, int], str | None], set[tuple[int, int]]]:
    sym: dict[tuple[int, int], str | None] = {}
    inst: set[tuple[int, int]] = set()
    for rel in s.relations:
        pair = (min(rel.a, rel.b), max(rel.a, rel.b))
        if rel.type == "symmetric":
            sym[pair] = rel.plane
        elif rel.type == "instance":
            inst.add(pair)
    return sym, inst


def relation_counts(pred: Structure, ref: Structure) -> RelationCounts:
    """True positives and set sizes of the symmetric and instance pairs of one object."""
    p_sym, p_inst = _pairs(pred)
    r_sym, r_inst = _pairs(ref)
    both = p_sym.keys() & r_sym.keys()
    return RelationCounts(
        sym_tp=len(both),
        sym_pred=len(p_sym),
        sym_ref=len(r_sym),
        inst_tp=len(p_inst & r_inst),
        inst_pred=len(p_inst),
        inst_ref=len(r_inst),
        plane_correct=sum(p_sym[k] == r_sym[k] for k in both),
    )
