"""The browsable side of ``jax3dc eval run``'s report: index.html with a thumbnail and the metrics
of every object, and for the first N parsed predictions an interactive viewer (jax3dc.viewer) of
the predicted structure on the record's own part meshes, with its physics verdict.

The part meshes are rebuilt as the verification stage does (``data_pipeline.record_parts``); an object
whose parts cannot be rebuilt (an imported record without ``--sources``) gets no viewer, and the
index says why.
"""

from __future__ import annotations

import html
import io
import re
from pathlib import Path
from typing import Any, Mapping, Sequence

from PIL import Image
from tqdm import tqdm

from data_pipeline.record_parts import record_parts
from eval.metrics.score import Case, Evaluation
from jax3dc.errors import Jax3dcError
from jax3dc.export.gltf import gltf_bytes
from jax3dc.physics.findings import Verdict
from jax3dc.physics.verdict import verdict_with_curves
from jax3dc.viewer import ViewerInputs, write_viewer

VIEWERS_DIR = "viewers"
THUMB_PX = 128
COLUMNS = (("Parent", "parent_acc", 1), ("Edge F1", "edge_f1", 1), ("Pres. F1", "presence_f1", 1))


def page_stem(key: str) -> str:
    """File stem of a record key (keys hold '/'): its viewer page's, and its overlay's (``overlay_name``)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", key)


def overlay_name(key: str) -> str:
    """File name of a record's joint overlay."""
    return page_stem(key) + ".png"


def write_thumbnail(image_png: bytes, path: Path) -> None:
    with Image.open(io.BytesIO(image_png)) as image:
        thumb = image.convert("RGB")
        thumb.thumbnail((THUMB_PX, THUMB_PX))
        thumb.save(path)


def write_object_viewer(case: Case, record: Any, sources: Mapping[str, Path], path: Path) -> Verdict:
    """The viewer of one parsed prediction; returns its physics verdict."""
    try:
        parts, scale, mounted = record_parts(record, sources)
    except KeyError as e:  # a record from before the build wrote what rebuilding needs
        raise Jax3dcError(f"record {case.key}: cannot rebuild its parts: no meta field {e}") from None
    verdict = verdict_with_curves(case.prediction, parts, scale, mounted=mounted)[0]
    glb = gltf_bytes(case.prediction, parts, scale)
    write_viewer(ViewerInputs(glb, case.key, case.key, verdict, record.image_png, record.seg_png), path)
    return verdict


def write_viewers(cases: Sequence[Case], records: Mapping[str, Any], folder: Path, limit: int,
                  sources: Mapping[str, Path]) -> dict[str, dict[str, Any]]:
    """Thumbnails of every object and viewers of the first ``limit`` parsed predictions in
    ``folder``; key -> {"thumb", "viewer" or "why", "physics"}."""
    (folder / "thumbs").mkdir(parents=True, exist_ok=True)
    done: dict[str, dict[str, Any]] = {}
    todo = [c for c in cases if c.prediction is not None][:limit]
    for case in cases:
        stem = page_stem(case.key)
        write_thumbnail(records[case.key].image_png, folder / "thumbs" / f"{stem}.png")
        done[case.key] = {"thumb": f"thumbs/{stem}.png",
                          "why": "parse failure" if case.prediction is None else f"beyond the first {limit}"}
    for case in tqdm(todo, desc="viewers", unit="obj", leave=False, disable=None):
        entry = done[case.key]
        try:
            verdict = write_object_viewer(case, records[case.key], sources, folder / f"{page_stem(case.key)}.html")
        except Jax3dcError as e:
            entry["why"] = str(e)
            continue
        entry.pop("why")
        entry["viewer"] = f"{page_stem(case.key)}.html"
        flagged = [str(part) for part in sorted(verdict.failed_joints)]
        entry["physics"] = "PASS" if verdict.ok else "FAIL" + (
            f" (joints of parts {', '.join(flagged)} flagged)" if flagged else "")
    return done


def _cell(row: Mapping[str, Any], key: str, decimals: int) -> str:
    value = row.get(key)
    return "-" if value is None else f"{value:.{decimals}f}"


def index_html(name: str, evaluation: Evaluation, objects: Mapping[str, Mapping[str, Any]]) -> str:
    """index.html: the split's headline and one row per object (thumbnail, metrics, viewer link)."""
    c = evaluation.metrics["counts"]
    head = "".join(f"<th>{h}</th>" for h in ("object", "image", "parsed") + tuple(h for h, _, _ in COLUMNS)
                   + ("joints matched / pred / ref", "physics", "viewer"))
    rows = []
    for row in evaluation.rows:
        key, entry = row["key"], objects.get(row["key"], {})
        thumb = f'<img src="{VIEWERS_DIR}/{html.escape(entry["thumb"])}" alt="">' if "thumb" in entry else ""
        parsed = "yes" if row["parsed"] else f"no ({html.escape(str(row.get('failure_rule')))})"
        joints = f"{row['joints_matched']} / {row['joints_pred']} / {row['joints_ref']}" if row["parsed"] else "-"
        link = (f'<a href="{VIEWERS_DIR}/{html.escape(entry["viewer"])}">open</a>' if "viewer" in entry
                else f'<span class="why">{html.escape(entry.get("why", "-"))}</span>')
        cells = [html.escape(key), thumb, parsed] + [_cell(row, k, d) for _, k, d in COLUMNS]
        cells += [joints, html.escape(entry.get("physics", "-")), link]
        rows.append("<tr>" + "".join(f"<td>{cell}</td>" for cell in cells) + "</tr>")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Evaluation report: {html.escape(name)}</title>
<style>body{{font-family:system-ui,sans-serif;margin:1.5em}} table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:middle}} .why{{color:#777}}</style></head>
<body><h1>Evaluation report: {html.escape(name)}</h1>
<p>{c['parsed']}/{c['objects']} predictions parsed; {c['joints_matched']} joints matched of {c['joints_ref']}
reference / {c['joints_pred']} predicted. Metrics in %; the viewer shows the prediction on the record's parts
with its physics verdict. <a href="index.md">index.md</a> links the tables and overlays.</p>
<table><tr>{head}</tr>
{chr(10).join(rows)}
</table></body></html>
"""
