"""The named axes and hinge lines a hand edit picks from (SPEC §9), in words a page can list.

An axis is one of a part's box directions, ``+x`` ... ``-z`` (the frame of SPEC §2: +Z up, the
front facing -Y). A hinge line is one of the nine lines of the moving part's box along its axis
that joint grounding scores (``jax3dc.grounding.features.LINES``): its four edges, four face
centre lines and its centre line, named by the box faces they lie on: ``edge +x -y`` (the edge
where the +x and -y faces meet), ``face -x`` (the middle of the -x face), ``centre``. The names
depend on the axis (an axis along z has the edges of the x and y faces), so a page asks
``hinge_lines`` for the ones that exist.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from jax3dc.grounding.features import LINES, cross_dims
from jax3dc.structure.schema import Box, Vec3

LETTERS = "xyz"
AXES: dict[str, Vec3] = {f"{sign}{LETTERS[k]}": tuple(float(s * (d == k)) for d in range(3))
                         for k in range(3) for sign, s in (("+", 1), ("-", -1))}
AXIS_TOLERANCE = 0.25  # rad: an axis this close to a box direction runs along it (SPEC §5's axis gate)
CENTRE = "centre"
ON_LINE = 0.01  # nu: a pivot this close to a line lies on it (structure.json keeps 3 decimals)


def box_direction(axis: Sequence[float]) -> int | None:
    """The box direction (0, 1, 2 for x, y, z) ``axis`` runs along, within AXIS_TOLERANCE; None
    for a free axis, which has no named lines."""
    norm = math.sqrt(sum(float(c) ** 2 for c in axis))
    k = max(range(3), key=lambda d: abs(float(axis[d])))
    return k if math.acos(min(1.0, abs(float(axis[k])) / norm)) <= AXIS_TOLERANCE else None


def line_name(k: int, fractions: tuple[float, float]) -> str:
    """The name of the line at box-side ``fractions`` across direction ``k`` (see the module docstring)."""
    faces = [f"{'+' if g > 0 else '-'}{LETTERS[d]}" for d, g in zip(cross_dims(k), fractions) if g != 0]
    if not faces:
        return CENTRE
    return ("face " if len(faces) == 1 else "edge ") + " ".join(faces)


def hinge_lines(box: Box, axis: Sequence[float]) -> dict[str, Vec3]:
    """Name -> a point on that line (its middle along the axis, nu) for the nine lines of ``box``
    along ``axis``, in ``LINES`` order; empty for a free axis."""
    k = box_direction(axis)
    if k is None:
        return {}
    out: dict[str, Vec3] = {}
    for fractions in LINES:
        point = list(box.centroid)
        for d, g in zip(cross_dims(k), fractions):
            point[d] += g * box.extent[d]
        out[line_name(k, fractions)] = tuple(float(v) for v in point)
    return out


def axis_name(axis: Sequence[float]) -> str | None:
    """The name of ``axis`` when it is one of AXES (as structure.json writes it), else None."""
    for name, unit in AXES.items():
        if all(abs(float(a) - u) <= 1e-6 for a, u in zip(axis, unit)):
            return name
    return None


def line_at(box: Box, axis: Sequence[float], pivot: Sequence[float]) -> str | None:
    """The name of the line of ``box`` along ``axis`` nearest ``pivot``, when within ON_LINE across
    the axis (a thin part's edges and face line are close); None for a free axis or a line off the nine (a hinge on its parent's edge)."""
    k = box_direction(axis)
    if k is None:
        return None
    i, j = cross_dims(k)
    distance = {name: math.hypot(float(pivot[i]) - point[i], float(pivot[j]) - point[j])
                for name, point in hinge_lines(box, axis).items()}
    nearest = min(distance, key=distance.get)
    return nearest if distance[nearest] <= ON_LINE else None
