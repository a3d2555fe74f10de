"""What is done to a structure reply after decoding, before anyone reads it: one step, in one order.

1. pivots written in the checkpoint's box frame go back to SPEC §2 absolute numbers
   (``jax3dc.structure.box_frame``), so every reader sees one frame whatever the model writes;
2. with ``scene_grouping``, parts the model wired across separate objects of a scene are regrouped
   (``jax3dc.structure.scene_grouping``);
3. with ``grounding``, joints are corrected by the legend boxes (``jax3dc.grounding``).

All three read the prompt's legend boxes, parsed once per prompt (``boxes``) and shared by its K
candidates. The decoder (``jax3dc.sampler``) only decodes and hands its texts here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from jax3dc.grounding import Grounding, ground_text
from jax3dc.prompt import legend_boxes
from jax3dc.structure import Box
from jax3dc.structure.box_frame import PivotFrame, text_to_absolute
from jax3dc.structure.scene_grouping import regroup_text


@dataclass(frozen=True)
class ReplyRewrite:
    """The rewrite of the module docstring for one checkpoint's ``pivot_frame`` and one decode's
    options (``DecodeOptions.scene_grouping`` and ``.grounding``)."""

    pivot_frame: PivotFrame
    scene_grouping: bool
    grounding: Grounding | None

    def boxes(self, prompt: str) -> dict[int, Box] | None:
        """The legend boxes of a structure ``prompt`` the steps read, or None when no step changes
        anything (absolute pivots, no grouping, no grounding), so the legend is not parsed for nothing."""
        if self.pivot_frame.name == "absolute" and not self.scene_grouping and self.grounding is None:
            return None
        return legend_boxes(prompt)

    def __call__(self, text: str, boxes: Mapping[int, Box]) -> str:
        """``text`` (a reply to a prompt with legend ``boxes``) after the steps, in order."""
        text = text_to_absolute(text, boxes, self.pivot_frame)
        if self.scene_grouping:
            text = regroup_text(text, boxes)
        if self.grounding is not None:
            text = ground_text(text, boxes, self.grounding)
        return text
