"""Numbers pulled toward the train mean by a factor per output fitted on val, then scored on test."""
import numpy as np
from pathlib import Path
from recipes.stage1_net import load_split_images
from eval.metrics.parameters import score_parameters, summarise
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.stage1_net import load_network, forward
from jax3dc.stage1_net.folder import decode_text
from train.stage1_net import targets
folders = [Path(f"runs/s1r2/data-{i}") for i in range(4)]
net = load_network("jax3dc/release/stage1"); layout = net.layout
sp = load_split_images(folders, 128)
T = {k: targets(v[1], v[2], layout, SCHEMAS) for k, v in sp.items()}
def outputs(t):
    outs = [forward(net.model, t.images[lo:lo+64].astype(np.float32) / 255.0) for lo in range(0, len(t), 64)]
    return [np.concatenate([np.asarray(o[i]) for o in outs]) for i in range(3)]
mean = (T["train"].numbers * T["train"].number_mask).sum(0) / np.maximum(T["train"].number_mask.sum(0), 1)
val_c, val_n, val_d = outputs(T["val"]); test_c, test_n, test_d = outputs(T["test"])
grid = np.linspace(0, 1, 11)
alpha = np.ones(len(mean))
v, m = T["val"], T["val"].number_mask
for j in range(len(mean)):
    col = m[:, j]
    if col.sum() < 5: continue
    errs = [np.abs(np.clip(mean[j] + a * (val_n[col, j] - mean[j]), 0, 1) - v.numbers[col, j]).mean() for a in grid]
    alpha[j] = grid[int(np.argmin(errs))]
print("alpha quartiles", np.percentile(alpha, [10, 25, 50, 75]), "zeros", int((alpha == 0).sum()))
t = T["test"]
for name, n in [("raw", test_n), ("shrunk", mean[None] + alpha[None] * (test_n - mean[None]))]:
    print(name, "test number MAE", np.abs(np.clip(n, 0, 1) - t.numbers)[t.number_mask].mean().round(4))
    keys, texts = sp["test"][0], sp["test"][2]
    pred = [decode_text(layout, SCHEMAS, test_c[i], n[i], test_d[i]) for i in range(len(keys))]
    s = summarise([score_parameters(k, r, p, SCHEMAS, run_parameters) for k, r, p in zip(keys, texts, pred)])
    print(name, {k: round(v, 2) for k, v in s.items() if isinstance(v, float)}, flush=True)
