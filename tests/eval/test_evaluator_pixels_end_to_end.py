"""eval.evaluators.pixels_end_to_end on a procedural record and an imported real one (no factory
parameters): the factory network's and a tiny slots network's rows beside the true parts' row, on
the rest views only; and its box score is 0 for the reference's own parts and 2 for none.

Stage 2 has no model folder (as in tests/predict/test_predict_slots.py: the structure model's
compiles would take most of a minute on two cores), so every predict stops after stage 1 — the case
where a backend's parts must still be scored. The true parts' row reads the records' own targets
(--true-parts)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from flax import nnx

from data_pipeline.build import BuildConfig, factory_sources, import_sources, run_build
from data_pipeline.shards import shard_paths
from eval.evaluators.pixels_end_to_end import main
from eval.pixels import score_boxes
from eval.records import read_records, reference_of
from jax3dc.stage1_slots import SlotsNet, SlotsNetConfig, save_slots
from tests.shared_fixtures import partnet_object

SLOTS = 4


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A stapler from its factory and the PartNet-Mobility door imported as `jax3dc data import`
    does, two views each (view 1 has a joint moved)."""
    folder = tmp_path_factory.mktemp("pixels_data")
    run_build(folder, factory_sources(1, 0, ["stapler"]) + import_sources([partnet_object("door_8877")]),
              BuildConfig(2, 0, 64, 4, split="test"), workers=1, progress=False)
    return folder


def _slots_model(folder):
    """A tiny random slots network whose every slot exists."""
    model = SlotsNet(SlotsNetConfig.tiny(slots=SLOTS), nnx.Rngs(0))
    model.exists.bias[...] = np.full((1,), 8.0, np.float32)
    model.exists.kernel[...] = np.zeros_like(model.exists.kernel[...])
    return save_slots(folder, model)


def test_both_backends_and_the_true_parts_are_scored_on_the_rest_views(data, tmp_path):
    records = list(read_records(shard_paths([data], "test"), "test"))
    rest = [r for r in records if r.meta["moved_joint"] is None]
    assert len(records) == 4 and len(rest) == 2 and any(r.parameters is None for r in rest)
    true_parts = tmp_path / "true_parts.jsonl"
    true_parts.write_text("".join(json.dumps({"key": r.key, "text": r.target}) + "\n" for r in rest))
    out = tmp_path / "out"
    summary = main(["--data", str(data), "--slots-model", str(_slots_model(tmp_path / "slots")), "--true-parts",
                    str(true_parts), "--structure-model", str(tmp_path / "no_structure_model"), "--out", str(out)])

    assert summary["records"] == 2
    backends = summary["backends"]
    assert list(backends) == ["factory", "slots", "true_parts"]
    for name in ("factory", "slots"):
        b = backends[name]
        assert b["failures"] == 2 and all("no_structure_model" in row["failure"] for row in b["rows"])
        assert b["parts"]["objects"] == 2 and b["parts"]["predicted_parts"] > 0  # scored although stage 2 stopped
        assert b["parts"]["reference_parts"] == sum(len(reference_of(r).boxes) for r in rest)
        assert 0.0 <= b["parts"]["rs_dgiou"] <= 2.0
    assert backends["slots"]["parts"]["predicted_parts"] == 2 * SLOTS
    joints = sum(len(reference_of(r).structure.joints()) for r in rest)
    assert backends["true_parts"]["joints"] == {**backends["true_parts"]["joints"], "success": joints,
                                                "ref_joints": joints}
    table = (out / "summary.md").read_text()
    rows = [line for line in table.splitlines() if line.startswith("| ")]
    assert [row.split(" | ")[0] for row in rows[1:]] == ["| factory network (stage1)", "| slots (slots)",
                                                         "| true parts (stage 2 alone)"]
    assert f"| {joints} of {joints} | 100.0 % |" in rows[-1]
    assert "through jax3dc.stage1_slots.kinds" in table and "Table 1a" in table
    assert json.loads((out / "summary.json").read_text())["backends"]["slots"]["rows"][0]["parts"]["predicted"] == SLOTS


def test_the_reference_parts_score_0_and_no_parts_score_2(data):
    for record in (r for r in read_records(shard_paths([data], "test"), "test") if r.meta["moved_joint"] is None):
        reference = reference_of(record)
        names = {int(pid): name for pid, name in record.meta["part_names"].items()}
        perfect = score_boxes(record, reference, reference.boxes, names)
        assert perfect.dgiou == pytest.approx(0.0, abs=1e-9)
        assert perfect.matched == perfect.reference == len(reference.boxes) and perfect.extra == 0
        assert perfect.kinds_right == perfect.kinds_scored == len(names)
        nothing = score_boxes(record, reference, {}, {})
        assert nothing.dgiou == 2.0 and nothing.matched == 0 and nothing.predicted == 0
