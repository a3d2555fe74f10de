"""Fit the joint prior of ``jax3dc.grounding`` on the reference joints of training records.

    python3 -m train.joint_prior --data .carry/real_train --out jax3dc/grounding/joint_prior.json

Both models are L2-regularised linear models fitted with L-BFGS in seconds on a CPU; the examples
are every joint of every record's target (its canonical structure, read against the record's legend
boxes). Before the final fit, a 5-fold cross-validation by object (never by view) prints how often
the type-and-axis class and the hinge line (within the origin tolerance) come out right on objects
left out. Only ever give it training records: the benchmark's held-out fifth and the fixtures stay
unseen.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from data_pipeline.record import Record
from data_pipeline.shards import read_shard, shard_paths
from jax3dc.grounding.features import LINES, MIN_SIDE, cross_dims, joint_features, line_features
from jax3dc.grounding.prior import CLASSES, JointPrior
from jax3dc.prompt import legend_boxes
from jax3dc.structure import parse_structure

ORIGIN_TOLERANCE = 0.05  # nu, SPEC §5: a hinge line within this of the reference passes
ALIGNED = 0.1  # rad: hinges whose axis is this close to a box direction teach the line scorer


def examples(records: Iterable[Record]) -> tuple[list, list, list, list, list]:
    """(joint features, class index, object) per joint; (line features, line distances, object) per aligned hinge."""
    x, y, objects, lines, distances, line_objects = [], [], [], [], [], []
    for record in records:
        boxes = legend_boxes(record.prompt)
        structure = parse_structure(record.target)
        obj = f"{record.meta.get('category')}/{record.meta.get('object_id')}"
        for pid, node in structure.nodes.items():
            joint = node.joint
            if joint is None or pid not in boxes:
                continue
            child, parent = boxes[pid], boxes.get(node.parent) if node.parent is not None else None
            handles = [boxes[c] for c in structure.children(pid) if c in boxes]
            axis = np.abs(np.asarray(joint.axis, float))
            axis /= np.linalg.norm(axis)
            k = int(np.argmax(axis))
            x.append(joint_features(child, parent, handles))
            y.append(CLASSES.index((joint.type, k)))
            objects.append(obj)
            if joint.type == "hinge" and axis[k] >= np.cos(ALIGNED):
                i, j = cross_dims(k)
                c, e = np.asarray(child.centroid, float), np.asarray(child.extent, float)
                points = np.array([[c[i] + gi * e[i], c[j] + gj * e[j]] for gi, gj in LINES])
                lines.append(line_features(child, parent, k, handles))
                distances.append(np.linalg.norm(points - np.asarray(joint.pivot, float)[[i, j]], axis=1))
                line_objects.append(obj)
    return (np.asarray(x), np.asarray(y), np.asarray(objects),
            (np.asarray(lines), np.asarray(distances), np.asarray(line_objects)))  # type: ignore[return-value]


def fit_classes(x: np.ndarray, y: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Multinomial logistic regression: (mean, scale, weights with a bias row)."""
    mean, scale = x.mean(0), x.std(0) + 1e-6
    z = np.hstack([(x - mean) / scale, np.ones((len(x), 1))])
    n, d, c = len(y), z.shape[1], len(CLASSES)

    def loss(w: np.ndarray) -> tuple[float, np.ndarray]:
        w = w.reshape(d, c)
        logits = z @ w
        logits -= logits.max(1, keepdims=True)
        logp = logits - np.log(np.exp(logits).sum(1, keepdims=True))
        grad_logits = np.exp(logp)
        grad_logits[np.arange(n), y] -= 1
        grad = z.T @ grad_logits / n
        grad[:-1] += 2 * lam * w[:-1]
        return -logp[np.arange(n), y].mean() + lam * (w[:-1] ** 2).sum(), grad.ravel()

    w = minimize(loss, np.zeros(d * c), jac=True, method="L-BFGS-B", options={"maxiter": 1000}).x
    return mean, scale, w.reshape(d, c)


