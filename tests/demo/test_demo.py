import json

from jax3dc.cli import main
from jax3dc.structure import parse_structure


def test_tiny_demo_runs_every_stage_with_the_shipped_model(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--size", "tiny", "--out", str(out), "--train-minutes", "0.1"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    stages = {s["stage"]: s for s in summary["stages"]}
    assert [s["stage"] for s in summary["stages"]] == [
        "data", "reference", "export", "evaluate", "baselines", "predict", "train"]
    assert all(s["status"] == "done" for s in summary["stages"]), summary
    # The shipped model on held-out records: valid structures, joints found.
    model = stages["evaluate"]["metrics"]
    assert stages["evaluate"]["objects"] == 4
    assert model["parse"] >= 75.0 and model["presence_f1"] >= 50.0, model
    predicted = stages["predict"]["objects"][0]
    assert predicted["status"] == "done" and predicted["joints"] >= 0
    assert isinstance(predicted["physics_ok"], bool)
    for name in ("structure", "mjcf", "urdf"):
        assert name in predicted["files"]
    # The same image from pixels alone (the shipped stage-1 network), scored by matched parts beside it.
    pixels = stages["predict"]["pixels"][0]
    assert pixels["key"] == predicted["key"] and pixels["status"] == "done", pixels
    assert pixels["parts_matched"] >= 1 and isinstance(pixels["physics_ok"], bool)
    assert (out / "predict" / "object_0" / "pixels" / "structure.json").is_file()
    rows = stages["predict"]["metrics"]
    assert rows["own parts"]["parse"] == rows["from pixels"]["parse"] == 100.0
    assert stages["train"]["steps"] >= 1 and (out / "train" / "hf" / "tokenizer.json").is_file()

    ref = stages["reference"]
    assert ref["objects"] >= 10
    assert all(v == 100.0 for v in ref["metrics"].values())  # the reference scores itself perfectly
    star = stages["baselines"]["metrics"]["star"]
    assert stages["baselines"]["metrics"]["heuristic"]["parse"] == 100.0
    assert star["parse"] == 100.0 and star["presence_f1"] == 0.0  # a star tree has no joints
    assert 0.0 < star["parent_acc"] < 100.0

    import mujoco  # after the demo: its renderer chooses the OpenGL backend first

    export = stages["export"]
    files = export["files"]
    structure = parse_structure((out / "asset" / "structure.json").read_text())
    assert len(structure.joints()) == export["joints_in_structure"] > 0
    for fmt in ("mjcf", "urdf"):
        assert mujoco.MjModel.from_xml_path(files[fmt]).njnt == export["joints_in_structure"]
    printed = capsys.readouterr().out
    assert "summary.json" in printed and "predict" in printed and "paper (Ours)" in printed
    assert "from pixels" in printed and "own parts" in printed
