"""Material family of an imported part, guessed from its names.

Source files rarely state physical materials, so a small keyword table over the part's names
picks a family, in this order of trust: the part's own names (semantic label, link / body
name); then the names of the materials its visuals / geoms use, when those with a keyword agree;
then the names of its visuals / geoms, only when every one of them names the same family (a
microwave door made of "glass" and "handle" visuals stays "Other" rather than becoming Glass).
A part without any such keyword gets "Other".
"""

from __future__ import annotations

import re

KEYWORDS: dict[str, tuple[str, ...]] = {
    "Glass": ("glass", "mirror", "lens", "windowpane", "pane"),
    "Metal": ("metal", "steel", "iron", "aluminium", "aluminum", "chrome", "brass", "copper"),
    "Wood": ("wood", "wooden", "oak", "pine", "walnut", "plywood"),
    "Fabric": ("fabric", "cloth", "cushion", "pillow", "curtain", "mattress", "textile"),
    "Leather": ("leather",),
    "Rubber": ("rubber", "tire", "tyre"),
    "Ceramic": ("ceramic", "porcelain", "tile"),
    "Stone": ("stone", "marble", "granite", "concrete"),
    "Plastic": ("plastic",),
}
DEFAULT_FAMILY = "Other"


def family_of_name(name: str) -> str | None:
    """Family named by a keyword among the words of ``name``, or None."""
    words = set(re.split(r"[^a-z]+", name.lower()))
    for family, keywords in KEYWORDS.items():
        if words.intersection(keywords):
            return family
    return None


def guess_family(own_names: list[str], material_names: list[str], shape_names: list[str]) -> str:
    """Family from the part's own names, else its material names, else its shape names."""
    for name in own_names:
        family = family_of_name(name)
        if family:
            return family
    named = {family_of_name(name) for name in material_names} - {None}
    if len(named) == 1:
        return named.pop()
    families = {family_of_name(name) for name in shape_names}
    if len(families) == 1 and None not in families:
        return families.pop()
    return DEFAULT_FAMILY
