"""The one-page report of a prediction: report.html and report.png.

Both show the input image I (with the predicted joints drawn over it when the camera is known),
the segmentation S, the part tree with each part's colour, name, material and joint, and the
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

from eval.overlay import draw_overlay
from jax3dc.palette import hex_colour, part_colour
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
    camera: Mapping[str, Any] | None
    structure: Structure | None
    verdict: Mapping[str, Any] | None
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
    joints = (r.verdict or {}).get("joints", {})
    out: list[tuple[int, int, str]] = []

    def visit(pid: int, depth: int) -> None:
        node = s.nodes[pid]
        material = s.materials.get(node.material)
        text = part_label(r, pid) + (f" ({material.family})" if material else "")
        if node.joint is not None:
            text += " | " + joint_text(node.joint)
            check = joints.get(str(pid))
            if check is not None:
                text += " | physics: " + ("ok" if check["ok"] else "; ".join(check["reasons"]))
        elif node.parent is not None:
            text += " | rigid"
        out.append((depth, pid, text))
        for child in s.children(pid):
            visit(child, depth + 1)

    for root in s.roots():
        visit(root, 0)
    return out


def verdict_line(r: ReportInputs) -> str:
    if r.verdict is None:
        return "physics: not checked" + (f" ({r.error})" if r.error else "")
    problems = [f"{k}: {', '.join(map(str, v))}" for k, v in sorted(r.verdict.get("checks", {}).items()) if v]
    verdict = "PASS" if r.verdict.get("ok") else "FAIL"
    return f"physics: {verdict}" + ("" if not problems else " | " + "; ".join(problems))


def overlay_image(r: ReportInputs) -> Image.Image:
    """I with the predicted joints drawn (the 'reference' passed to draw_overlay has no joints)."""
    if r.structure is None or r.camera is None or not r.structure.joints():
        return r.image.convert("RGB")
    buf = io.BytesIO()
    r.image.convert("RGB").save(buf, format="PNG")
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
    page = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>jax3dc prediction</title>
<style>body{{font-family:sans-serif;margin:1.5em}} img{{width:{PANEL // 1.4:.0f}px;image-rendering:pixelated;border:1px solid #ccc}}
.sw{{display:inline-block;width:0.9em;height:0.9em;margin-right:0.4em;border:1px solid #444;vertical-align:middle}}
ul{{list-style:none;padding-left:0}} .err{{color:#b00}}</style></head>
<body><h1>jax3dc prediction</h1>
<p><img alt="image I with predicted joints" src="{_png_data_uri(overlay_image(r))}">
<img alt="segmentation S" src="{_png_data_uri(Image.fromarray(r.seg))}"></p>
{error}<h2>Parts and joints</h2><ul>{''.join(rows)}</ul>
<h2>Physics</h2><p>{html.escape(verdict_line(r))}</p>
</body></html>
"""
    path.write_text(page, encoding="utf-8")
    return path


def _wrap(text: str, width: int) -> list[str]:
    return [text[i:i + width] for i in range(0, max(len(text), 1), width)]


def write_png(r: ReportInputs, path: Path) -> Path:
    """Image panel, S panel, and a text panel with the tree, joints and verdict."""
    panels = [overlay_image(r), Image.fromarray(r.seg)]
    panels = [p.convert("RGB").resize((PANEL, max(1, round(PANEL * p.height / p.width))), Image.Resampling.NEAREST)
              for p in panels]
    font = ImageFont.load_default(size=13)
    lines: list[tuple[int, int | None, str]] = [(0, None, "jax3dc prediction")]
    if r.error:
        lines += [(0, None, t) for t in _wrap("error: " + r.error, 90)]
    for depth, pid, text in tree_lines(r):
        for k, piece in enumerate(_wrap(text, 90 - 3 * depth)):
            lines.append((depth, pid if k == 0 else None, piece))
    lines += [(0, None, t) for t in _wrap(verdict_line(r), 90)]
    height = max(max(p.height for p in panels), (len(lines) + 1) * LINE)
    canvas = Image.new("RGB", (PANEL * len(panels) + TEXT_WIDTH, height), (255, 255, 255))
    for i, p in enumerate(panels):
        canvas.paste(p, (PANEL * i, 0))
    draw = ImageDraw.Draw(canvas)
    x0 = PANEL * len(panels) + 8
    for row, (depth, pid, text) in enumerate(lines):
        y, x = 4 + row * LINE, x0 + depth * 18
        if pid is not None:
            draw.rectangle((x, y + 2, x + 10, y + 12), fill=part_colour(r.palette, pid), outline=(0, 0, 0))
        draw.text((x + (14 if pid is not None else 0), y), text, fill=(0, 0, 0), font=font)
    canvas.save(path)
    return path


def write_report(r: ReportInputs, out: Path) -> dict[str, Path]:
    return {"report_html": write_html(r, out / "report.html"), "report_png": write_png(r, out / "report.png")}
