"""``jax3dc physics check`` end to end, and MJX against C MuJoCo on the same joint states."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from jax3dc.cli import main
from jax3dc.geometry.parts import save_parts
from jax3dc.structure import parse_structure, to_json


def _box(extents, centre):
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(centre)
    return mesh


def _lid_box():
    """A base block and a lid hinged on its back edge: small enough for a quick MJX compile."""
    parts = {1: _box([1.0, 0.6, 0.4], [0, 0, -0.2]), 2: _box([1.0, 0.6, 0.05], [0, 0, 0.025])}
    doc = {"materials": {"0": {"family": "Wood", "desc": "pine"}},
           "nodes": {"1": {"parent": None, "material": 0},
                     "2": {"parent": 1, "material": 0,
                           "joint": {"type": "hinge", "axis": [-1, 0, 0], "pivot": [0, 0.3, 0], "range": [0, 1.8]}}},
           "relations": []}
    return parse_structure(doc, part_ids=parts.keys()), parts


def test_cli_check_writes_verdict(tmp_path, capsys):
    structure, parts = _lid_box()
    save_parts(parts, tmp_path / "parts")
    (tmp_path / "o.json").write_text(to_json(structure))
    rc = main(["physics", "check", str(tmp_path / "o.json"), "--parts", str(tmp_path / "parts"),
               "--scale", "0.5", "--out", str(tmp_path / "v.json")])
    assert rc == 0
    verdict = json.loads((tmp_path / "v.json").read_text())
    assert verdict == json.loads(capsys.readouterr().out)
    assert verdict["ok"] and verdict["joints"]["2"] == {"ok": True, "reasons": [], "warnings": []}
    # a lid hinged the wrong way swings into the base: still exit 0, the verdict says why
    flipped = to_json(structure).replace('"axis":[-1.0,0.0,0.0]', '"axis":[1.0,0.0,0.0]')
    assert flipped != to_json(structure)
    (tmp_path / "bad.json").write_text(flipped)
    assert main(["physics", "check", str(tmp_path / "bad.json"), "--parts", str(tmp_path / "parts")]) == 0
    reasons = json.loads(capsys.readouterr().out)["joints"]["2"]["reasons"]
    assert any(r.startswith("penetrates part 1") for r in reasons), reasons


def test_cli_check_rejects_unusable_input(tmp_path, capsys):
    structure, parts = _lid_box()
    (tmp_path / "o.json").write_text(to_json(structure))
    assert main(["physics", "check", str(tmp_path / "o.json"), "--parts", str(tmp_path / "missing")]) == 1
    save_parts({1: parts[1]}, tmp_path / "one")  # node 2 has no mesh
    assert main(["physics", "check", str(tmp_path / "o.json"), "--parts", str(tmp_path / "one")]) == 1
    save_parts(parts, tmp_path / "parts")
    assert main(["physics", "check", str(tmp_path / "o.json"), "--parts", str(tmp_path / "parts"), "--scale", "-1"]) == 1


@pytest.mark.slow
def test_mjx_and_c_give_the_same_penetration_verdicts():
    from jax3dc.physics.cpu_backend import pair_distances
    from jax3dc.physics.mjx_backend import PairDistances
    from jax3dc.physics.sim_model import SimOptions, build_sim_model
    from jax3dc.physics.tolerances import PENETRATION_TOL_NU

    structure, parts = _lid_box()
    sim = build_sim_model(structure, parts, 0.5, SimOptions())
    rng = np.random.default_rng(0)
    qpos = rng.uniform(-1.8, 1.8, size=(48, sim.model.nq))  # negative angles swing the lid into the base
    c = pair_distances(sim.model, qpos)
    g = np.asarray(PairDistances(sim.model)(qpos), dtype=np.float64)
    tol = PENETRATION_TOL_NU * 0.5
    pen_c, pen_g = (c < -tol).any(axis=(1, 2)), (g < -tol).any(axis=(1, 2))
    assert pen_c.any() and not pen_c.all()
    assert np.array_equal(pen_c, pen_g)
    both = np.isfinite(c) & np.isfinite(g) & (c < -tol)
    np.testing.assert_allclose(g[both], c[both], atol=2e-3 * 0.5 + 0.01 * np.abs(c[both]).max())


def _sweep_build(tmp_path):
    """A data build of two factory objects, an import without a program, and two unusable records."""
    from jax3dc.factories import generate_object
    from data_pipeline.record import Record
    from data_pipeline.shards import write_dataset

    records = []
    for category in ("microwave", "laptop"):
        obj = generate_object(category, 0)
        meta = {"category": category, "object_id": obj.object_id, "view": 0, "scale": obj.scale_m_per_nu,
                "moved_joint": None, "augmentation": None}
        records.append(Record(f"{category}/{obj.object_id}/0", b"", b"", "", to_json(obj.structure),
                              obj.program_text, meta))
    records.append(Record("imported/x/0", b"", b"", "", records[0].target, None,
                          {"object_id": "imported_x", "view": 0}))
    records.append(Record("bad/program/0", b"", b"", "", records[0].target, "part(1, box((1, 1, 1))\n",
                          {"object_id": "bad_program", "view": 0}))
    records.append(Record("bad/target/0", b"", b"", "", records[0].target[:-2], records[0].program,
                          {"object_id": "bad_target", "view": 0}))
    write_dataset(tmp_path, records)
    return tmp_path


def test_sweep_reads_the_scale_the_data_build_writes():
    from eval.physics_sweep import record_scale

    assert record_scale({"scale_m_per_nu": 0.32, "object_id": "kettle_1"}) == 0.32
    assert record_scale({"scale": 1.5}) == 1.5
    assert record_scale({}) == 1.0


def test_cli_sweep_writes_report(tmp_path):
    build = _sweep_build(tmp_path / "build")
    out = tmp_path / "report"
    assert main(["physics", "sweep", str(build), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["objects"] == 2 and summary["skipped"] == 3 and summary["joints"] >= 2
    lines = {line["object"]: line for line in map(json.loads, (out / "verdicts.jsonl").read_text().splitlines())}
    assert set(lines) == {"microwave_000000", "laptop_000000", "imported_x", "bad_program", "bad_target"}
    # an unusable record is reported with the error and where it is, and the sweep goes on
    assert lines["bad_program"]["skipped"].startswith("ProgramError: line 1")
    assert lines["bad_target"]["skipped"].startswith("StructureError: line ")
    assert (out / "plots" / "microwave_000000.png").stat().st_size > 0
    assert "| microwave_000000 |" in (out / "index.md").read_text()
    # objects checked in two worker processes: the same report
    parallel = tmp_path / "parallel"
    assert main(["physics", "sweep", str(build), "--out", str(parallel), "--workers", "2"]) == 0
    assert (parallel / "verdicts.jsonl").read_text() == (out / "verdicts.jsonl").read_text()
    with pytest.raises(SystemExit) as exit_:
        main(["physics", "sweep", str(build), "--out", str(parallel), "--workers", "0"])
    assert exit_.value.code == 2


def test_cli_sweep_worker_error_is_one_line(tmp_path, capsys):
    """A plot that cannot be written in a worker process ends the sweep with the error naming the
    file (exit 1), as in one process, not with a broken process pool."""
    build = _sweep_build(tmp_path / "build")
    out = tmp_path / "report"
    out.mkdir()
    (out / "plots").write_text("a file where the plots folder goes")
    assert main(["physics", "sweep", str(build), "--out", str(out), "--workers", "2"]) == 1
    assert "plots/microwave_000000.png: cannot write the plot" in capsys.readouterr().err


def test_cli_sweep_on_mjx_writes_the_c_verdicts(tmp_path):
    """``physics sweep --backend mjx``: worker processes send their states to the batched device
    check in the main process; the verdicts file is the C backend's, and the summary says what the
    device did (launches, compiles)."""
    build = _sweep_build(tmp_path / "build")
    c, mjx = tmp_path / "c", tmp_path / "mjx"
    assert main(["physics", "sweep", str(build), "--out", str(c)]) == 0
    # its own process: the device service's arrays stay out of the test runner's memory
    subprocess.run([sys.executable, "-m", "jax3dc.cli", "physics", "sweep", str(build), "--out", str(mjx), "--backend", "mjx",
                    "--workers", "2", "--compile-cache", ""], check=True, cwd=Path(__file__).resolve().parents[2],
                   env={**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).resolve().parents[2]),
                                                                      os.environ.get("PYTHONPATH")]))}, capture_output=True)
    assert (mjx / "verdicts.jsonl").read_text() == (c / "verdicts.jsonl").read_text()
    device = json.loads((mjx / "summary.json").read_text())["device"]
    assert device["objects"] == 2 and 1 <= device["launches"] <= 2 and device["compiles"] >= 2
    assert device["states"] > 2 and device["shapes"]["objects"] == 16
    costs = [json.loads(line) for line in (mjx / "costs.jsonl").read_text().splitlines()]
    assert {c["object"] for c in costs} == {"microwave_000000", "laptop_000000"}
    assert all(c["seconds"] > 0 and c["pieces"] >= c["parts"] >= 2 for c in costs)
