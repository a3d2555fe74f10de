"""The report folder of ``jax3dc eval run``: metrics, markdown tables, a chart, overlays, an index.

Files: metrics.json and per_object.jsonl (as ``jax3dc eval metrics`` writes them), tables.md
(Table 1 and, with scenes, Table 2), per_category.md (the split metrics per meta.category),
failure_attribution.png (the five shares of SPEC §5), overlays/<key>.png and index.md linking all;
index.html with a thumbnail, the metrics and a 3D viewer link per object (``eval.viewers``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

from eval.cli import write_evaluation
from eval.metrics.score import Case, Evaluation, evaluate
from eval.metrics.tables import TABLE1_FAILURES_RELATIONS, TABLE1_STRUCTURE_JOINT, TABLE2, Column
from jax3dc.overlay import draw_overlay
from eval.viewers import VIEWERS_DIR, index_html, overlay_name, write_viewers
from jax3dc.errors import InputFileError

FAILURE_BARS: tuple[tuple[str, str], ...] = (
    ("type", "fail_type"), ("axis", "fail_axis"), ("origin", "fail_origin"), ("limit", "fail_limit"),
    ("success", "success"),
)
PER_CATEGORY: tuple[Column, ...] = (
    ("Parse", "parse", 1), ("Parent", "parent_acc", 1), ("Edge F1", "edge_f1", 1), ("Pres. F1", "presence_f1", 1),
    ("Type", "type_acc", 1), ("Axis", "axis_acc", 1), ("Pos.", "pos_err", 3), ("Range IoU", "range_iou", 1),
    ("Success", "success", 1),
)


def _cell(value: Any, decimals: int) -> str:
    return "-" if value is None else f"{value:.{decimals}f}"


def markdown_table(columns: Sequence[Column], rows: Sequence[tuple[str, Mapping[str, Any]]], first: str = "system") -> str:
    """A markdown table: one row per (name, metrics); '-' where there was nothing to measure."""
    lines = ["| " + " | ".join([first] + [h for h, _, _ in columns]) + " |",
             "|" + "---|" + "---:|" * len(columns)]
    for name, metrics in rows:
        lines.append("| " + " | ".join([name] + [_cell(metrics.get(k), d) for _, k, d in columns]) + " |")
    return "\n".join(lines)


def tables_markdown(name: str, metrics: Mapping[str, Any]) -> str:
    rows = [(name, metrics)]
    parts = ["## Table 1a: structure and joints (%; Pos. in nu)", markdown_table(TABLE1_STRUCTURE_JOINT, rows),
             "## Table 1b: failure attribution and relations (%)", markdown_table(TABLE1_FAILURES_RELATIONS, rows)]
    if metrics["counts"]["scenes"]:
        parts += ["## Table 2: multi-object scenes (%; Obj./scene a count)", markdown_table(TABLE2, rows)]
    return "\n\n".join(parts) + "\n"


def per_category_markdown(cases: Sequence[Case], categories: Mapping[str, str]) -> str:
    """Split metrics recomputed on each category's objects (Objects = references in it)."""
    groups: dict[str, list[Case]] = {}
    for case in cases:
        groups.setdefault(categories.get(case.key, "unknown"), []).append(case)
    rows = []
    for category in sorted(groups):
        metrics = evaluate(groups[category]).metrics
        rows.append((category, {"objects": len(groups[category]), **metrics}))
    columns = (("Objects", "objects", 0),) + PER_CATEGORY
    return "# Metrics per category (%; Pos. in nu)\n\n" + markdown_table(columns, rows, first="category") + "\n"


