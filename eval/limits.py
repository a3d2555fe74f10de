"""Caps on what the evaluation commands take, kept apart so the CLI can name them without
importing the metrics (numpy, scipy)."""

MAX_SCORED_PARTS = 1000
"""Parts of one reference object the metrics take unless raised: joint matching grows with the
square of the joints (6,000 jointed parts with coincident boxes: over 120 s and 5.9 GB; 1,000:
18 s and 0.6 GB on 2 CPU cores, start-up included). PartNet-Mobility objects have under 100."""
