"""Scores only: metrics.json (every key, exact) and per_object.jsonl (line by line) of two report folders.
usage: python3 compare_scores.py DIR_A DIR_B"""
import json, sys
from pathlib import Path
a, b = map(Path, sys.argv[1:3])
ma, mb = (json.loads((d / "metrics.json").read_text()) for d in (a, b))
oa, ob = ((d / "per_object.jsonl").read_text().splitlines() for d in (a, b))
oa, ob = ({json.loads(l)["key"]: json.loads(l) for l in x} for x in (oa, ob))
diff_m = [k for k in ma.keys() | mb.keys() if ma.get(k) != mb.get(k)]
diff_o = [k for k in oa.keys() | ob.keys() if oa.get(k) != ob.get(k)]
print(f"{a.name} vs {b.name}: metrics.json keys differing: {diff_m or 'none'}; "
      f"per_object lines {len(oa)} vs {len(ob)}, differing: {diff_o or 'none'}")
print("RESULT:", "IDENTICAL" if not diff_m and not diff_o else "DIFFERENT")
