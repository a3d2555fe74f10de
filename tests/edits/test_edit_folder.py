"""`jax3dc edit` on a predict folder: the edit reaches every export and the verdict, the history
keeps it, and an edit that fails (a bad patch, a write that fails, a swap that fails, another
edit at the same time) leaves the folder byte for byte as it was."""

from __future__ import annotations

import json
import os

import pytest

from jax3dc.cli import main
from jax3dc.edits import folder as edit_module
from jax3dc.edits import staging
from jax3dc.edits.folder import EDITS_FILE, edit_folder
from jax3dc.errors import EditError, FolderBusyError, InputFileError
from jax3dc.render import mujoco  # mujoco imported after render chose the GL backend
from edit_cases import snapshot

TO_THE_OTHER_EDGE = {"part": 3, "ops": [{"op": "set_line", "value": "edge +x +y"}]}  # the left door's hinge
BACK = {"part": 3, "ops": [{"op": "set_line", "value": "edge -x +y"}]}  # where the prediction had it


def hinge(folder, export: str = "object.xml") -> tuple[list[float], list[float]]:
    """(world anchor, world axis) of the left door's joint in an exported model, as MuJoCo reads it."""
    model = mujoco.MjModel.from_xml_path(str(folder / export))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    k = next(j for j in range(model.njnt) if model.joint(j).name.endswith("3"))
    return data.xanchor[k].round(3).tolist(), data.xaxis[k].round(3).tolist()


def test_an_edit_moves_the_hinge_in_every_export_and_checks_again(folder, tmp_path, capsys):
    anchor, axis = hinge(folder)
    assert anchor[0] == pytest.approx(-0.391, abs=2e-3)
    predicted = {name: (folder / name).read_bytes() for name in ("structure.json", "physics.json")}
    viewer, report = (folder / "viewer.html").read_bytes(), (folder / "report.html").read_bytes()
    assert json.loads(predicted["physics.json"])["ok"] is True
    patch = tmp_path / "patch.json"
    patch.write_text(json.dumps(TO_THE_OTHER_EDGE))

    assert main(["edit", str(folder), str(patch)]) == 0
    assert "the physics check fails" in capsys.readouterr().out
    for export in ("object.xml", "object.urdf"):
        moved, same = hinge(folder, export)
        assert moved[0] == pytest.approx(-0.002, abs=2e-3) and moved[1:] == anchor[1:] and same == axis, export
    verdict = json.loads((folder / "physics.json").read_text())
    assert verdict["joints"]["3"]["ok"] is False  # it now opens into the other door before its limit
    assert (folder / "viewer.html").read_bytes() != viewer and (folder / "report.html").read_bytes() != report
    (line,) = (folder / EDITS_FILE).read_text().splitlines()
    assert json.loads(line) == {"patch": TO_THE_OTHER_EDGE, "before": json.loads(predicted["structure.json"]),
                                "physics_ok": False}
    assert main(["edit", str(folder)]) == 0
    assert "part 3: hinge on part 1, axis +z, line edge +x +y" in capsys.readouterr().out

    result = edit_folder(folder, json.dumps(BACK))  # and back: the predicted structure and verdict again
    assert result.verdict.ok is True and hinge(folder) == (anchor, axis)
    assert {name: (folder / name).read_bytes() for name in predicted} == predicted
    assert len((folder / EDITS_FILE).read_text().splitlines()) == 2
    assert not list(folder.glob(staging.STAGE_PREFIX + "*"))


@pytest.mark.parametrize("patch, where", [
    ('{"part": 9, "ops": [{"op": "set_type", "value": "fixed"}]}', "part:"),
    ('{"part": 3, "ops": [{"op": "set_axis", "value": [Infinity, 0, 0]}]}', "ops[0].value:"),
])
def test_a_bad_patch_is_one_error_line_and_writes_nothing(folder, tmp_path, capsys, patch, where):
    before = snapshot(folder)
    (tmp_path / "patch.json").write_text(patch)
    assert main(["edit", str(folder), str(tmp_path / "patch.json")]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"jax3dc edit: error: {where}") and "\n" not in err
    assert snapshot(folder) == before


def test_a_failure_while_writing_leaves_the_folder_byte_identical(folder, monkeypatch):
    before = snapshot(folder)

    def fail(*args, **kwargs):  # after structure.json, the exports and physics.json are staged
        raise InputFileError("viewer.html", "disk full")

    monkeypatch.setattr(edit_module, "write_pages", fail)
    with pytest.raises(InputFileError):
        edit_folder(folder, TO_THE_OTHER_EDGE)
    assert snapshot(folder) == before


def test_a_failure_while_swapping_puts_back_what_it_moved(folder, monkeypatch):
    before = snapshot(folder)
    rename, failed = os.rename, []

    def flaky(src, dst):  # the new physics.json fails to move in, once (after the old one moved out)
        if os.path.basename(dst) == "physics.json" and not failed and staging.STAGE_PREFIX not in str(dst):
            failed.append(src)
            raise OSError(28, "No space left on device")
        rename(src, dst)

    monkeypatch.setattr(staging.os, "rename", flaky)
    with pytest.raises(OSError):
        edit_folder(folder, TO_THE_OTHER_EDGE)
    assert failed and snapshot(folder) == before


def test_a_second_edit_at_the_same_time_is_refused(folder):
    before = snapshot(folder)
    with staging.folder_lock(folder), pytest.raises(FolderBusyError):
        edit_folder(folder, TO_THE_OTHER_EDGE)
    assert snapshot(folder) == before
    with pytest.raises(EditError):  # the lock is free again: the next edit gets as far as its patch
        edit_folder(folder, {"part": 3, "ops": []})