def failure_chart(metrics: Mapping[str, Any], path: Path) -> None:
    """Bar chart of the five failure-attribution shares (they sum to 100 when joints matched)."""
    import matplotlib  # lazy: matplotlib (0.21 s with pyplot) for the plots only

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: after the Agg backend is chosen

    values = [metrics.get(key) or 0.0 for _, key in FAILURE_BARS]
    fig, ax = plt.subplots(figsize=(5, 3.2), dpi=120)
    ax.bar([label for label, _ in FAILURE_BARS], values, color=["#c44", "#d84", "#cb3", "#88c", "#4a4"])
    for x, v in enumerate(values):
        ax.text(x, v + 1, f"{v:.1f}", ha="center", fontsize=8)
    matched = metrics["counts"]["joints_matched"]
    ax.set_ylim(0, 110)
    ax.set_ylabel("% of matched joints")
    ax.set_title(f"Failure attribution ({matched} matched joints)" if matched else "Failure attribution (no matched joints)")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def write_overlays(cases: Sequence[Case], records: Mapping[str, Any], refs: Mapping[str, Any], folder: Path,
                   limit: int) -> dict[str, str]:
    """Overlays for the first ``limit`` cases; key -> file name, or a reason when none was drawn."""
    folder.mkdir(parents=True, exist_ok=True)
    done: dict[str, str] = {}
    for case in cases[:limit]:
        camera = records[case.key].meta.get("camera")
        if not isinstance(camera, Mapping):
            done[case.key] = "no camera in meta"
            continue
        try:
            image = draw_overlay(records[case.key].image_png, camera, refs[case.key].boxes, case.reference,
                                 case.prediction)
        except InputFileError as e:
            done[case.key] = f"camera unusable: {e}"
            continue
        image.save(folder / overlay_name(case.key))
        done[case.key] = overlay_name(case.key)
    return done


def index_markdown(name: str, evaluation: Evaluation, overlays: Mapping[str, str], extra: Mapping[str, str],
                   notes: Sequence[str] = ()) -> str:
    m = evaluation.metrics
    c = m["counts"]
    lines = [f"# Evaluation report: {name}", "",
             f"{c['parsed']}/{c['objects']} predictions parsed; {c['joints_matched']} joints matched of "
             f"{c['joints_ref']} reference / {c['joints_pred']} predicted.", ""]
    lines += [line for note in notes for line in (note, "")]
    if m["parse_failures"]:
        lines += ["Parse failures by rule: " + ", ".join(f"`{k}` {v}" for k, v in m["parse_failures"].items()), ""]
    lines += ["- [tables.md](tables.md): Tables 1 and 2", "- [per_category.md](per_category.md): metrics per category",
              "- [failure_attribution.png](failure_attribution.png): failure attribution chart",
              "- [metrics.json](metrics.json), [per_object.jsonl](per_object.jsonl)"]
    lines += [f"- [{label}]({target})" for label, target in extra.items()]
    lines += ["", "![failure attribution](failure_attribution.png)", "",
              "## Overlays (reference joints green, predicted red)", ""]
    parsed = {row["key"]: row for row in evaluation.rows}
    for key, target in overlays.items():
        row = parsed[key]
        status = "parsed" if row["parsed"] else f"parse failure `{row['failure_rule']}`"
        if target.endswith(".png"):
            lines.append(f"- [{key}](overlays/{target}) ({status})")
        else:
            lines.append(f"- {key}: {target} ({status})")
    return "\n".join(lines) + "\n"


def write_report(out: Path, name: str, cases: Sequence[Case], records: Mapping[str, Any], refs: Mapping[str, Any],
                 overlay_limit: int, extra: Mapping[str, str] = {}, notes: Sequence[str] = (), viewer_limit: int = 0,
                 sources: Mapping[str, Path] = {}) -> Evaluation:
    """Scores ``cases`` and writes the whole report folder; returns the evaluation. index.html and
    viewers/ (``eval.viewers``) hold viewers of the first ``viewer_limit`` parsed predictions;
    ``sources``: the source folders of imported records, by object id, to rebuild their parts."""
    evaluation = evaluate(cases)
    write_evaluation(evaluation, out)
    categories = {key: str(r.meta.get("category", "unknown")) for key, r in records.items()}
    try:
        (out / "tables.md").write_text(tables_markdown(name, evaluation.metrics), encoding="utf-8")
        (out / "per_category.md").write_text(per_category_markdown(cases, categories), encoding="utf-8")
        failure_chart(evaluation.metrics, out / "failure_attribution.png")
        overlays = write_overlays(cases, records, refs, out / "overlays", overlay_limit)
        objects = write_viewers(cases, records, out / VIEWERS_DIR, viewer_limit, sources)
        (out / "index.html").write_text(index_html(name, evaluation, objects), encoding="utf-8")
        extra = {**extra, "index.html": "index.html: a thumbnail, the metrics and a 3D viewer per object"}
        (out / "index.md").write_text(index_markdown(name, evaluation, overlays, extra, notes), encoding="utf-8")
    except OSError as e:
        raise InputFileError(out, f"cannot write the report: {e.strerror or e}") from None
    return evaluation
