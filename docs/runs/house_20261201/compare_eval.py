"""Compare two `jax3dc eval run` report folders: predictions text by text, per-object scores, metrics.

usage: python3 compare_eval.py BEFORE_DIR AFTER_DIR
Predictions: every key's line (all fields; 'text' reported separately). Metrics: every key of
metrics.json (numbers compared exactly; the largest |difference| printed). per_object.jsonl: line by line.
"""
import json, sys
from pathlib import Path


def lines(p):
    return {r["key"]: r for r in map(json.loads, Path(p).read_text().splitlines()) if r}


def flat(d, pre=""):
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(flat(v, f"{pre}{k}."))
        else:
            out[f"{pre}{k}"] = v
    return out


a_dir, b_dir = map(Path, sys.argv[1:3])
ok = True
pa, pb = lines(a_dir / "predictions.jsonl"), lines(b_dir / "predictions.jsonl")
both = sorted(pa.keys() & pb.keys())
same_text = [k for k in both if pa[k].get("text") == pb[k].get("text")]
same_line = [k for k in both if pa[k] == pb[k]]
print(f"predictions: before {len(pa)}, after {len(pb)}, in both {len(both)}; "
      f"only before {len(pa.keys() - pb.keys())}, only after {len(pb.keys() - pa.keys())}")
print(f"generated text identical: {len(same_text)}/{len(both)}; whole line identical: {len(same_line)}/{len(both)}")
fields = sorted({f for k in both for f in pa[k].keys() | pb[k].keys()})
print(f"prediction fields: {fields}")
for k in both:
    if pa[k].get("text") != pb[k].get("text"):
        ok = False
        ta, tb = pa[k].get("text", ""), pb[k].get("text", "")
        i = next((i for i, (x, y) in enumerate(zip(ta, tb)) if x != y), min(len(ta), len(tb)))
        print(f"  TEXT DIFF {k}: first at char {i} (lengths {len(ta)}, {len(tb)}): "
              f"...{ta[max(0, i - 60):i + 60]!r} | ...{tb[max(0, i - 60):i + 60]!r}")
    elif pa[k] != pb[k]:
        ok = False
        print(f"  LINE DIFF {k}: " + ", ".join(f"{f}: {pa[k].get(f)!r} != {pb[k].get(f)!r}"
                                                 for f in fields if pa[k].get(f) != pb[k].get(f)))
if pa.keys() != pb.keys():
    ok = False

oa, ob = lines(a_dir / "per_object.jsonl"), lines(b_dir / "per_object.jsonl")
same_obj = sum(oa.get(k) == ob.get(k) for k in oa.keys() | ob.keys())
print(f"per_object.jsonl: {len(oa)} vs {len(ob)} lines, identical {same_obj}/{len(oa.keys() | ob.keys())}")
for k in sorted(oa.keys() | ob.keys()):
    if oa.get(k) != ob.get(k):
        ok = False
        x, y = oa.get(k) or {}, ob.get(k) or {}
        print(f"  PER-OBJECT DIFF {k}: " + ", ".join(f"{f}: {x.get(f)!r} != {y.get(f)!r}"
                                                  for f in sorted(x.keys() | y.keys()) if x.get(f) != y.get(f)))

ma, mb = (flat(json.loads((d / "metrics.json").read_text())) for d in (a_dir, b_dir))
print(f"metrics.json: {len(ma)} vs {len(mb)} keys")
for k in sorted(ma.keys() | mb.keys()):
    x, y = ma.get(k, "<absent>"), mb.get(k, "<absent>")
    mark = "same" if x == y else "DIFF"
    ok &= x == y
    print(f"  {mark:4} {k:28} {x!r:>24} {y!r:>24}")
ra, rb = ((d / "references.jsonl").read_bytes() for d in (a_dir, b_dir))
print(f"references.jsonl byte-identical: {ra == rb}")
ok &= ra == rb
print("RESULT:", "IDENTICAL" if ok else "DIFFERENT")
