"""Plain-text Tables 1 and 2 in the paper's layout, one row per system."""

from __future__ import annotations

from typing import Any, Mapping, Sequence

Column = tuple[str, str, int]  # header, metrics key, decimals

TABLE1_STRUCTURE_JOINT: tuple[Column, ...] = (
    ("Parse", "parse", 1), ("Parent", "parent_acc", 1), ("Edge F1", "edge_f1", 1),
    ("Pres. F1", "presence_f1", 1), ("Type", "type_acc", 1), ("Axis", "axis_acc", 1),
    ("Pos.", "pos_err", 3), ("Range IoU", "range_iou", 1),
)
TABLE1_FAILURES_RELATIONS: tuple[Column, ...] = (
    ("Type", "fail_type", 1), ("Axis", "fail_axis", 1), ("Origin", "fail_origin", 1),
    ("Limit", "fail_limit", 1), ("Success", "success", 1), ("Sym F1", "sym_f1", 1),
    ("Inst F1", "inst_f1", 1), ("Plane", "plane_acc", 1),
)
TABLE2: tuple[Column, ...] = (
    ("Parse", "scene_parse", 1), ("Obj./scene", "objects_per_scene", 2), ("Count", "count_match", 1),
    ("Full part.", "full_partition", 1), ("Cluster acc", "cluster_acc", 1), ("Rand", "rand_index", 1),
    ("Prec.", "pair_precision", 1), ("Rec.", "pair_recall", 1), ("F1", "pair_f1", 1),
)


def _cell(value: Any, decimals: int) -> str:
    return "-" if value is None else f"{value:.{decimals}f}"


def format_block(title: str, columns: Sequence[Column], systems: Sequence[tuple[str, Mapping[str, Any]]]) -> str:
    """One aligned block: a title line, a header and one line per (name, metrics) system."""
    name_width = max([len("system")] + [len(name) for name, _ in systems])
    widths = [max(len(h), 7) for h, _, _ in columns]
    lines = [title, "  ".join(["system".ljust(name_width)] + [h.rjust(w) for (h, _, _), w in zip(columns, widths)])]
    for name, metrics in systems:
        cells = [_cell(metrics.get(key), d).rjust(w) for (_, key, d), w in zip(columns, widths)]
        lines.append("  ".join([name.ljust(name_width)] + cells))
    return "\n".join(lines)


def format_tables(systems: Sequence[tuple[str, Mapping[str, Any]]]) -> str:
    """Table 1 (two blocks) and, when any system has scenes, Table 2; '-' = nothing to measure."""
    parts = [
        format_block("Table 1a  structure and joints (%; Pos. in nu)", TABLE1_STRUCTURE_JOINT, systems),
        format_block("Table 1b  failure attribution and relations (%)", TABLE1_FAILURES_RELATIONS, systems),
    ]
    if any((m.get("counts") or {}).get("scenes") for _, m in systems):
        ref_count = next((m["objects_per_scene_ref"] for _, m in systems if m.get("objects_per_scene_ref")), None)
        note = f"; reference {ref_count:.2f} objects/scene" if ref_count is not None else ""
        parts.append(format_block(f"Table 2  multi-object scenes (%; Obj./scene a count{note})", TABLE2, systems))
    return "\n\n".join(parts)
