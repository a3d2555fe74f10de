"""Joint grounding: the joints a model writes, corrected by the geometry of the parts at decode time.

A small model trained mostly on procedural objects reads a real drawer as a hinge, tilts an axis,
or puts a door's hinge on the wrong line of its frame. The part boxes of the prompt's legend say
something about each of these, and three steps use them, each switchable (``Grounding``):

1. ``axis_snap``: an axis within ``AXIS_SNAP`` of a box direction becomes exactly that direction
   (sign kept).
2. ``type_axis``: the prior's classifier (``jax3dc.grounding.prior``) scores hinge/slide along
   x/y/z from the boxes; the model's own choice is kept unless another is ``keep_ratio`` times
   likelier. With ``axis_dim_kept`` (the default) only the type may change, along the direction
   the model wrote: letting the classifier move axes cost axis accuracy everywhere. A part that
   becomes a slide opens out of the face of its parent it sits nearest, by ``SLIDE_OPENING`` of
   its side; one that becomes a hinge opens by a quarter turn, away from its parent.
3. ``line_snap`` (off by default): a box-aligned hinge's pivot moves to the best of the nine lines
   of its part's box along the axis (edges, face centre lines, centre line), scored by the prior's
   line scorer plus a Gaussian of the distance to the model's own line (width ``line_sigma``); a
   written line farther than ``line_sigma`` from all nine (a hinge at the parent's edge, off its
   part's box) is kept. When a hinge moves to another line, or is new, its range is turned so
   that opening moves the part away from its parent's centre.

What each step bought on the release-3 benchmark is in docs/runs/grounding_20261128. Grounding
never changes parents, materials or relations, and turns a valid structure into a valid one
(``ground_text`` leaves a text that does not parse against the prompt's part ids as it is, for
the validator to judge).
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from jax3dc.grounding.features import LINES, cross_dims, joint_features, line_features
from jax3dc.grounding.prior import CLASSES, JointPrior, shipped_prior
from jax3dc.structure.rewrite import rewrite_structure
from jax3dc.structure.schema import Box, Joint, Structure
from jax3dc.structure.serialize import to_dict

AXIS_SNAP = 0.35  # rad (20°): a written axis this close to a box direction is snapped onto it
SLIDE_OPENING = 0.8  # a new slide's travel, as a fraction of its part's side along the axis (real median)
MAX_SLIDE = 0.6  # nu
HINGE_OPENING = math.pi / 2


@dataclass(frozen=True)
class Grounding:
    """Which grounding steps run (module docstring; ``line_snap`` acts on snapped or new axes only),
    and with which prior (None: the shipped one)."""

    axis_snap: bool = True
    type_axis: bool = True
    axis_dim_kept: bool = True
    line_snap: bool = False  # off by default: it cost procedural splits 6 points and bought nothing on real objects
    prior: JointPrior | None = None

    def resolved_prior(self) -> JointPrior:
        return self.prior if self.prior is not None else shipped_prior()


def _unit(k: int, sign: float = 1.0) -> np.ndarray:
    out = np.zeros(3)
    out[k] = 1.0 if sign >= 0 else -1.0
    return out


def opening_outward(joint: Joint, child: Box, parent: Box | None) -> Joint:
    """The joint with its range turned (if need be) so that the side of the range it mostly spans
    moves the child away from its parent's centre: a hinge swings out of its parent, a slide pulls
    out. Grounding and hand edits (jax3dc.edits) give a new or moved joint a range this way."""
    if parent is None:
        return joint
    c = np.asarray(child.centroid, float)
    away = c - np.asarray(parent.centroid, float)
    if joint.type == "slide":
        opens = float(np.asarray(joint.axis, float) @ away)
    else:
        opens = float(np.cross(np.asarray(joint.axis, float), c - np.asarray(joint.pivot, float)) @ away)
    lo, hi = joint.range
    if abs(opens) < 1e-9 or (opens > 0) == (hi >= -lo):
        return joint
    return replace(joint, range=(-hi, -lo))


def _choose_class(joint: Joint, k: int, features: np.ndarray, prior: JointPrior, dim_kept: bool) -> tuple[str, int]:
    logp = prior.class_logprobs(features)
    written = CLASSES.index((joint.type, k))
    logp[written] += math.log(prior.keep_ratio)
    if dim_kept:
        logp[[i for i, (_, d) in enumerate(CLASSES) if d != k]] = -np.inf
    return CLASSES[int(np.argmax(logp))]


def _best_line(joint: Joint, k: int, child: Box, parent: Box | None, handles: Sequence[Box],
               prior: JointPrior, trust_written: bool) -> np.ndarray:
    """The pivot on the best candidate line (its coordinate along the axis: the part's centre)."""
    i, j = cross_dims(k)
    c = np.asarray(child.centroid, float)
    sides = np.maximum(np.asarray(child.extent, float), 0.0)
    points = np.array([[c[i] + gi * sides[i], c[j] + gj * sides[j]] for gi, gj in LINES])
    score = prior.line_logits(line_features(child, parent, k, handles))
    if trust_written:
        written = np.asarray(joint.pivot, float)[[i, j]]
        distance = np.linalg.norm(points - written, axis=1)
        if distance.min() > prior.line_sigma:  # the model's line is none of the box's: keep it
            return np.asarray(joint.pivot, float)
        score = score - 0.5 * (distance / prior.line_sigma) ** 2
    best = points[int(np.argmax(score))]
    pivot = c.copy()
    pivot[i], pivot[j] = best
    return pivot


def ground_joint(joint: Joint, child: Box, parent: Box | None, handles: Sequence[Box],
                 grounding: Grounding) -> Joint:
    """One joint grounded in its part's box, its parent's box and its children's (handles)."""
    prior = grounding.resolved_prior()
    axis = np.asarray(joint.axis, float)
    axis = axis / np.linalg.norm(axis)
    k = int(np.argmax(np.abs(axis)))
    aligned = math.acos(min(1.0, abs(axis[k]))) <= AXIS_SNAP
    if grounding.axis_snap and aligned:
        axis = _unit(k, axis[k])
    new = replace(joint, axis=tuple(float(v) for v in axis))
    retyped = False
    if grounding.type_axis:
        kind, dim = _choose_class(joint, k, joint_features(child, parent, handles), prior, grounding.axis_dim_kept)
        if (kind, dim) != (joint.type, k):
            retyped = True
            c = np.asarray(child.centroid, float)
            if kind == "slide":
                out = 1.0 if parent is None else float(np.sign(round(c[dim] - parent.centroid[dim], 6)) or 1.0)
                travel = min(MAX_SLIDE, max(0.02, SLIDE_OPENING * float(child.extent[dim])))
                new = Joint("slide", tuple(float(v) for v in _unit(dim, out)), tuple(float(v) for v in c), (0.0, travel))
            else:
                new = Joint("hinge", tuple(float(v) for v in _unit(dim)), tuple(float(v) for v in c), (0.0, HINGE_OPENING))
            k, aligned = dim, True
    # the nine lines run along a box direction: the axis must be one (snapped, or new)
    if grounding.line_snap and new.type == "hinge" and aligned and (grounding.axis_snap or retyped):
        pivot = _best_line(new, k, child, parent, handles, prior, trust_written=not retyped)
        i, j = cross_dims(k)
        moved = float(np.linalg.norm((pivot - np.asarray(new.pivot, float))[[i, j]]))
        new = replace(new, pivot=tuple(float(v) for v in pivot))
        if retyped or moved > prior.line_sigma:
            new = opening_outward(new, child, parent)
    elif retyped and new.type == "hinge":
        new = opening_outward(new, child, parent)
    return new


def ground_structure(structure: Structure, boxes: Mapping[int, Box], grounding: Grounding) -> Structure:
    """``structure`` with every joint of a part with a box grounded; everything else as it was."""
    nodes = dict(structure.nodes)
    for pid, node in structure.nodes.items():
        if node.joint is None or pid not in boxes:
            continue
        handles = [boxes[c] for c in structure.children(pid) if c in boxes]
        parent = boxes.get(node.parent) if node.parent is not None else None
        nodes[pid] = replace(node, joint=ground_joint(node.joint, boxes[pid], parent, handles, grounding))
    return replace(structure, nodes=nodes)


def ground_text(text: str, boxes: Mapping[int, Box], grounding: Grounding) -> str:
    """A generated document with its joints grounded in the legend ``boxes``.

    The JSON object inside ``text`` (an unconstrained model may fence it; a tokenizer may spell out
    the stop token after it) is replaced; a text whose JSON does not parse and validate against
    the legend's part ids is returned unchanged, so the validator reports the model's own error.
    """
    if not boxes:
        return text
    return rewrite_structure(text, boxes.keys(),
                             lambda structure, _: to_dict(ground_structure(structure, boxes, grounding)))
