"""Candidates averaged: python3 ensemble_check.py FOLDER_A FOLDER_B (test records of runs/s1r2/data-0..3)."""
import sys, numpy as np, jax
from pathlib import Path
from recipes.stage1_net import load_split_images
from eval.metrics.parameters import score_parameters, summarise
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.stage1_net import load_network, forward
from jax3dc.stage1_net.folder import decode_text
folders = [Path(f"runs/s1r2/data-{i}") for i in range(4)]
nets = [load_network(f) for f in sys.argv[1:]]
keys, images, texts, builds = load_split_images(folders, 128, only="test")["test"]
outs = []
for net in nets:
    cat, num, disc = [], [], []
    for lo in range(0, len(keys), 64):
        c, n, d = (np.asarray(x) for x in forward(net.model, np.asarray(images[lo:lo+64], np.float32) / 255.0))
        cat.append(jax.nn.log_softmax(c, -1)); num.append(n); disc.append(jax.nn.log_softmax(np.where(net.layout.class_mask()[None], d, -1e9), -1))
    outs.append([np.concatenate(x) for x in (cat, num, disc)])
for name, chosen in [("a", [0]), ("b", [1]), ("a+b", [0, 1])]:
    c = np.mean([outs[i][0] for i in chosen], 0); n = np.mean([outs[i][1] for i in chosen], 0); d = np.mean([outs[i][2] for i in chosen], 0)
    pred = [decode_text(nets[0].layout, SCHEMAS, c[i], n[i], d[i]) for i in range(len(keys))]
    m = summarise([score_parameters(k, t, p, SCHEMAS, run_parameters) for k, t, p in zip(keys, texts, pred)])
    print(name, {k: round(v, 2) for k, v in m.items() if isinstance(v, float)}, flush=True)
