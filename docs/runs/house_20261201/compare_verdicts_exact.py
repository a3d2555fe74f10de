"""Compare two physics_ground_truth.py --verdicts files object by object, timing removed.

Every key named 'seconds' (at any depth) is dropped; the rest of each object's line must be equal.
Also prints, per side, sha256 of each object's verdict without timing (canonical JSON, sorted keys).
usage: python3 compare_verdicts_exact.py BEFORE.jsonl AFTER.jsonl [--digests OUT.tsv]
"""
import argparse, hashlib, json, sys
from pathlib import Path


def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if k != "seconds"}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x


def load(p):
    out, order = {}, []
    for n, line in enumerate(Path(p).read_text().splitlines(), 1):
        try:
            r = json.loads(line)
        except json.JSONDecodeError:
            print(f"{p}:{n}: not a whole JSON line", file=sys.stderr)
            continue
        out[r["object"]] = strip(r)
        order.append(r["object"])
    return out, order


def canon(x):
    return json.dumps(x, sort_keys=True, separators=(",", ":"))


def diff(a, b, path=""):
    if type(a) != type(b):
        return [f"{path}: {a!r} != {b!r}"]
    if isinstance(a, dict):
        out = []
        for k in sorted(a.keys() | b.keys()):
            if k not in a or k not in b:
                out.append(f"{path}/{k}: only in {'after' if k not in a else 'before'}")
            else:
                out += diff(a[k], b[k], f"{path}/{k}")
        return out
    if isinstance(a, list):
        if len(a) != len(b):
            return [f"{path}: lists of {len(a)} vs {len(b)}: {a!r} != {b!r}"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in diff(x, y, f"{path}[{i}]")]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


ap = argparse.ArgumentParser()
ap.add_argument("before"); ap.add_argument("after"); ap.add_argument("--digests")
args = ap.parse_args()
a, oa = load(args.before)
b, ob = load(args.after)
both = sorted(a.keys() & b.keys())
same = [k for k in both if canon(a[k]) == canon(b[k])]
print(f"objects: before {len(a)}, after {len(b)}, in both {len(both)}")
print(f"only before: {sorted(a.keys() - b.keys())}")
print(f"only after: {sorted(b.keys() - a.keys())}")
print(f"same order of lines: {oa == ob}")
joints = sum(len(a[k]['verdict']['joints']) for k in both)
print(f"joints in both: {joints}")
print(f"objects whose verdict (timing removed) is identical: {len(same)}/{len(both)}")
for k in both:
    for d in diff(a[k], b[k]):
        print(f"  DIFF {k}{d}")
if args.digests:
    with open(args.digests, "w") as f:
        f.write("object\tsha256_before\tsha256_after\n")
        for k in sorted(a.keys() | b.keys()):
            h = lambda d: hashlib.sha256(canon(d[k]).encode()).hexdigest() if k in d else "-"
            f.write(f"{k}\t{h(a)}\t{h(b)}\n")
print("RESULT:", "IDENTICAL" if len(same) == len(both) == len(a) == len(b) else "DIFFERENT")
