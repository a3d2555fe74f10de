"""The one-page report of a prediction: report.html and report.png.

Both show the input image I, the segmentation S, the predicted joints drawn over I when the
image's camera was given (else over S, which is rendered from the camera used, so it always lines
up), the part tree with each part's colour, name, material and joint, and the
physics verdict. When stage 2 failed (no valid structure) they show the parts and the error, so
the page is still useful for finding out why.
"""

from __future__ import annotations

import base64
import html
import io
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from jax3dc.overlay import draw_overlay
from jax3dc.palette import hex_colour, part_colour
from jax3dc.physics.findings import FAILURE, WARNING, Verdict
from jax3dc.structure import Box, Joint, Structure

PANEL = 512  # px, side of each image panel of report.png
TEXT_WIDTH = 620
LINE = 16


@dataclass(frozen=True)
class ReportInputs:
    """Everything the report shows (structure / verdict None when that step did not succeed)."""

    image: Image.Image
    seg: np.ndarray  # S, RGB uint8
    palette: np.ndarray
    names: Mapping[int, str]
    boxes: Mapping[int, Box]
    camera: Mapping[str, Any]  # the camera S was rendered from
    camera_given: bool  # the image's own camera (joints line up with I), not the default view
    structure: Structure | None
    verdict: Verdict | None
    error: str | None  # why there is no structure / verdict


def _fmt(values) -> str:
    return "[" + ", ".join(f"{float(v):.3f}" for v in values) + "]"


def joint_text(joint: Joint) -> str:
    unit = "rad" if joint.type == "hinge" else "nu"
    return f"{joint.type} axis {_fmt(joint.axis)} pivot {_fmt(joint.pivot)} range {_fmt(joint.range)} {unit}"


def part_label(r: ReportInputs, pid: int) -> str:
    name = r.names.get(pid)
    return f"{pid} {name}" if name else str(pid)


def tree_lines(r: ReportInputs) -> list[tuple[int, int, str]]:
    """(depth, part id, text) in depth-first order of the part tree (flat list without a structure)."""
    if r.structure is None:
        return [(0, pid, part_label(r, pid)) for pid in sorted(r.boxes)]
    s = r.structure
    checked = set(r.verdict.joint_parts) if r.verdict is not None else set()
    out: list[tuple[int, int, str]] = []

    def visit(pid: int, depth: int) -> None:
        node = s.nodes[pid]
        material = s.materials.get(node.material)
        text = part_label(r, pid) + (f" ({material.family})" if material else "")
        if node.joint is not None:
            text += " | " + joint_text(node.joint)
            if pid in checked:
                reasons, warnings = r.verdict.joint_reasons(pid, FAILURE), r.verdict.joint_reasons(pid, WARNING)
                text += " | physics: " + ("; ".join(reasons) if reasons else "ok")
                if warnings:
                    text += " (warning: " + "; ".join(warnings) + ")"
        elif node.parent is not None:
            text += " | rigid"
        out.append((depth, pid, text))
        for child in s.children(pid):
            visit(child, depth + 1)

    for root in s.roots():
        visit(root, 0)
    return out


def relations_line(r: ReportInputs) -> str | None:
    """``relations: symmetric 3-5 (yz), instance 6-7`` (None without a structure or relations)."""
    if r.structure is None or not r.structure.relations:
        return None
    items = [f"{rel.type} {rel.a}-{rel.b}" + (f" ({rel.plane})" if rel.plane else "") for rel in r.structure.relations]
    return "relations: " + ", ".join(items)


def verdict_line(r: ReportInputs) -> str:
    if r.verdict is None:
        return "physics: not checked" + (f" ({r.error})" if r.error else "")
    problems = [f"{k}: {', '.join(v)}" for k, v in sorted(r.verdict.object_reasons().items()) if v]
    verdict = "PASS" if r.verdict.ok else "FAIL"
    return f"physics: {verdict}" + ("" if not problems else " | " + "; ".join(problems))


def panels(r: ReportInputs) -> list[tuple[str, Image.Image]]:
    """(caption, image) of I and S, the joints drawn on I when its camera is known, else on S."""
    image, seg = r.image.convert("RGB"), Image.fromarray(r.seg)
    if r.structure is None or not r.structure.joints():
        return [("image I", image), ("segmentation S", seg)]
    if r.camera_given:
        return [("image I with the predicted joints", joint_overlay(r, image)), ("segmentation S", seg)]
    return [("image I", image), ("segmentation S with the predicted joints (default camera)", joint_overlay(r, seg))]


