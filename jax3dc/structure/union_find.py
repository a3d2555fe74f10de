"""Connected sets of part ids: the one union-find of the structure code.

Canonical relations gather instance groups with it (``canonical.canonical_relations``) and scene
grouping gathers bodies of touching boxes (``scene_grouping``). The sets come out in one order
whatever order the links came in, so what is built from them is deterministic.
"""

from __future__ import annotations

from collections.abc import Iterable


def connected_sets(items: Iterable[int], links: Iterable[tuple[int, int]]) -> list[list[int]]:
    """The connected sets of ``items`` under ``links`` (pairs of items), each sorted, the sets
    ordered by their smallest member; an item no link touches is a set of its own."""
    parent = {i: i for i in items}

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]  # path halving: later finds walk half as far
            i = parent[i]
        return i

    for a, b in links:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    sets: dict[int, list[int]] = {}
    for i in sorted(parent):  # a set is met first at its smallest member, so the sets come out in order
        sets.setdefault(find(i), []).append(i)
    return list(sets.values())
