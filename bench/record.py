"""Read, check and plot the benchmark record, docs/benchmarks.jsonl.

Each line is one measured figure; the latest line of a name is its current figure, so a script
can show where a figure stands and how it got there. The check exists because the file is
written by hand: a missing key or a number typed as text would otherwise surface only in a plot.

python3 bench/record.py                      check the file, print the current figure of each name
python3 bench/record.py --plot NAME OUT.png  plot the history of one figure
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import re
import sys
from pathlib import Path

RECORD = Path(__file__).resolve().parent.parent / "docs" / "benchmarks.jsonl"
REQUIRED = ("name", "date", "machine", "commit", "command", "value", "unit",
            "baseline", "ratio", "target", "met")
OPTIONAL = ("note",)
_DATE = re.compile(r"\d{4}-\d{2}-\d{2}")


class RecordError(ValueError):
    """A line of the record that a reader could not trust; the message names file and line."""


def _is_number(x: object) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _problem(entry: object) -> str | None:
    """What is wrong with one parsed line, or None; kept apart so every rule reads in one place."""
    if not isinstance(entry, dict):
        return "not a JSON object"
    missing = [k for k in REQUIRED if k not in entry]
    if missing:
        return f"missing key(s) {', '.join(missing)}"
    unknown = sorted(set(entry) - set(REQUIRED) - set(OPTIONAL))
    if unknown:
        return f"unknown key(s) {', '.join(unknown)}"
    for key in ("name", "machine", "command", "unit"):
        if not isinstance(entry[key], str) or not entry[key].strip():
            return f"{key} must be a non-empty string"
    if not isinstance(entry["date"], str) or not _DATE.fullmatch(entry["date"]):
        return f"date {entry['date']!r} is not YYYY-MM-DD"
    try:
        datetime.date.fromisoformat(entry["date"])
    except ValueError:
        return f"date {entry['date']!r} is not a calendar date"
    if entry["commit"] is not None and not isinstance(entry["commit"], str):
        return "commit must be a string or null"
    if not _is_number(entry["value"]):
        return f"value {entry['value']!r} must be a finite number"
    for key in ("baseline", "ratio"):
        if entry[key] is not None and not _is_number(entry[key]):
            return f"{key} {entry[key]!r} must be a finite number or null"
    if entry["target"] is not None and not (_is_number(entry["target"]) or isinstance(entry["target"], str)):
        return "target must be a number, a string or null"
    if entry["met"] is not None and not isinstance(entry["met"], bool):
        return "met must be true, false or null"
    if "note" in entry and not isinstance(entry["note"], str):
        return "note must be a string"
    return None


def load(path: Path = RECORD) -> list[dict]:
    """Every line of the record, checked; raises RecordError naming the first bad line.

    Dates must not go backwards, since "latest line of a name" is what makes a figure current."""
    entries: list[dict] = []
    previous = ""
    for n, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            entry = json.loads(line)
        except json.JSONDecodeError as e:
            raise RecordError(f"{path}:{n}: not valid JSON ({e.msg})") from None
        problem = _problem(entry)
        if problem is None and entry["date"] < previous:
            problem = f"date {entry['date']} is earlier than the line before ({previous}); keep lines in date order"
        if problem:
            raise RecordError(f"{path}:{n}: {problem}")
        previous = entry["date"]
        entries.append(entry)
    return entries


def latest(entries: list[dict]) -> dict[str, dict]:
    """Name -> its last line, in the order names first appear."""
    current: dict[str, dict] = {}
    for entry in entries:
        current[entry["name"]] = entry
    return current


def _fmt(x: object) -> str:
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "met" if x else "missed"
    return f"{x:g}" if _is_number(x) else str(x)


def table(entries: list[dict], unit_width: int = 44) -> str:
    """The current figure of each name as an aligned text table."""
    rows = [("name", "date", "value", "unit", "baseline", "ratio", "target")]
    for name, e in latest(entries).items():
        unit = e["unit"] if len(e["unit"]) <= unit_width else e["unit"][:unit_width - 1] + "…"
        target = "—" if e["target"] is None else f"{_fmt(e['target'])} ({_fmt(e['met'])})"
        rows.append((name, e["date"], _fmt(e["value"]), unit, _fmt(e["baseline"]), _fmt(e["ratio"]), target))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


def plot(entries: list[dict], name: str, out: Path) -> None:
    """Draw one figure's lines (and their baselines) against their dates into a PNG."""
    import matplotlib  # lazy: matplotlib (0.31 s with pyplot) for the plots only; the tests read the record without it

    matplotlib.use("Agg")
    # lazy: after the Agg backend is chosen
    import matplotlib.dates as mdates
    import matplotlib.pyplot as plt

    history = [e for e in entries if e["name"] == name]
    if not history:
        raise RecordError(f"no line named {name!r} in the record")
    dates = [datetime.date.fromisoformat(e["date"]) for e in history]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(dates, [e["value"] for e in history], "o-", label="ours")
    with_base = [(d, e["baseline"]) for d, e in zip(dates, history) if e["baseline"] is not None]
    if with_base:
        ax.plot(*zip(*with_base), "x--", label="baseline")
    if _is_number(history[-1]["target"]):
        ax.axhline(history[-1]["target"], color="grey", linestyle=":", label="target")
    ax.set_title(name)
    ax.set_ylabel(history[-1]["unit"][:60])
    ax.legend()
    ax.xaxis.set_major_locator(mdates.DayLocator())
    ax.xaxis.set_major_formatter(mdates.DateFormatter("%Y-%m-%d"))
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--record", type=Path, default=RECORD, help="the JSONL file (default: docs/benchmarks.jsonl)")
    ap.add_argument("--plot", nargs=2, metavar=("NAME", "OUT.png"), help="plot the history of one figure")
    args = ap.parse_args(argv)
    try:
        entries = load(args.record)
        if args.plot:
            plot(entries, args.plot[0], Path(args.plot[1]))
            print(f"wrote {args.plot[1]}")
        else:
            print(table(entries))
    except RecordError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
