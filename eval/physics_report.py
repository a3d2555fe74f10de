"""The report folder of ``jax3dc physics sweep``: verdict lines, a summary, plots and an index.

Each object's plot is drawn where it was checked (``plot_penetration``, in the sweep's worker
processes); ``write_report`` then writes the lines, the summary and the index that links the plots,
from each object's typed verdict: the summary counts the joints' findings by check, the lines and
the index hold their reason strings.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

from jax3dc.errors import InputFileError
from jax3dc.physics.findings import FAILURE, WARNING, Verdict


def plot_penetration(object_id: str, curves: dict[int, Any], path: Path) -> None:
    """Deepest penetration (nu) against each joint's value, one line per jointed part."""
    import matplotlib  # lazy: matplotlib (0.37 s with pyplot) for the plots only
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: after the Agg backend is chosen

    fig, ax = plt.subplots(figsize=(5, 3))
    for part, (q, depth) in curves.items():
        ax.plot(q, depth, marker=".", label=f"joint of part {part}")
    ax.set_xlabel("joint value (rad or nu)")
    ax.set_ylabel("deepest penetration (nu)")
    ax.set_title(object_id)
    ax.legend(fontsize=7)
    fig.tight_layout()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=80)
    except OSError as e:
        raise InputFileError(path, f"cannot write the plot: {e.strerror or e}") from None
    finally:
        plt.close(fig)


def write_report(results: list[dict[str, Any]], skipped: list[dict[str, Any]], out: Path,
                 device: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write verdicts.jsonl, costs.jsonl (each result's "cost", where it has one), summary.json
    (with ``device``, what the MJX sweep's accelerator did) and index.md (linking each result's
    "plot", a path relative to ``out``, where it has one); return the summary. Each result's
    "verdict" is a ``Verdict``; the summary's "reasons" and "warnings" count the joints' failures
    and warnings by check (``jax3dc.physics.findings.CHECKS``)."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        verdicts: list[Verdict] = [r["verdict"] for r in results]
        joints = sum(len(v.joint_parts) for v in verdicts)
        found = [f for v in verdicts for p in v.joint_parts for f in v.joint_findings(p)]
        reasons = Counter(f.check for f in found if f.severity == FAILURE)
        warnings = Counter(f.check for f in found if f.severity == WARNING)
        summary = {
            "objects": len(results), "objects_ok": sum(v.ok for v in verdicts),
            "joints": joints, "joints_ok": joints - sum(v.flagged for v in verdicts),
            "reasons": dict(reasons.most_common()), "warnings": dict(warnings.most_common()), "skipped": len(skipped),
        }
        if device is not None:
            summary["device"] = device
        with (out / "verdicts.jsonl").open("w", encoding="utf-8") as f:
            for r in results:
                f.write(json.dumps({"object": r["object"], "category": r["category"], **r["verdict"].to_json()}) + "\n")
            for s in skipped:
                f.write(json.dumps({"object": s["object"], "skipped": s["why"]}) + "\n")
        with (out / "costs.jsonl").open("w", encoding="utf-8") as f:
            for r in results:
                if "cost" in r:
                    f.write(json.dumps({"object": r["object"], "category": r["category"], **r["cost"]}) + "\n")
        (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
        lines = ["# Physics sweep", "", f"{summary['objects_ok']} / {summary['objects']} objects pass, "
                 f"{summary['joints_ok']} / {summary['joints']} joints pass, {len(skipped)} skipped.", "",
                 "| object | joint | ok | reasons | warnings |", "|---|---|---|---|---|"]
        for r in results:
            verdict = r["verdict"]
            for part in verdict.joint_parts:
                reasons = "; ".join(verdict.joint_reasons(part, FAILURE))
                warned = "; ".join(verdict.joint_reasons(part, WARNING))
                lines.append(f"| {r['object']} | {part} | {'no' if reasons else 'yes'} | {reasons} | {warned} |")
            if r.get("plot"):
                lines.append(f"\n![{r['object']}]({r['plot']})\n")
        (out / "index.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    except OSError as e:
        raise InputFileError(out, f"cannot write the report: {e.strerror or e}") from None
    return summary
