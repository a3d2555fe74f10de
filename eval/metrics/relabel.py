"""A structure predicted on stage 1's own parts, renamed onto the reference's part ids.

Table 1 compares two structures node by node, so both must name the same parts (SPEC §5: they do
when both read one S). From pixels they do not: stage 1 made its own parts, ids and count. Given
the one-to-one pairing of predicted to reference parts by box overlap
(``eval.metrics.part_matching.match_bounds``), ``relabel`` writes the prediction over the
reference's ids:

* a matched part takes its reference partner's id; its parent is its nearest matched ancestor
  (a joint stays on the part; a part left with no parent loses its joint: SPEC §2 allows none);
* a predicted part with no partner is dropped (its children move up to its nearest matched
  ancestor): the node metrics have no reference node to score it against. Stage 1's extra parts
  are charged by its own scores (part count, matched IoU), not here;
* a reference part with no partner is added as a root of its own, rigid, no relations: stage 1
  never made it, so its parent and joint count as misses (unless the reference part is a root);
* relations whose two ends are matched are kept, renamed.
"""

from __future__ import annotations

from typing import Iterable, Mapping

from jax3dc.structure.schema import Material, Node, Relation, Structure

MISSING_MATERIAL = Material("Other", "a part stage 1 did not make")


def _matched_ancestor(structure: Structure, part: int, renamed: Mapping[int, int]) -> int | None:
    """The renamed id of the nearest ancestor of ``part`` that has a partner, or None."""
    parent = structure.nodes[part].parent
    seen = {part}
    while parent is not None and parent not in renamed:
        if parent in seen:  # a cycle: the structure was not validated; treat the part as a root
            return None
        seen.add(parent)
        parent = structure.nodes[parent].parent
    return None if parent is None else renamed[parent]


def relabel(predicted: Structure, pairs: Mapping[int, int], reference_ids: Iterable[int]) -> Structure:
    """``predicted`` over ``reference_ids``; ``pairs`` maps a predicted part id to its reference
    partner's (one-to-one, partners among ``reference_ids``). A pair naming a part that is not in
    the prediction or the reference is a ValueError."""
    reference_ids = set(reference_ids)
    unknown = sorted(p for p in pairs if p not in predicted.nodes)
    strangers = sorted(r for r in pairs.values() if r not in reference_ids)
    if unknown or strangers or len(set(pairs.values())) != len(pairs):
        raise ValueError(f"pairs must be one-to-one from predicted to reference parts: predicted parts not in the "
                         f"structure {unknown}, partners not among the reference parts {strangers}")
    materials = dict(predicted.materials)
    nodes: dict[int, Node] = {}
    for part, ref_id in pairs.items():
        node = predicted.nodes[part]
        parent = _matched_ancestor(predicted, part, pairs)
        nodes[ref_id] = Node(parent, node.material, node.joint if parent is not None else None, node.name)
    missing = sorted(reference_ids - set(nodes))
    if missing:
        spare = max(materials, default=-1) + 1
        materials[spare] = MISSING_MATERIAL
        nodes.update({ref_id: Node(None, spare) for ref_id in missing})
    relations = tuple(Relation(r.type, pairs[r.a], pairs[r.b], r.plane) for r in predicted.relations
                      if r.a in pairs and r.b in pairs)
    return Structure(materials, dict(sorted(nodes.items())), relations)
