"""verify_many: many objects in worker processes give what one process gives, in job order."""

from functools import partial

from eval.run_verify import record_object
from jax3dc.verify.pool import Job, verify_many
from jax3dc.verify.select import Candidate
from jax3dc.structure import to_json
from tests.verify.verified_cases import IMPORTED, checked_object, pivot_moved_away
from tests.shared_fixtures import partnet_object

BOX = "storage_box/storage_box_000001/0"


def test_workers_agree_with_one_process_and_repair_failing_winners(checked_records, imported_records):
    box = checked_records[BOX]
    broken = to_json(pivot_moved_away(checked_object(box).target, 2))
    door = imported_records["Door/door_8877/0"]
    jobs = [
        Job(box.key, (Candidate(broken, -1.0), Candidate(box.target, -3.0)), box),
        Job(box.key, (Candidate(broken, -1.0),), box),  # nothing better to choose: the winner is repaired
        Job(door.key, (Candidate(door.target, -2.0),), door),
    ]
    load = partial(record_object, sources={IMPORTED[0]: partnet_object(IMPORTED[0])})
    alone = verify_many(jobs, load, workers=1)
    pooled = verify_many(jobs, load, workers=2)
    assert [v.key for v in pooled] == [box.key, box.key, door.key]
    summary = [(v.choice.index, v.choice.reason, [r.flagged for r in v.choice.rows], v.repaired and v.repaired.repairs)
               for v in pooled]
    assert summary == [(v.choice.index, v.choice.reason, [r.flagged for r in v.choice.rows],
                        v.repaired and v.repaired.repairs) for v in alone]
    first, lone, door_done = pooled
    assert first.choice.index == 1 and first.repaired is None  # the winner passes: nothing to repair
    assert not lone.choice.rows[0].ok and lone.repaired.after.ok and lone.repaired.repairs
    assert door_done.choice.rows[0].ok and door_done.repaired is None


def test_mjx_workers_choose_and_repair_as_c(checked_records):
    """Backend "mjx" with workers: their candidates go to one device service in this process, and
    the choices, verdicts and repairs are C's."""
    box = checked_records[BOX]
    broken = to_json(pivot_moved_away(checked_object(box).target, 2))
    jobs = [Job(box.key, (Candidate(broken, -1.0), Candidate(box.target, -3.0)), box),
            Job(box.key, (Candidate(broken, -1.0),), box)]
    load = partial(record_object, sources={})

    def summary(verified):
        return [(v.choice.index, v.choice.reason, [r.verdict.to_json()["joints"] for r in v.choice.rows],
                 v.repaired and [r.to_dict() for r in v.repaired.repairs]) for v in verified]

    assert summary(verify_many(jobs, load, workers=2, backend="mjx")) == summary(verify_many(jobs, load, workers=1))
