"""`jax3dc serve`'s JSON API through Starlette's TestClient: an upload is predicted in turn and
served; every bad input gets one clear error, the server keeps serving, nothing is written outside
--out and no earlier result changes; an edit is `jax3dc edit`'s, its errors are 400 and a second
edit of a busy folder is 409."""

from __future__ import annotations

import io
import json
import shutil
import struct
import zipfile
import zlib
from pathlib import Path

import pytest
from starlette.testclient import TestClient

from tests.serve.serve_cases import ORIGIN, served_app
from jax3dc.cli import main
from jax3dc.edits.staging import folder_lock
from jax3dc.errors import Jax3dcError
from jax3dc.serve.cli import is_loopback, listen, warn_if_exposed
from jax3dc.serve.app import create_app
from jax3dc.serve.jobs import JobBoard
from jax3dc.viewer import cli as viewer_cli
from tests.edits.edit_cases import snapshot

HOSTILE_NAME = "../../<img src=x onerror=alert(1)>.png"
TO_THE_OTHER_EDGE = {"part": 3, "ops": [{"op": "set_line", "value": "edge +x +y"}]}  # the left door's hinge


def png_header(width: int, height: int) -> bytes:
    """A PNG whose header says ``width`` x ``height`` and whose pixels are a few bytes: a decoder
    that trusted the header would allocate width * height * 3 bytes."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b"")


def upload(served, data: bytes, name: str = "photo.png", **headers):
    return served.client.post("/api/jobs", files={"image": (name, data, "image/png")}, headers=headers)


def outside(served) -> list[str]:
    """Entries of the test's root folder besides --out (the server writes nothing there)."""
    return sorted(p.name for p in served.root.iterdir() if p.name != "out")


def test_an_upload_is_predicted_in_turn_and_its_files_are_served(served, inputs):
    _config, image, _out = inputs
    assert [j["id"] for j in served.client.get("/api/jobs").json()["jobs"]] == ["cabinet"]  # predicted before
    first = upload(served, image.read_bytes(), HOSTILE_NAME)
    second = upload(served, image.read_bytes(), "cabinet.png")
    assert first.status_code == second.status_code == 202, first.text
    job, later = first.json(), second.json()
    assert job["name"] == HOSTILE_NAME and job["id"] == "img_src_x_onerror_alert_1" and later["id"] == "cabinet-2"
    assert later["number"] == job["number"] + 1
    done, done_later = served.wait(job["id"]), served.wait(later["id"])
    assert done["state"] == done_later["state"] == "done" and done["verdict"]["ok"] is True
    assert done_later["position"] == 0 and served.board.get(job["id"]).finished <= served.board.get(later["id"]).started
    for name in ("object.urdf", "object.xml", "object.usda", "object.glb", "object_blender.py", "structure.json",
                 "physics.json", "viewer.html", "done.json"):
        assert name in done["files"]
    assert served.client.get(f"/api/jobs/{job['id']}/files/viewer_files/viewer.js").status_code == 200
    xml = served.client.get(f"/api/jobs/{job['id']}/files/object.xml")
    assert xml.status_code == 200 and xml.content == (served.out / job["id"] / "object.xml").read_bytes()
    names = zipfile.ZipFile(io.BytesIO(served.client.get(done["zip"]).content)).namelist()
    assert {f"{job['id']}/object.xml", f"{job['id']}/meshes/1.obj", f"{job['id']}/physics.json"} <= set(names)
    assert outside(served) == [] and (served.out / job["id"]).is_dir()
    gallery = (served.out / "index.html").read_text()
    assert "&lt;img src=x onerror=alert(1)&gt;" in gallery and "<img src=x" not in gallery
    assert not any((served.out / ".uploads").iterdir())  # each upload is removed once its job ran
    assert served.client.get("/").text.count("onerror") == 0  # the page is static: names come as JSON text


