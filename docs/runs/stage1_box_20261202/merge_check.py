import numpy as np
from pathlib import Path
from collections import defaultdict
from recipes.stage1_net import load_split_images
from eval.metrics.parameters import score_parameters, summarise
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.stage1_net import load_network, forward
from jax3dc.stage1_net.folder import decode_text
folders = [Path(f"runs/s1r2/data-{i}") for i in range(4)]
r4 = load_network("jax3dc/release/stage1"); d = load_network("runs/s1b/d/stage1")
keys, images, texts, builds = load_split_images(folders, 128, only="test")["test"]
def outs(net):
    o = [forward(net.model, np.asarray(images[lo:lo+64], np.float32) / 255.0) for lo in range(0, len(keys), 64)]
    return [np.concatenate([np.asarray(x[i]) for x in o]) for i in range(3)]
A, B = outs(r4), outs(d)
rows = {}
for name, (c, n, k) in {"merge r4 cat+disc, d numbers": (A[0], B[1], A[2]), "d cat, r4 disc": (B[0], B[1], A[2])}.items():
    sc = [score_parameters(key, ref, decode_text(d.layout, SCHEMAS, c[i], n[i], k[i]), SCHEMAS, run_parameters)
          for i, (key, ref) in enumerate(zip(keys, texts))]
    m = summarise(sc); print(name, {x: round(m[x], 1) for x in ("category", "count_exact", "matched_iou")}, flush=True)
    rows[name] = sc
sd = [score_parameters(key, ref, decode_text(d.layout, SCHEMAS, B[0][i], B[1][i], B[2][i]), SCHEMAS, run_parameters) for i, (key, ref) in enumerate(zip(keys, texts))]
s4 = [score_parameters(key, ref, decode_text(d.layout, SCHEMAS, A[0][i], A[1][i], A[2][i]), SCHEMAS, run_parameters) for i, (key, ref) in enumerate(zip(keys, texts))]
g = defaultdict(list)
for a, b in zip(s4, sd): g[a.key.split("/")[0].rsplit("_", 1)[0]].append((a.count_exact, b.count_exact, a.matched_iou, b.matched_iou))
for c, v in sorted(g.items(), key=lambda kv: sum(x[1] - x[0] for x in kv[1])):
    v = np.array(v, float); print(c, len(v), "count r4 %.0f d %.0f  iou r4 %.1f d %.1f" % tuple(100 * v.mean(0)))
