"""The slots network's exists threshold chosen on validation records (the build's val split, never
the held-out fifth), then the held-out fifth scored at that threshold."""
import json, sys
import numpy as np
from pathlib import Path
from eval.metrics.part_boxes import score_part_boxes, summarise
from jax3dc.stage1_slots import load_slots
from recipes.stage1_slots import _bounds, load_records

def score(net, rows):
    rest = [r for r in rows if r[5]] or rows
    out = []
    for lo in range(0, len(rest), 64):
        chunk = rest[lo:lo + 64]
        images = np.stack([r[0] for r in chunk]).astype(np.float32) / 255.0
        for row, slots in zip(chunk, net.read(images)):
            out.append(score_part_boxes(row[4], row[2], row[3], [_bounds(s.centre, s.extent) for s in slots], [s.kind for s in slots]))
    return summarise(out)

folder = Path(sys.argv[1])
val = load_records(["/tmp/slots/proc", "/tmp/slots/composed"], "val", 128, 24, 1)
held = load_records(["/tmp/slots/heldout_named"], "test", 128, 24, 1)
results = {}
for t in (0.5, 0.6, 0.7, 0.8, 0.9):
    results[t] = score(load_slots(folder, t), val)
    print("val", t, json.dumps(results[t]), flush=True)
best = min(results, key=lambda t: results[t]["rs_dgiou"])
print("best on val", best, "held-out", json.dumps(score(load_slots(folder, best), held)), flush=True)
