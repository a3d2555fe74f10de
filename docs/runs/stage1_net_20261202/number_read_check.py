"""Numbers of the shipped network against the train mean, per output (test records of runs/s1r2/data-0..3)."""
import numpy as np
from collections import defaultdict
from pathlib import Path
from recipes.stage1_net import load_split_images
from jax3dc.factories.registry import SCHEMAS
from jax3dc.stage1_net import load_network, forward, OutputLayout
from train.stage1_net import targets
folders = [Path(f"runs/s1r2/data-{i}") for i in range(4)]
net = load_network("jax3dc/release/stage1")
layout = net.layout
sp = load_split_images(folders, 128)
train = targets(sp["train"][1], sp["train"][2], layout, SCHEMAS)
test = targets(sp["test"][1], sp["test"][2], layout, SCHEMAS)
pred = np.concatenate([np.clip(np.asarray(forward(net.model, test.images[lo:lo+64].astype(np.float32) / 255.0)[1]), 0, 1) for lo in range(0, len(test), 64)])
m = test.number_mask
err = np.abs(pred - test.numbers)
# baselines: constant 0.5, and the train mean of each output
mean = (train.numbers * train.number_mask).sum(0) / np.maximum(train.number_mask.sum(0), 1)
print("network MAE", err[m].mean().round(3), "| constant 0.5", np.abs(0.5 - test.numbers)[m].mean().round(3),
      "| train mean", np.abs(mean[None] - test.numbers)[m].mean().round(3))
per = []
for s in layout.numbers:
    col = m[:, s.index]
    if col.sum() < 10: continue
    e = err[col, s.index].mean(); b = np.abs(mean[s.index] - test.numbers[col, s.index]).mean()
    per.append((e / b, s.category, s.spec.name, s.slot, round(float(e), 3), round(float(b), 3)))
per.sort()
print("best read (error / train-mean error):", [p[1:4] + (round(p[0], 2),) for p in per[:8]])
print("worst read:", [p[1:4] + (round(p[0], 2),) for p in per[-8:]])
r = np.array([p[0] for p in per]); print("ratio quartiles", np.percentile(r, [25, 50, 75]).round(2), "of", len(r))
