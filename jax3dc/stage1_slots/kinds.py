"""The generic part kinds the slots network names, and the one table from part names to them.

Part names come from three sources: the factories' semantic names (``freezer_door``,
``bail_handle``, ``seat_cushion_2``), PartNet-Mobility's semantics labels as the importer keeps
them (``rotation_door``, ``furniture_body``, ``toggle_button``) and the composed objects' part
names. A name is read as words (split on ``_``, ``-``, spaces and digits); the last word the table
knows decides, because the head noun of such a compound comes last (``lever_handle`` is a handle,
``tap_lever`` a lever, ``laptop_base`` a body). A name with no known word, and a part without a
name (records built before names were kept), is ``other``: an unknown kind is a truthful target,
a guessed one is not.
"""

from __future__ import annotations

import re

KINDS: tuple[str, ...] = ("body", "door", "drawer", "lid", "handle", "knob", "button", "wheel", "leg", "shelf",
                          "seat", "screen", "blade", "cap", "lever", "other")
OTHER = KINDS.index("other")

# word -> kind; one entry per word, grouped by kind
KIND_OF_WORD: dict[str, str] = {
    **dict.fromkeys(("body", "base", "frame", "shell", "tank", "stand", "pedestal", "plinth", "column", "countertop",
                     "top", "side", "panel", "bottom", "apron", "upright", "container", "bowl", "basin", "housing",
                     "cabinet", "case", "casing", "carcass"), "body"),
    **dict.fromkeys(("door", "doors", "leaf", "sash", "window", "pane", "flap", "gate"), "door"),
    **dict.fromkeys(("drawer", "drawers", "tray", "bin"), "drawer"),
    **dict.fromkeys(("lid", "cover", "hatch"), "lid"),
    **dict.fromkeys(("handle", "handles", "latch", "grip", "pull"), "handle"),
    **dict.fromkeys(("knob", "knobs", "dial", "rotor"), "knob"),
    **dict.fromkeys(("button", "buttons", "switch", "toggle", "key"), "button"),
    **dict.fromkeys(("wheel", "wheels", "caster", "casters", "castor", "roller"), "wheel"),
    **dict.fromkeys(("leg", "legs", "foot", "feet", "post"), "leg"),
    **dict.fromkeys(("shelf", "shelves", "board", "rack", "divider"), "shelf"),
    **dict.fromkeys(("seat", "cushion", "saddle"), "seat"),
    **dict.fromkeys(("screen", "display", "monitor"), "screen"),
    **dict.fromkeys(("blade", "blades", "knife"), "blade"),
    **dict.fromkeys(("cap", "stopper", "cork"), "cap"),
    **dict.fromkeys(("lever", "tap", "slider", "pedal", "trigger"), "lever"),
}

_WORD = re.compile(r"[a-z]+")


def kind_of(name: str | None) -> str:
    """The generic kind of a part name (see the module docstring); ``other`` when none applies."""
    for word in reversed(_WORD.findall((name or "").lower())):
        if word in KIND_OF_WORD:
            return KIND_OF_WORD[word]
    return "other"


def kind_index(name: str | None) -> int:
    """``kind_of`` as an index into KINDS (the network's class)."""
    return KINDS.index(kind_of(name))
