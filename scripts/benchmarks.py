"""Read, check, plot and publish the benchmark record, docs/benchmarks.jsonl.

Each line is one measured figure; the latest line of a name is its current figure, so a script
can show where a figure stands and how it got there. The check exists because the file is
written by hand: a missing key or a number typed as text would otherwise surface only in a plot.
docs/BENCHMARKS.md is written from the record, never by hand, so the page cannot drift from it:
it shows the current figure of every name whose latest line names a ``topic``, grouped by topic.

python3 scripts/benchmarks.py                      check the file, print the current figure of each name
python3 scripts/benchmarks.py --plot NAME OUT.png  plot the history of one figure
python3 scripts/benchmarks.py --page               write docs/BENCHMARKS.md from the record
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"
RECORD = DOCS / "benchmarks.jsonl"
PAGE = DOCS / "BENCHMARKS.md"
REQUIRED = ("name", "date", "machine", "commit", "command", "value", "unit",
            "baseline", "ratio", "target", "met")
OPTIONAL = ("note", "topic")
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
    if "topic" in entry and (not isinstance(entry["topic"], str) or not entry["topic"].strip()):
        return "topic must be a non-empty string"
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


def _number(x: float) -> str:
    """A figure as the record writes it, thousands separated: 95.0 stays "95.0" beside 33.9, and
    an integral count of thousands drops its ".0" ("5,064")."""
    if isinstance(x, int) or (float(x).is_integer() and abs(x) >= 1000):
        return f"{int(x):,}"
    return f"{x:,}" if abs(x) >= 1000 else repr(float(x))


def _fmt(x: object) -> str:
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "met" if x else "missed"
    return _number(x) if _is_number(x) else str(x)


def table(entries: list[dict], unit_width: int = 44) -> str:
    """The current figure of each name as an aligned text table."""
    rows = [("name", "date", "value", "unit", "baseline", "ratio", "target")]
    for name, e in latest(entries).items():
        unit = e["unit"] if len(e["unit"]) <= unit_width else e["unit"][:unit_width - 1] + "…"
        target = "—" if e["target"] is None else f"{_fmt(e['target'])} ({_fmt(e['met'])})"
        rows.append((name, e["date"], _fmt(e["value"]), unit, _fmt(e["baseline"]), _fmt(e["ratio"]), target))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


# The page's sections in order. A topic not named here follows these, in the order the record first
# names it, so a new topic needs no code; naming it here only places it.
TOPICS = (
    "Release models: real objects",
    "Release models: procedural objects",
    "Scenes and joint grounding",
    "Stage 1 from the image",
    "Verified decoding",
    "Physics checks",
    "Exports and part programs",
    "Appearance shift",
    "How the shipped model was chosen",
    "Speed of predict, demo and decoding",
    "Training speed",
    "Data, tokenizer, metrics and a learning check",
    "Test suite and hostile inputs",
)
PAGE_COMMAND = "python3 scripts/benchmarks.py --page"
MAX_PAGE_LINES = 300
_COLUMNS = ("figure", "value", "unit", "baseline", "ratio", "target", "date", "machine", "commit", "cmd")
# A command this short stands in its row's cell; a longer one is numbered and listed at the end.
_INLINE_COMMAND = 50
# The last page written by hand: its notes (why a target is missed, profiles) are kept only in part
# by the record's notes and docs/runs/.
_HAND_WRITTEN = "e09c126"


def short_machine(machine: str) -> str:
    """The page's name for a machine the record describes in words ("1 x NVIDIA H100 80GB HBM3 +
    16 CPU cores" -> "H100"); the lines were written by hand over weeks, so the same machine has
    several spellings. Text that matches no rule is shown as written."""
    text = machine.lower()
    shared = " (shared)" if "shared" in text else ""
    if re.search(r"developer|2-core|\(2 (?:shared )?cores", text):
        return "CPU-2" + (", one core" if "one core" in text else "") + shared
    gpu = re.search(r"(?:(\d+) ?x )?(?:nvidia )?(h100|h200)", text)
    if gpu is None:
        return machine
    count, kind = int(gpu.group(1) or 1), gpu.group(2).upper()
    name = f"{count}×{kind}" if count > 1 else kind
    return f"{name} CPUs{shared}" if re.search(r"cores of (?:the|a)\b", text) else name


def short_unit(unit: str, width: int = 44) -> str:
    """The head of a line's unit ("s cold compile (trace+lower 2.2, XLA 27.7); ..." -> "s cold
    compile"): many units describe the run as well, which the record keeps and a cell cannot hold.
    The head ends at the first "(" or ";", or, when still long, at the first comma."""
    head = re.split(r";\s|\s\(", unit, maxsplit=1)[0].strip()
    if len(head) > width:
        head = head.split(", ", 1)[0]
    if len(head) <= width:
        return head
    return head[:width].rsplit(" ", 1)[0] + "…"


def _cell(text: str) -> str:
    """A table cell's text; a bare "|" (in a command's "c|mjx") would split the cell."""
    return text.replace("|", "\\|")


def _target(entry: dict) -> str:
    """The target with its verdict, so a missed one stands out in the column."""
    if entry["target"] is None:
        return "—"
    verdict = {True: ": met", False: ": **missed**", None: ""}[entry["met"]]
    return f"{_fmt(entry['target'])}{verdict}"


def on_page(entries: list[dict]) -> dict[str, list[dict]]:
    """Topic -> the current lines that name it, topics in page order. Within a topic, the figures of
    one family (the name's first part, e.g. ``physics_rollouts``) stand together, families and
    figures in the order the record first names them, so a family's headline figure leads it."""
    shown: dict[str, list[dict]] = {topic: [] for topic in TOPICS}
    for entry in latest(entries).values():
        if "topic" in entry:
            shown.setdefault(entry["topic"], []).append(entry)
    for topic, lines in shown.items():
        families: dict[str, int] = {}
        for e in lines:
            families.setdefault(e["name"].split(".")[0], len(families))
        lines.sort(key=lambda e: families[e["name"].split(".")[0]])  # stable: record order within a family
    return {topic: lines for topic, lines in shown.items() if lines}


def left_page(entries: list[dict]) -> list[str]:
    """Names an earlier line put on the page whose latest line names no topic: a figure retired on
    purpose, or a new measurement appended without its topic, which would otherwise vanish unnoticed."""
    had_topic = {e["name"] for e in entries if "topic" in e}
    return [name for name, e in latest(entries).items() if name in had_topic and "topic" not in e]


def page(entries: list[dict]) -> str:
    """docs/BENCHMARKS.md for these lines: a table per topic, one row per current figure; a long
    command line is numbered in its row and written once under Commands, so every cell stays short."""
    numbered: dict[str, int] = {}
    out = [
        "# Benchmarks",
        "",
        f"Written from [`benchmarks.jsonl`](benchmarks.jsonl) by `{PAGE_COMMAND}`, never by hand",
        "(`tests/test_benchmark_record.py` checks both agree). A row is the current figure of a name, its latest",
        "line, filed under that line's `topic`; a figure leaves the page when its latest line names none (a",
        "release replaced). Earlier lines stay in the record, logs in [`runs/`](runs/), the notes of the",
        f"hand-written page in `git show {_HAND_WRITTEN}:docs/BENCHMARKS.md`, every column of the release tables in",
        "the model cards ([structure](../jax3dc/release/MODEL_CARD.md), [stage 1](../jax3dc/release/stage1/MODEL_CARD.md)).",
        "",
        "**baseline**: measured in the same run unless the line's note says otherwise (for a release, the one",
        "before it); **ratio**: ours / baseline; **unit**: the head of the line's unit (nu: object coordinates,",
        "largest extent 1); **machine**: H100 or H200 is one GPU with its host's 16 CPU cores, \"CPUs\" those cores",
        "alone, CPU-2 a 2-core developer machine (\"shared\": other jobs beside it); **cmd**: the command, or its",
        "number under [Commands](#commands).",
    ]
    for topic, lines in on_page(entries).items():
        out += ["", f"## {topic}", "| " + " | ".join(_COLUMNS) + " |", "|" + " --- |" * len(_COLUMNS)]
        for e in lines:
            command = e["command"]
            if len(command) <= _INLINE_COMMAND:
                cmd = f"`{command}`"
            else:
                cmd = str(numbered.setdefault(command, len(numbered) + 1))
            ratio = "—" if e["ratio"] is None else f"{e['ratio']:g}×"
            cells = (f"`{e['name']}`", _fmt(e["value"]), short_unit(e["unit"]), _fmt(e["baseline"]), ratio,
                     _target(e), e["date"], short_machine(e["machine"]), e["commit"] or "—", cmd)
            out.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    out += ["", "## Commands", ""]
    out += [f"{n}. `{command}`" for command, n in numbered.items()]
    return "\n".join(out) + "\n"


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
    ap.add_argument("--page", action="store_true", help="write docs/BENCHMARKS.md from the record")
    args = ap.parse_args(argv)
    try:
        entries = load(args.record)
        if args.plot:
            plot(entries, args.plot[0], Path(args.plot[1]))
            print(f"wrote {args.plot[1]}")
        elif args.page:
            text = page(entries)
            PAGE.write_text(text, encoding="utf-8")
            lines = len(text.splitlines())
            print(f"wrote {PAGE} ({lines} lines)")
            if lines > MAX_PAGE_LINES:
                print(f"error: over {MAX_PAGE_LINES} lines: retire figures the new ones replace "
                      "(drop `topic` from their latest lines)", file=sys.stderr)
                return 1
            for name in left_page(entries):
                print(f"note: {name} left the page (its latest line names no topic)", file=sys.stderr)
        else:
            print(table(entries))
    except RecordError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
