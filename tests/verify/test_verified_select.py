"""choose: parses > passes the physics check > fewer flagged joints > higher log-likelihood."""

import json

import pytest

import jax3dc.verify.verdicts as verdicts
from jax3dc.verify.select import Candidate, choose
from jax3dc.structure import to_dict, to_json
from tests.verify.verified_cases import checked_object, pivot_moved_away, with_joint

BOX = "storage_box/storage_box_000001/0"
MICROWAVE = "microwave/microwave_000001/0"


def run(obj, candidates):
    return choose(candidates, obj.boxes, obj.check())


@pytest.fixture
def box(checked_records):
    return checked_object(checked_records[BOX])


def test_a_parsing_candidate_beats_an_unparsable_likelier_one(box):
    choice = run(box, [Candidate('{"nodes": {', -0.5), Candidate(to_json(box.target), -9.0)])
    assert choice.index == 1 and choice.structure == box.target
    assert choice.reason == "only candidate that parses"
    bad, good = choice.rows
    assert not bad.parsed and bad.rule and bad.verdict is None and bad.logprob == -0.5
    assert good.parsed and good.ok and good.flagged == 0


def test_node_ids_other_than_the_legend_do_not_parse(box):
    doc = to_dict(box.target)
    doc["nodes"]["9"] = doc["nodes"].pop("5")
    choice = run(box, [Candidate(to_json(box.target) + "\n", -3.0), Candidate(json.dumps(doc), -1.0)])
    assert choice.index == 0 and choice.rows[1].rule == "part_ids"


def test_the_physics_check_beats_likelihood(box):
    broken = pivot_moved_away(box.target, 2)
    choice = run(box, [Candidate(to_json(broken), -1.0), Candidate(to_json(box.target), -7.0)])
    assert choice.index == 1 and choice.structure == box.target
    assert choice.rows[0].parsed and not choice.rows[0].ok and choice.rows[0].flagged == 1
    assert choice.reason == "passes the physics check; 1 other fails"


def test_fewer_flagged_joints_win_when_none_passes(checked_records):
    microwave = checked_object(checked_records[MICROWAVE])
    tilted = with_joint(microwave.target, 5, axis=(1.0, 0.0, 0.0))  # the turntable turned on its side
    both_broken = pivot_moved_away(tilted, 2)  # ... and the door off its hinge line
    choice = run(microwave, [Candidate(to_json(both_broken), -1.0), Candidate(to_json(tilted), -4.0)])
    assert [row.flagged for row in choice.rows] == [2, 1]
    assert choice.index == 1 and choice.reason == "fewest flagged joints (1 vs 2)"


def test_likelihood_breaks_ties_and_identical_structures_are_checked_once(box, monkeypatch):
    calls = []
    real = verdicts.verdict_with_curves
    monkeypatch.setattr(verdicts, "verdict_with_curves", lambda *a, **k: calls.append(1) or real(*a, **k))
    same = to_json(box.target)
    fenced = f"```json\n{same}\n```"  # the same structure as a model may wrap it
    choice = run(box, [Candidate(same, -6.0), Candidate(fenced, -2.0), Candidate(same, -4.0)])
    assert choice.index == 1 and choice.reason == "highest log-likelihood among equals"
    assert len(calls) == 1
    assert all(row.ok for row in choice.rows)


def test_no_candidate_parses(box):
    choice = run(box, [Candidate("nope", -3.0), Candidate("{}", -1.0)])
    assert choice.index == 1 and choice.structure is None
    assert choice.reason == "no candidate parses; highest log-likelihood"
