"""Compare two ``physics_ground_truth.py --verdicts`` files (C against MJX), object by object.

Prints, over the objects both files hold: joints whose ok flag agrees, joints whose reasons agree
(a reason's text up to " at ", the joint value being where a sweep first found it), the objects'
verdicts, each disagreement, and each backend's seconds per object (MJX's include its compiles).

python3 scripts/compare_verdicts.py c.jsonl mjx.jsonl
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path


def load(path: Path) -> dict[str, dict]:
    """Object name -> its verdict line; a line cut off by a killed run is skipped, named on stderr."""
    out = {}
    for n, line in enumerate(path.read_text().splitlines(), 1):
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            print(f"{path}:{n}: not a whole JSON line, skipped", file=sys.stderr)
            continue
        out[record["object"]] = record
    return out


def _kinds(reasons: list[str]) -> list[str]:
    return sorted(r.split(" at ")[0] for r in reasons)


def compare(a: dict[str, dict], b: dict[str, dict]) -> dict:
    """Counts of agreeing joints and objects over the objects in both, and the disagreements."""
    joints = same_ok = same_reasons = objects = same_object = 0
    differences = []
    for name in sorted(a.keys() & b.keys()):
        va, vb = a[name]["verdict"], b[name]["verdict"]
        objects += 1
        same_object += va["ok"] == vb["ok"]
        for part in sorted(va["joints"].keys() | vb["joints"].keys(), key=int):
            ja, jb = va["joints"].get(part), vb["joints"].get(part)
            joints += 1
            if ja is None or jb is None:
                differences.append(f"{name} joint {part}: only in one file")
                continue
            same_ok += ja["ok"] == jb["ok"]
            agree = _kinds(ja["reasons"]) == _kinds(jb["reasons"])
            same_reasons += agree
            if not agree:
                differences.append(f"{name} joint {part}: {ja['reasons']} | {jb['reasons']}")
    return {"objects": objects, "same object verdict": same_object, "joints": joints, "same ok": same_ok,
            "same reasons": same_reasons, "differences": differences}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("first", type=Path)
    parser.add_argument("second", type=Path)
    args = parser.parse_args()
    a, b = load(args.first), load(args.second)
    r = compare(a, b)
    print(f"objects in both: {r['objects']} (only in {args.first.name}: {len(a.keys() - b.keys())}, "
          f"only in {args.second.name}: {len(b.keys() - a.keys())})")
    print(f"object verdicts agree: {r['same object verdict']}/{r['objects']}")
    print(f"joint ok flags agree: {r['same ok']}/{r['joints']}; joint reasons agree: {r['same reasons']}/{r['joints']}")
    for line in r["differences"]:
        print("  " + line)
    for name, records in ((args.first.name, a), (args.second.name, b)):
        seconds = [v["seconds"] for v in records.values()]
        if seconds:
            print(f"{name}: seconds per object median {statistics.median(seconds):.1f}, max {max(seconds):.1f} "
                  f"({max(records, key=lambda k: records[k]['seconds'])})")


if __name__ == "__main__":
    main()
