"""Typed findings (jax3dc.physics.findings): what the checks produce, how the verdict counts them, and a
limit far past the first contact as a failure with the value the joint reaches."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from eval.verdict_accuracy import ground_truth
from eval.verdict_accuracy.mutations import DETACHED, LIMIT, PENETRATES, PIVOT, RELATION
from jax3dc.factories import generate_object
from jax3dc.physics.findings import CHECKS, FAILURE, WARNING, Finding, Verdict, describe
from jax3dc.physics.tolerances import LIMIT_PAST_CONTACT_HINGE_RAD
from jax3dc.physics.verdict import check_object


def test_findings_round_trip_through_json_and_read_as_the_stable_reasons():
    found = [
        Finding("penetration", joints=(3,), parts=(1,), depth=0.04, state=((3, 1.2),)),
        Finding("penetration", joints=(6,), parts=(1,), depth=0.03, state=((3, 0.4),)),
        Finding("crossing", joints=(5,), parts=(2,), state=((2, -0.25),)),
        Finding("rest gap", joints=(4,), parts=(1,)),
        Finding("carried out of guide", joints=(7,), parts=(2,), state=((7, 0.3), (2, 1.0))),
        Finding("limit", WARNING, joints=(3,), reachable=2.7721, limit="hi"),
        Finding("limit", FAILURE, joints=(3,), reachable=0.9, limit="lo"),
        Finding("gravity", depth=0.21, tilt=0.5),
    ]
    assert [describe(f) for f in found] == [
        "penetrates part 1 at q=1.200",
        "penetrates part 1 while joint 3 moves (q=0.400)",
        "penetrates part 2 (passes through it) while joint 2 moves (q=-0.250)",
        "detached from parent at rest (gap over 0.2 nu)",
        "detached from its guide (part 2, runs out of it with joint 7 at 0.300, joint 2 at 1.000)",
        "limit past contact: hi (stops at q=2.772)",
        "limit unreachable: lo (stops at q=0.900)",
        "unstable under gravity: root moved 0.210 nu, tilted 0.50 rad",
    ]
    text = json.dumps([f.to_json() for f in found])
    assert [Finding.from_json(d) for d in json.loads(text)] == found
    # numpy scalars from the checks become plain numbers
    found = Finding("guide", joints=(np.int64(4),), depth=np.float64(0.25), state=((np.int64(4), np.float64(0.5)),))
    assert found == Finding("guide", joints=(4,), depth=0.25, state=((4, 0.5),))
    assert json.dumps(found.to_json()) == '{"check": "guide", "severity": "failure", "joints": [4], "depth": 0.25, "state": [[4, 0.5]]}'
    with pytest.raises(ValueError):
        Finding("limit", "error")
    with pytest.raises(ValueError):
        Finding("no such check")


def test_the_verdict_fails_on_failures_only():
    found = [Finding("limit", WARNING, joints=(3,), reachable=2.77, limit="hi"),
             Finding("combination", WARNING, parts=(2, 3))]
    verdict = Verdict((3, 5), tuple(found)).to_json()
    assert verdict["ok"] and verdict["joints"]["3"] == {"ok": True, "reasons": [], "warnings": [describe(found[0])]}
    assert verdict["checks"] == {"rest": [], "combinations": ["combination interpenetration: parts 2,3"], "gravity": []}
    assert [Finding.from_json(d) for d in verdict["findings"]] == found
    failed = Verdict((3, 5), (*found, Finding("pivot", joints=(5,), parts=(1,)))).to_json()
    assert not failed["ok"] and failed["joints"]["3"]["ok"] and failed["joints"]["5"]["reasons"] == ["pivot detached"]
    rest = Verdict((3,), (Finding("rest", parts=(1, 2), depth=0.08),), gravity_checked=False).to_json()
    assert not rest["ok"] and rest["checks"] == {"rest": ["rest interpenetration: parts 1,2"], "combinations": []}


def _doors_to(structure, doors, hi):
    nodes = dict(structure.nodes)
    for p in doors:
        joint = nodes[p].joint
        nodes[p] = dataclasses.replace(nodes[p], joint=dataclasses.replace(joint, range=(joint.range[0], hi)))
    return dataclasses.replace(structure, nodes=nodes)


def test_a_limit_far_past_the_first_contact_fails_with_where_the_joint_stops():
    # the cabinet's doors opened past lying flat fold back round the carcass and stop there, about
    # 3.2-3.6 rad (both doors, or the relation check flags the pair); the PartNet safe's door, a
    # limit a little past its contact, is a warning (test_physics_ground_truth)
    cabinet = generate_object("cabinet", 0)
    doors = sorted(p for p, n in cabinet.structure.nodes.items() if n.joint is not None and n.joint.type == "hinge")
    assert doors == [3, 5]
    far = check_object(_doors_to(cabinet.structure, doors, 4.2), cabinet.parts, cabinet.scale_m_per_nu)
    stops = [Finding.from_json(f) for f in far["findings"] if f["check"] == "limit"]
    assert {f.joints[0] for f in stops} == {3, 5} and all(f.severity == FAILURE and f.limit == "hi" for f in stops), far
    assert not far["ok"] and all(4.2 - f.reachable > LIMIT_PAST_CONTACT_HINGE_RAD for f in stops)
    assert all(far["joints"][str(f.joints[0])]["reasons"] == [describe(f)] for f in stops)


def test_ground_truth_counts_a_warned_joint_as_flagged_but_not_failing(monkeypatch):
    warning = Finding("limit", WARNING, joints=(3,), reachable=2.77, limit="hi")
    monkeypatch.setattr(ground_truth, "verdict_with_curves", lambda *args, **kwargs: (Verdict((3, 5), (warning,)), {}))
    obj = ground_truth.GroundTruthObject("safe", None, {}, 1.0)
    counts = ground_truth.false_alarms([obj])
    assert (counts["joints"], counts["flagged"], counts["failing"], counts["objects_failed"]) == (2, 1, 0, [])
    assert counts["findings"] == [warning]


# one finding of every check (joints 2-9 of an object with parts 1-9), values at the JSON's decimals
EVERY_CHECK = (
    Finding("rest", parts=(3, 1), depth=0.08),
    Finding("rest parent", joints=(2,), parts=(1,), depth=0.05),
    Finding("penetration", joints=(2,), parts=(1,), depth=0.04, state=((2, 1.2),)),
    Finding("penetration", joints=(3,), parts=(1,), depth=0.03, state=((2, 0.4),)),
    Finding("crossing", joints=(3,), parts=(2,), state=((3, -0.25),)),
    Finding("floor", joints=(4,), depth=0.02, state=((4, 0.7),)),
    Finding("detached", joints=(4,), depth=0.3, state=((4, 1.5),)),
    Finding("lifted off", joints=(5,), state=((5, 0.12),)),
    Finding("guide", joints=(5,), state=((5, 0.4),)),
    Finding("carried out of guide", joints=(6,), parts=(5,), state=((6, 0.3), (5, 1.0))),
    Finding("rest gap", joints=(6,), parts=(1,), depth=0.031),
    Finding("rest gap", joints=(7,), parts=(1,)),
    Finding("pivot", joints=(7,), parts=(1,)),
    Finding("relation parents", joints=(8,), parts=(9, 1, 4), relation="symmetric"),
    Finding("relation joint type", joints=(8,), parts=(9,), relation="instance", joint_types=("hinge", "slide")),
    Finding("relation motion", joints=(9,), parts=(8,), depth=0.125, relation="symmetric"),
    Finding("limit", joints=(2,), reachable=0.9, limit="lo"),
    Finding("limit", WARNING, joints=(3,), reachable=2.7721, limit="hi"),
    Finding("sag", joints=(9,), depth=0.0312),
    Finding("gravity", depth=0.21, tilt=0.5),
    Finding("gravity", parts=(1,), depth=0.4, tilt=1.25),
    Finding("combination", WARNING, parts=(4, 2)),
)


@pytest.mark.parametrize("gravity_checked", [True, False])
def test_a_verdict_of_every_check_reads_back_from_its_json_as_it_was(gravity_checked):
    assert {f.check for f in EVERY_CHECK} == set(CHECKS)  # a new check joins EVERY_CHECK
    found = tuple(f for f in EVERY_CHECK if gravity_checked or f.check != "gravity")
    verdict = Verdict(tuple(range(2, 10)), found, gravity_checked)
    text = json.dumps(verdict.to_json(), indent=1, sort_keys=True)  # as physics.json holds it
    again = Verdict.from_json(json.loads(text))
    assert again == verdict and again.to_json() == verdict.to_json()
    assert ("gravity" in again.to_json()["checks"]) == gravity_checked


def test_a_blown_up_rollout_reads_back_with_the_same_reasons():
    """JSON has no NaN: a non-finite float is written null and read back as NaN (an absent one is None)."""
    verdict = Verdict((2,), (Finding("gravity", depth=float("nan"), tilt=float("inf")),
                             Finding("sag", joints=(2,), depth=float("nan")), Finding("rest gap", joints=(2,), parts=(1,))))
    data = json.loads(json.dumps(verdict.to_json()))
    assert data["findings"][0]["depth"] is None and "depth" not in data["findings"][2]
    again = Verdict.from_json(data)
    assert again.to_json()["joints"] == data["joints"] and again.findings[2].depth is None
    assert again.to_json()["checks"]["gravity"] == ["unstable under gravity: root moved nan nu, tilted nan rad"]


def test_the_joint_findings_are_what_the_json_lists_beside_each_joint():
    verdict = Verdict(tuple(range(2, 10)), EVERY_CHECK)
    data = verdict.to_json()
    for part in verdict.joint_parts:
        joint = data["joints"][str(part)]
        assert joint["reasons"] == [describe(f) for f in verdict.joint_findings(part, FAILURE)]
        assert joint["warnings"] == [describe(f) for f in verdict.joint_findings(part, WARNING)]
        assert verdict.joint_findings(part) == tuple(f for f in EVERY_CHECK if f.joints[:1] == (part,))
    assert verdict.object_reasons() == data["checks"]
    assert data["checks"]["rest"] == ["rest interpenetration: parts 1,3"]


def test_the_mutations_expect_the_checks_whose_reasons_they_named():
    """The checks a mutation expects are those whose reasons start as the expected reasons did."""
    groups = {("penetrates",): PENETRATES, ("detached",): DETACHED, ("pivot detached",): PIVOT,
              ("limit unreachable", "limit past contact"): LIMIT, ("disagrees with part",): RELATION}
    joint_level = [f for f in EVERY_CHECK if f.joints]
    for prefixes, checks in groups.items():
        assert set(checks) <= set(CHECKS)
        assert {f.check for f in joint_level if describe(f).startswith(prefixes)} == set(checks), prefixes


def test_the_json_form_is_the_same_for_floats_a_backend_apart():
    """C (float64) and MJX (float32) measured this depth 3e-8 apart; their verdict files agree."""
    c = Finding("penetration", joints=(2,), parts=(1,), depth=0.13386382328205643, state=((2, 0.90000001),))
    mjx = Finding("penetration", joints=(2,), parts=(1,), depth=0.13386379182338715, state=((2, 0.9),))
    assert c != mjx and c.to_json() == mjx.to_json()
    assert c.to_json()["depth"] == 0.1339 and c.to_json()["state"] == [[2, 0.9]]
