"""Where matched IoU is lost: predicted vs hybrids with the reference's numbers or discrete values."""
import json, sys, numpy as np
from pathlib import Path
from recipes.stage1_net import load_split_images
from eval.metrics.parameters import score_parameters, summarise
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.parameters import Parameters, parse_parameters, format_parameters
from jax3dc.parameters.schema import Number
from jax3dc.stage1_net import load_network
folders = [Path(f"runs/s1r2/data-{i}") for i in range(4)]
net = load_network("jax3dc/release/stage1")
keys, images, texts, builds = load_split_images(folders, 128, only="test")["test"]
pred = []
for lo in range(0, len(keys), 64):
    pred += net.read(np.asarray(images[lo:lo+64], np.float32) / 255.0)
rows = {"pred": [], "true_numbers": [], "true_discrete": []}
for k, ref, p in zip(keys, texts, pred):
    rows["pred"].append(score_parameters(k, ref, p, SCHEMAS, run_parameters))
    r, q = parse_parameters(ref, SCHEMAS), parse_parameters(p, SCHEMAS)
    if r.category != q.category:
        for n in ("true_numbers", "true_discrete"): rows[n].append(rows["pred"][-1])
        continue
    sch = SCHEMAS[r.category]
    isnum = {s.name: isinstance(s, Number) for s in sch.specs}
    tn = Parameters(r.category, {n: (r.values[n] if isnum[n] else q.values[n]) for n in r.values})
    td = Parameters(r.category, {n: (q.values[n] if isnum[n] else r.values[n]) for n in r.values})
    rows["true_numbers"].append(score_parameters(k, ref, format_parameters(tn, sch), SCHEMAS, run_parameters))
    rows["true_discrete"].append(score_parameters(k, ref, format_parameters(td, sch), SCHEMAS, run_parameters))
for n, s in rows.items():
    m = summarise(s); print(n, {x: round(m[x], 1) for x in ("category", "count_exact", "matched_iou")}, flush=True)

