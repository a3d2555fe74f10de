"""Board crossings of many verdicts in one launch (jax3dc.physics.crossing_batch) against the numpy
path (crossing.first_crossings), one query at a time; and the candidate verdicts and the device
service that send their queries to it."""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import threading

import numpy as np

from eval.verdict_accuracy.candidates import sampled_candidates
from eval.verdict_accuracy.ground_truth import factory_objects
from jax3dc.geometry.parts import part_boxes
from jax3dc.physics.candidate_verdicts import candidate_verdicts
from jax3dc.physics.crossing import crossing_plan, first_crossings
from jax3dc.physics.crossing_batch import CHUNK_POINTS, CrossingShapes, batch_first_crossings
from jax3dc.physics.mjx_service import DeviceClient, DeviceService
from jax3dc.physics.mjx_batch import object_arrays
from jax3dc.physics.verdict import crossing_plan_of, kinematic_inputs
from jax3dc.verify.select import parse_candidate
from tests.physics.test_physics_crossing import _box_with_lid

CATEGORIES = (("laptop", 0), ("dishwasher", 0))  # a folding screen, a door and racks


def _candidate_structures(category: str, seed: int):
    obj = next(factory_objects([category], [seed]))
    boxes = part_boxes(obj.parts)
    structures = [obj.structure]
    for candidate in sampled_candidates(obj.structure, obj.parts, 5, seed=seed):
        with contextlib.suppress(Exception):
            structures.append(parse_candidate(candidate.text, boxes.keys(), boxes))
    return obj, structures


def _plans(obj, structures):
    plans = []
    for s in structures:
        inputs = kinematic_inputs(s, obj.parts, obj.scale)
        plans.append(crossing_plan_of(s, obj.parts, inputs.sim, inputs.states))
    return plans


def test_batched_states_are_the_numpy_states_of_every_query():
    """Factory candidates (perturbed joints cross boards): every query's first state, hits and
    misses, as numpy finds it, tracks longer than a chunk included; and again with every capacity
    padded further (a later launch of a sweep pads to the largest met)."""
    plans = [p for category, seed in CATEGORIES for p in _plans(*_candidate_structures(category, seed))]
    want = [first_crossings(p) for p in plans]
    assert sum(s is not None for w in want for s in w) >= 10  # crossings happen among them
    assert any(len(t.rest) > CHUNK_POINTS for p in plans for t in p.tracks)
    got, shapes = batch_first_crossings(plans)
    assert got == want
    more = CrossingShapes(shapes.items * 2, shapes.chunks + 8, shapes.tracks + 8, shapes.boards + 8, shapes.states * 2,
                          (shapes.cells[0] + 8, shapes.cells[1] + 8))
    assert batch_first_crossings(plans[-3:], more)[0] == want[-3:]


def test_hand_built_lid_and_an_empty_plan():
    """The lid swung the wrong way crosses its base at the numpy state; a plan without queries (no
    boards, or a joint that does not move) answers nothing, alone and beside another."""
    structure, parts = _box_with_lid()
    wrong = crossing_plan(structure, parts, {2: -np.linspace(0.0, 1.5, 9)})
    still = crossing_plan(structure, parts, {2: np.zeros(3)})
    assert not still.queries
    got, _ = batch_first_crossings([still, wrong])
    assert got == [[], first_crossings(wrong)]
    assert wrong.resolve(got[1])[2][0] == 1
    assert batch_first_crossings([still])[0] == [[]]


def test_candidate_verdicts_and_the_service_give_the_numpy_verdicts():
    """The crossing queries in the launch (in this process, and through a device service's request
    of their own beside the sweeps) change no verdict of a toilet's candidates (two of them cross a board)."""
    obj, structures = _candidate_structures("toilet", 0)
    plans = _plans(obj, structures)
    structures = [s for n, (s, p) in enumerate(zip(structures, plans)) if n == 0 or p.resolve(first_crossings(p))]
    want = [v.to_json() for v in candidate_verdicts(structures, obj.parts, obj.scale, obj.mounted, False, threads=1,
                                                    crossings=False)]
    got = [v.to_json() for v in candidate_verdicts(structures, obj.parts, obj.scale, obj.mounted, False, threads=1,
                                                   crossings=True)]
    assert got == want
    assert any(f["check"] == "crossing" for v in want for f in v["findings"])  # the check decided something

    service = DeviceService(mp.get_context("spawn"), 1, start_shapes={}, crossings=True)
    stop = threading.Event()
    server = threading.Thread(target=service.serve, args=(stop,), daemon=True)
    server.start()
    try:
        client = DeviceClient(0, service.requests, service.replies[0], crossings=True)
        inputs = [kinematic_inputs(s, obj.parts, obj.scale) for s in structures]
        arrays = [object_arrays(i.sim.model, ignore_margin=True) for i in inputs]
        plans = [crossing_plan_of(s, obj.parts, i.sim, i.states) for s, i in zip(structures, inputs)]
        distances, first = client.submit(arrays, [i.states.qpos for i in inputs], plans)()
    finally:
        stop.set()
        server.join()
    assert first == [first_crossings(p) for p in plans]
    assert len(distances) == len(structures) and all(d.shape[0] == len(i.states.qpos) for d, i in zip(distances, inputs))
    assert service.stats.phases.get("crossings", 0.0) > 0.0
