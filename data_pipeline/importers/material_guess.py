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
# What an imported material says when its source names none: text of our own, not a fact about the
# object, and written only for imported objects, so a model that learns it learns which domain an
# object comes from. Training leaves it unscored (``placeholder_spans``).
UNKNOWN_DESC = "default: no material named in the source"
GUESSED_DESC = "guessed from part names ({})"
_VALUE = r'"{key}"\s*:\s*"({value})"'
_PLACEHOLDERS = re.compile(
    _VALUE.format(key="family", value=re.escape(DEFAULT_FAMILY)) + r"\s*,\s*"
    + _VALUE.format(key="desc", value=re.escape(UNKNOWN_DESC))
    + "|" + _VALUE.format(key="desc", value=re.escape(GUESSED_DESC).replace(r"\{\}", "[a-z]+")))


def placeholder_spans(target_json: str) -> list[tuple[int, int]]:
    """Character spans of ``target_json`` (a structure's JSON text) that an importer wrote in place
    of a material it does not know: the description of every placeholder material, and its family
    when that is only the default. Empty for factory objects."""
    spans = []
    for m in _PLACEHOLDERS.finditer(target_json):
        spans += [m.span(g) for g in range(1, 4) if m.group(g) is not None]
    return spans


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
