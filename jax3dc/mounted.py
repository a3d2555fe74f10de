"""Which objects are fixed in place in use, by category: their simulation base stays fixed.

A faucet on its sink, a toilet bolted to the floor, a door frame and a window frame set in a wall,
a light switch on its wall plate need not stand free: the physics checks hold their root in the
gravity test and the MJCF export keeps their base fixed even when asked for a free one. The names
are factory categories (``jax3dc.factories``) and PartNet-Mobility's ("Door", "Switch"),
matched without case.
"""

from __future__ import annotations

MOUNTED_CATEGORIES = frozenset({"faucet", "toilet", "door", "window", "sliding_window", "toggle_faucet_lever", "switch"})


def is_mounted(category: str | None) -> bool:
    """Whether objects of ``category`` are fixed in place in use (an unknown or missing one is not)."""
    return (category or "").lower() in MOUNTED_CATEGORIES
