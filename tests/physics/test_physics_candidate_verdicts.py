"""Best-of-K and repair with backend "mjx" (the candidates' interpenetration sweeps in one MJX launch,
``jax3dc.physics.candidate_verdicts``) against the C path: the same winner, the same verdict lines
for every candidate, the same repairs, on factory objects of several categories and seeds and on
PartNet-Mobility fixtures. Candidates are the object's own structure, perturbations of its joints
(flipped axis, moved pivot, wrong type; ``eval.verdict_accuracy.candidates``) and one text that
does not parse."""

from __future__ import annotations

import pytest

from eval.verdict_accuracy.candidates import sampled_candidates
from eval.verdict_accuracy.ground_truth import factory_objects, imported_objects
from jax3dc.geometry.parts import part_boxes
from jax3dc.physics.candidate_verdicts import candidate_verdicts
from jax3dc.structure import to_json
from jax3dc.verify.repair import repair
from jax3dc.verify.select import Candidate, Choice, choose, parse_candidate
from jax3dc.verify.verdicts import Physics, VerdictCache
from tests.physics.test_physics_ground_truth import PARTNET_MOBILITY

K = 8
FACTORY = (("cabinet", 0), ("cabinet", 1), ("laptop", 2), ("microwave", 0))
FIXTURES = ("window_rotate_103135", "door_8877")  # the fixtures of fewest geom pairs: a CPU pads every launch to the largest


def _objects():
    """The fixtures first: the window has the most geom pairs, and the launches after it, padded to
    the largest shapes met, reuse its compiled code."""
    yield from imported_objects([PARTNET_MOBILITY / name for name in FIXTURES])
    for category, seed in FACTORY:
        yield from factory_objects([category], [seed])


def _lines(choice: Choice) -> list:
    """Per candidate: parse rule, or the verdict's lines (ok, per joint reasons and warnings, object checks)."""
    out = []
    for row in choice.rows:
        if not row.parsed:
            out.append(row.rule)
            continue
        verdict = row.verdict.to_json()
        out.append((verdict["ok"], verdict["joints"], verdict["checks"]))
    return out


def _choose(obj, candidates, backend: str) -> tuple[Choice, VerdictCache]:
    boxes = part_boxes(obj.parts)
    check = VerdictCache(Physics(obj.parts, obj.scale, obj.mounted, backend, threads=1))
    return choose(candidates, boxes, check), check


def test_mjx_chooses_as_c_does():
    """Factory objects and fixtures: the same winner, reason and verdict lines per candidate; a
    set whose winner fails is repaired alike (same joints, same verdict after)."""
    repaired = 0
    for n, obj in enumerate(_objects()):
        candidates = sampled_candidates(obj.structure, obj.parts, K - 1, seed=n) + [Candidate('{"nodes": ', -1.0)]
        assert len(candidates) >= 4, obj.name
        c, c_check = _choose(obj, candidates, "c")
        mjx, mjx_check = _choose(obj, candidates, "mjx")
        assert (mjx.index, mjx.reason) == (c.index, c.reason), obj.name
        assert _lines(mjx) == _lines(c), obj.name
        worst = min((i for i, r in enumerate(c.rows) if r.parsed), key=lambda i: c.rows[i].verdict.merit())
        if c.rows[worst].ok or repaired >= 2:  # repairs are slow on a CPU: two objects show it
            continue
        boxes = part_boxes(obj.parts)
        flagged = parse_candidate(candidates[worst].text, boxes.keys(), boxes)
        fixed = [repair(flagged, boxes, check) for check in (c_check, mjx_check)]
        assert to_json(fixed[1].structure) == to_json(fixed[0].structure), obj.name
        assert [r.to_dict() for r in fixed[1].repairs] == [r.to_dict() for r in fixed[0].repairs], obj.name
        assert fixed[1].after.to_json()["joints"] == fixed[0].after.to_json()["joints"], obj.name
        repaired += 1
    assert repaired == 2


def test_bad_backend_and_empty_batch():
    obj = next(factory_objects(["cabinet"], [0]))
    with pytest.raises(ValueError, match="physics backend must be 'c' or 'mjx', got 'gpu'"):
        Physics(obj.parts, obj.scale, obj.mounted, "gpu")
    assert candidate_verdicts([], obj.parts, obj.scale, obj.mounted) == []
