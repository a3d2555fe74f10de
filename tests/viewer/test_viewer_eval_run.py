"""``jax3dc eval run`` writes index.html: a thumbnail and the metrics of every object, and a link
to the 3D viewer of the first N, which loads in chromium with its physics verdict."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from jax3dc.cli import main
from test_viewer_sources import page_data


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("eval_run")
    data, out = folder / "data", folder / "report"
    assert main(["data", "build", "--objects", "3", "--views", "1", "--size", "64", "--out", str(data), "--quiet"]) == 0
    assert main(["eval", "run", "--data", str(data), "--split", "all", "--reference-as-prediction",
                 "--out", str(out), "--overlays", "0", "--viewers", "1"]) == 0
    return out


def test_index_has_every_object_and_links_the_first_viewer(report: Path) -> None:
    rows = [json.loads(line) for line in (report / "per_object.jsonl").read_text().splitlines()]
    page = (report / "index.html").read_text()
    assert "index.html" in (report / "index.md").read_text()
    links = re.findall(r'<a href="viewers/([^"]+\.html)">open</a>', page)
    assert len(links) == 1 and page.count("beyond the first 1") == len(rows) - 1
    for row in rows:
        assert row["key"] in page
    thumbs = re.findall(r'<img src="viewers/(thumbs/[^"]+\.png)"', page)
    assert len(thumbs) == len(rows) and all((report / "viewers" / t).is_file() for t in thumbs)
    data = page_data(report / "viewers" / links[0])
    # the reference as prediction on its own parts: a ground-truth object passes the physics check
    assert data["verdict"]["ok"] is True and "<td>PASS</td>" in page
    assert [i["caption"] for i in data["images"]] == ["image I", "segmentation S"]


def test_index_link_opens_a_working_viewer(report: Path, browser) -> None:
    page = browser.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto((report / "index.html").resolve().as_uri())
    page.click("text=open")
    page.wait_for_selector("body[data-ready=true]", timeout=60_000)
    assert errors == []
    assert page.locator("#verdict-badge").inner_text() == "physics: PASS"
    page.close()