def fit_lines(features: np.ndarray, distances: np.ndarray, lam: float) -> np.ndarray:
    """Conditional logit over the nine lines; the label is the line nearest the reference."""
    y = distances.argmin(1)
    n = len(y)

    def loss(w: np.ndarray) -> tuple[float, np.ndarray]:
        logits = features @ w
        logits -= logits.max(1, keepdims=True)
        logp = logits - np.log(np.exp(logits).sum(1, keepdims=True))
        p = np.exp(logp)
        p[np.arange(n), y] -= 1
        return -logp[np.arange(n), y].mean() + lam * (w ** 2).sum(), np.einsum("ncd,nc->d", features, p) / n + 2 * lam * w

    return minimize(loss, np.zeros(features.shape[2]), jac=True, method="L-BFGS-B").x


def cross_validate(x, y, objects, lines, distances, line_objects, class_lam: float, line_lam: float) -> dict:
    """Shares right on left-out objects (5 folds by object)."""
    order = np.unique(objects)
    np.random.default_rng(0).shuffle(order)
    folds = np.array_split(order, 5)
    chosen, line_right = np.zeros(len(y), int), np.zeros(len(distances), bool)
    for fold in folds:
        test = np.isin(objects, fold)
        mean, scale, w = fit_classes(x[~test], y[~test], class_lam)
        chosen[test] = (np.hstack([(x[test] - mean) / scale, np.ones((test.sum(), 1))]) @ w).argmax(1)
        test = np.isin(line_objects, fold)
        best = (lines[test] @ fit_lines(lines[~test], distances[~test], line_lam)).argmax(1)
        line_right[test] = distances[test][np.arange(test.sum()), best] <= ORIGIN_TOLERANCE
    is_slide = np.array([CLASSES[i][0] == "slide" for i in y])
    said_slide = np.array([CLASSES[i][0] == "slide" for i in chosen])
    return {"type": float((is_slide == said_slide).mean()), "type_axis": float((chosen == y).mean()),
            "hinge_line": float(line_right.mean()),
            "line_upper_bound": float((distances.min(1) <= ORIGIN_TOLERANCE).mean())}


def sources(data: list[str]) -> str:
    """The --data sources in a line: folders as given, shard files counted per folder."""
    files: dict[str, int] = {}
    for source in data:
        path = Path(source)
        key = f"{path.parent}/" if path.is_file() else source
        files[key] = files.get(key, 0) + path.is_file()
    return ", ".join(f"{k} ({n} shards)" if n else k for k, n in files.items())


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", nargs="+", required=True, help="training shards (or folders of them)")
    p.add_argument("--split", default="train", help="the records' split to read (default train)")
    p.add_argument("--out", required=True, help="the prior JSON to write")
    p.add_argument("--class-l2", type=float, default=1e-3)
    p.add_argument("--line-l2", type=float, default=1e-4)
    p.add_argument("--keep-ratio", type=float, default=4.0)
    p.add_argument("--line-sigma", type=float, default=0.05)
    a = p.parse_args(argv)
    records = (r for path in shard_paths(a.data, a.split) for r in read_shard(path) if r.meta.get("split", a.split) == a.split)
    x, y, objects, (lines, distances, line_objects) = examples(records)
    if not len(y) or not len(lines):
        raise SystemExit(f"no joints (or no box-aligned hinges) in {a.data}")
    cv = cross_validate(x, y, objects, lines, distances, line_objects, a.class_l2, a.line_l2)
    print(f"{len(y)} joints of {len(np.unique(objects))} objects, {len(lines)} aligned hinges; 5-fold by object: "
          + ", ".join(f"{k} {v:.3f}" for k, v in cv.items()))
    mean, scale, w = fit_classes(x, y, a.class_l2)
    note = (f"fitted by `python3 -m train.joint_prior` on {len(y)} joints of {len(np.unique(objects))} objects of "
            f"{sources(a.data)} (split {a.split}); 5-fold by object: "
            + ", ".join(f"{k} {v:.3f}" for k, v in cv.items()))
    JointPrior(mean, scale, w, fit_lines(lines, distances, a.line_l2), a.keep_ratio, a.line_sigma, note).save(a.out)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