def joint_overlay(r: ReportInputs, base: Image.Image) -> Image.Image:
    """``base`` with the predicted joints drawn (the 'reference' passed to draw_overlay has no joints)."""
    buf = io.BytesIO()
    base.save(buf, format="PNG")
    bare = replace(r.structure, nodes={pid: replace(n, joint=None) for pid, n in r.structure.nodes.items()})
    return draw_overlay(buf.getvalue(), r.camera, r.boxes, bare, r.structure)


def _png_data_uri(image: Image.Image) -> str:
    buf = io.BytesIO()
    image.save(buf, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def write_html(r: ReportInputs, path: Path) -> Path:
    rows = []
    for depth, pid, text in tree_lines(r):
        colour = hex_colour(part_colour(r.palette, pid))
        rows.append(f'<li style="margin-left:{depth * 1.5}em"><span class="sw" style="background:{colour}"></span>'
                    f"{html.escape(text)}</li>")
    error = f'<p class="err">{html.escape(r.error)}</p>' if r.error else ""
    relations = f"<p>{html.escape(relations_line(r))}</p>" if relations_line(r) else ""
    images = "".join(f'<figure><img alt="{html.escape(caption)}" src="{_png_data_uri(image)}">'
                     f"<figcaption>{html.escape(caption)}</figcaption></figure>" for caption, image in panels(r))
    page = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>jax3dc prediction</title>
<style>body{{font-family:sans-serif;margin:1.5em}} img{{width:{PANEL // 1.4:.0f}px;image-rendering:pixelated;border:1px solid #ccc}}
.sw{{display:inline-block;width:0.9em;height:0.9em;margin-right:0.4em;border:1px solid #444;vertical-align:middle}}
figure{{display:inline-block;margin:0 1em 0 0}} ul{{list-style:none;padding-left:0}} .err{{color:#b00}}</style></head>
<body><h1>jax3dc prediction</h1>
<div>{images}</div>
{error}<h2>Parts and joints</h2><ul>{''.join(rows)}</ul>{relations}
<h2>Physics</h2><p>{html.escape(verdict_line(r))}</p>
</body></html>
"""
    path.write_text(page, encoding="utf-8")
    return path


def _wrap(text: str, width: int) -> list[str]:
    return [text[i:i + width] for i in range(0, max(len(text), 1), width)]


def write_png(r: ReportInputs, path: Path) -> Path:
    """Image panel, S panel, and a text panel with the tree, joints and verdict."""
    shown = [(caption, p.convert("RGB").resize((PANEL, max(1, round(PANEL * p.height / p.width))),
                                               Image.Resampling.NEAREST)) for caption, p in panels(r)]
    font = ImageFont.load_default(size=13)
    lines: list[tuple[int, int | None, str]] = [(0, None, "jax3dc prediction")]
    if r.error:
        lines += [(0, None, t) for t in _wrap("error: " + r.error, 90)]
    for depth, pid, text in tree_lines(r):
        for k, piece in enumerate(_wrap(text, 90 - 3 * depth)):
            lines.append((depth, pid if k == 0 else None, piece))
    for text in (relations_line(r), verdict_line(r)):
        lines += [(0, None, t) for t in _wrap(text, 90)] if text else []
    height = max(max(p.height for _, p in shown) + 2 * LINE, (len(lines) + 1) * LINE)
    canvas = Image.new("RGB", (PANEL * len(shown) + TEXT_WIDTH, height), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    for i, (caption, p) in enumerate(shown):
        canvas.paste(p, (PANEL * i, 0))
        draw.text((PANEL * i + 8, p.height + 4), caption, fill=(0, 0, 0), font=font)
    x0 = PANEL * len(shown) + 8
    for row, (depth, pid, text) in enumerate(lines):
        y, x = 4 + row * LINE, x0 + depth * 18
        if pid is not None:
            draw.rectangle((x, y + 2, x + 10, y + 12), fill=part_colour(r.palette, pid), outline=(0, 0, 0))
        draw.text((x + (14 if pid is not None else 0), y), text, fill=(0, 0, 0), font=font)
    canvas.save(path)
    return path


def write_report(r: ReportInputs, out: Path) -> dict[str, Path]:
    return {"report_html": write_html(r, out / "report.html"), "report_png": write_png(r, out / "report.png")}
