"""The report folder of ``jax3dc physics sweep``: verdict lines, a summary, plots and an index.

Each object's plot is drawn where it was checked (``plot_penetration``, in the sweep's worker
processes); ``write_report`` then writes the lines, the summary and the index that links the plots.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

from jax3dc.errors import InputFileError


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


def _kind(reason: str) -> str:
    """A reason or warning without its values ("penetrates part 3 at q=0.4" -> "penetrates part 3")."""
    return reason.split(" at q=")[0].split(" (")[0]


def write_report(results: list[dict[str, Any]], skipped: list[dict[str, Any]], out: Path,
                 device: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write verdicts.jsonl, costs.jsonl (each result's "cost", where it has one), summary.json
    (with ``device``, what the MJX sweep's accelerator did) and index.md (linking each result's
    "plot", a path relative to ``out``, where it has one); return the summary."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        joints = [j for r in results for j in r["verdict"]["joints"].values()]
        reasons = Counter(_kind(reason) for j in joints for reason in j["reasons"])
        warnings = Counter(_kind(warning) for j in joints for warning in j.get("warnings", []))
        summary = {
            "objects": len(results), "objects_ok": sum(r["verdict"]["ok"] for r in results),
            "joints": len(joints), "joints_ok": sum(j["ok"] for j in joints),
            "reasons": dict(reasons.most_common()), "warnings": dict(warnings.most_common()), "skipped": len(skipped),
        }
        if device is not None:
            summary["device"] = device
        with (out / "verdicts.jsonl").open("w", encoding="utf-8") as f:
            for r in results:
                f.write(json.dumps({"object": r["object"], "category": r["category"], **r["verdict"]}) + "\n")
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
            for part, j in r["verdict"]["joints"].items():
                lines.append(f"| {r['object']} | {part} | {'yes' if j['ok'] else 'no'} | {'; '.join(j['reasons'])} | "
                             f"{'; '.join(j.get('warnings', []))} |")
            if r.get("plot"):
                lines.append(f"\n![{r['object']}]({r['plot']})\n")
        (out / "index.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    except OSError as e:
        raise InputFileError(out, f"cannot write the report: {e.strerror or e}") from None
    return summary