@pytest.mark.parametrize("path", ["../cabinet/object.xml", "..%2F..%2Fobject.glb", ".edit-x/a", "meshes/../../x",
                                  "nothing.txt", "meshes"])
def test_a_file_outside_the_folder_or_hidden_is_not_served(served, path):
    reply = served.client.get(f"/api/jobs/cabinet/files/{path}")
    assert reply.status_code == 404 and "error" in reply.json()


def test_bad_uploads_get_one_error_each_and_the_server_keeps_serving(inputs, tmp_path):
    served = served_app(inputs, tmp_path, max_upload_bytes=200_000)
    good = inputs[1].read_bytes()
    before = snapshot(served.out)
    with served.client:
        cases = {
            "not an image": (upload(served, b"%PDF-1.4 not an image at all"), 400, "not an image file"),
            "truncated": (upload(served, good[: len(good) // 2]), 400, "truncated"),
            "30,000 px": (upload(served, png_header(30_000, 30_000)), 400, "30000 x 30000 pixels; the cap is"),
            "30,000 px long": (upload(served, png_header(30_000, 40)), 400, "at most 200 times the other"),
            "tiny": (upload(served, png_header(20, 20)), 400, "at least 32 px"),
            "over the cap": (upload(served, good + b"\0" * 300_000), 413, "over the upload cap of 0.2 MB"),
            "no file": (served.client.post("/api/jobs", data={"x": "1"},
                                           files={"other": ("a.png", good, "image/png")}), 400, "no file in the field"),
            "not a form": (served.client.post("/api/jobs", content=good, headers={"content-type": "image/png"}),
                           415, "multipart/form-data"),
        }
        body = (b"--b\r\nContent-Disposition: form-data; name=\"image\"; filename=\"a.png\"\r\n"
                b"Content-Type: image/png\r\n\r\n" + good[:500])  # the form never ends: the connection dropped
        cases["cut short"] = (served.client.post("/api/jobs", content=body,
                                                 headers={"content-type": "multipart/form-data; boundary=b"}),
                              400, "cut short")
        for case, (reply, status, words) in cases.items():
            assert reply.status_code == status, (case, reply.text)
            assert list(reply.json()) == ["error"] and words in reply.json()["error"], case
        assert "photo.png: " in cases["not an image"][0].json()["error"]  # the file's name, as given
        assert served.client.get("/api/jobs").json()["jobs"][0]["id"] == "cabinet"
        assert snapshot(served.out) == before | {".uploads": b"<dir>"} and outside(served) == []
        assert upload(served, good).status_code == 202  # and a good one still goes through
        assert served.wait("photo")["state"] == "done"
    served.board.stop()


def test_an_edit_is_jax3dc_edit_and_its_errors_are_400(served):
    folder = served.out / "cabinet"
    xml = (folder / "object.xml").read_bytes()
    for patch, words in [({"part": 99, "ops": [{"op": "set_line", "value": "centre"}]}, "part 99 is not a part"),
                         ({"part": 3, "ops": [{"op": "set_axis", "value": [1e999, 0, 0]}]}, "is not finite"),
                         ({"part": 3, "ops": [{"op": "set_line", "value": "edge +q"}]}, "unknown line"),
                         ("{not json", "patch")]:
        before = snapshot(folder)
        body = patch if isinstance(patch, str) else json.dumps(patch)
        reply = served.client.post("/api/jobs/cabinet/edit", content=body)
        assert reply.status_code == 400 and words in reply.json()["error"], reply.text
        assert snapshot(folder) == before
    reply = served.client.post("/api/jobs/cabinet/edit", content=json.dumps(TO_THE_OTHER_EDGE))
    assert reply.status_code == 200, reply.text
    assert reply.json()["ok"] is False and reply.json()["job"]["verdict"]["joints"]["3"]["ok"] is False
    assert (folder / "object.xml").read_bytes() != xml
    rows = {r["part"]: r for r in served.client.get("/api/jobs/cabinet/joints").json()["joints"]}
    assert rows[3]["type"] == "hinge" and rows[3]["axis"] == "+z" and rows[3]["line"] == "edge +x +y"
    assert "edge -x +y" in rows[3]["lines"]["z"] and rows[1]["type"] == "root"


def test_a_second_edit_of_a_busy_folder_is_409_and_changes_nothing(served):
    folder = served.out / "cabinet"
    before = snapshot(folder)
    with folder_lock(folder):  # another edit (the command line, another tab) holds the folder
        reply = served.client.post("/api/jobs/cabinet/edit", content=json.dumps(TO_THE_OTHER_EDGE))
    assert reply.status_code == 409 and "another edit of this folder is running" in reply.json()["error"]
    assert snapshot(folder) == before


def test_unknown_and_unfinished_jobs(served):
    assert served.client.get("/api/jobs/nope").status_code == 404
    assert served.client.post("/api/jobs/nope/edit", content="{}").status_code == 404
    assert served.client.get("/api/jobs/nope/zip").status_code == 404


def test_a_request_from_another_origin_may_change_nothing(served, inputs):
    before = snapshot(served.out)
    patch = json.dumps(TO_THE_OTHER_EDGE)
    for headers in ({"origin": "http://evil.example"}, {"origin": "null"}, {"origin": "http://127.0.0.1:9999"},
                    {"sec-fetch-site": "cross-site"}):
        for reply in (served.client.post("/api/jobs/cabinet/edit", content=patch, headers=headers),
                      upload(served, inputs[1].read_bytes(), **headers)):
            assert reply.status_code == 403 and "may not change anything" in reply.json()["error"], headers
    rebound = served.client.get("/api/jobs", headers={"host": "attacker.example:8000"})
    assert rebound.status_code == 403 and "loopback names only" in rebound.json()["error"]
    assert snapshot(served.out) == before
    same = served.client.post("/api/jobs/cabinet/edit", content=patch, headers={"origin": ORIGIN})
    assert same.status_code == 200


def test_view_serve_edits_one_folder_and_takes_no_upload(inputs, tmp_path):
    copy = Path(shutil.copytree(inputs[2] / "cabinet", tmp_path / "my object"))
    client = TestClient(create_app(JobBoard.single(copy)), base_url=ORIGIN)
    (job,) = client.get("/api/jobs").json()["jobs"]
    assert job["id"] == "my_object" and job["state"] == "done" and client.get("/api/settings").json()["uploads"] is False
    refused = client.post("/api/jobs", files={"image": ("a.png", inputs[1].read_bytes(), "image/png")})
    assert refused.status_code == 405 and "jax3dc serve" in refused.json()["error"]
    reply = client.post("/api/jobs/my_object/edit", content=json.dumps(TO_THE_OTHER_EDGE))
    assert reply.status_code == 200 and json.loads((copy / "physics.json").read_text())["ok"] is False


def test_view_serve_of_a_predict_folder_serves_the_edit_page(inputs, tmp_path, monkeypatch):
    served = []
    monkeypatch.setattr(viewer_cli, "serve_folder", lambda *args: served.append(args))
    copy = Path(shutil.copytree(inputs[2] / "cabinet", tmp_path / "cabinet"))
    assert main(["view", str(copy), "--serve", "--port", "0", "--no-open"]) == 0
    assert served == [(copy, "127.0.0.1", 0, False)]


def test_the_command_listens_on_loopback_and_warns_otherwise(capsys):
    assert is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("::1")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.5")
    warn_if_exposed("127.0.0.1")
    assert capsys.readouterr().err == ""
    warn_if_exposed("0.0.0.0")
    assert "reachable from the network" in capsys.readouterr().err
    sock = listen("127.0.0.1", 0)
    try:
        with pytest.raises(Jax3dcError, match="cannot listen"):
            listen("127.0.0.1", sock.getsockname()[1])
    finally:
        sock.close()
