"""How each record's numbers move its parts' boxes: a per-record metric for the stage-1 number loss.

Matched part-box IoU, not the numbers' error, is what stage 1 is judged on, and the two disagree:
the factory's parts are normalised (centred, largest side 1), so a change of every length at once
moves no box, and an entry a branch never reads moves nothing; the plain number loss asks the
network to read both from the image anyway. Here the factory is run with each number of the
record nudged (central differences of 0.05 of its range) to get J, the change of every part's box
corners per unit of normalised number, each corner's row divided by its part's extent along that
axis (floored at ``MIN_EXTENT``), since a box's IoU falls with its error relative to its size. The
metric is ``M = Jᵀ J / parts`` over the record's numbers, so ``dᵀ M d`` is, to first order, the
mean squared relative box error a number error ``d`` causes (train.stage1_net's ``box_weight``).
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from jax3dc.errors import Jax3dcError
from jax3dc.factories.registry import run_parameters
from jax3dc.parameters import Parameters, Schema, parse_parameters
from jax3dc.parameters.schema import DECIMALS
from jax3dc.stage1_net.folder import normalised_number
from jax3dc.stage1_net.layout import OutputLayout, Slot

STEP = 0.05  # of an entry's range
MIN_EXTENT = 0.02  # nu: a part thinner than this counts as this thick


def _boxes(parameters: Parameters) -> dict[int, np.ndarray]:
    return {pid: np.asarray(mesh.bounds, np.float64) for pid, mesh in run_parameters(parameters).parts.items()}


def _nudged(parameters: Parameters, name: str, slot: int | None, value: float) -> Parameters:
    values = dict(parameters.values)
    if slot is None:
        values[name] = value
    else:
        values[name] = tuple(value if k == slot else v for k, v in enumerate(values[name]))
    return Parameters(parameters.category, values)


def _end(params: Parameters, slot: Slot, share: float, target: float, base: dict[int, np.ndarray]
         ) -> tuple[float, dict[int, np.ndarray]]:
    """(share, boxes) with ``slot``'s number moved to ``target`` (clipped to its range and rounded as
    the schema rounds); the record itself where the move is none, fails, or changes the set of parts
    (a count derived from a length)."""
    lo, hi = slot.spec.lo, slot.spec.hi
    moved = round(lo + min(max(target, 0.0), 1.0) * (hi - lo), DECIMALS)
    value = params[slot.spec.name] if slot.slot is None else params[slot.spec.name][slot.slot]
    if moved == value:
        return share, base
    try:
        boxes = _boxes(_nudged(params, slot.spec.name, slot.slot, moved))
    except Jax3dcError:
        return share, base
    return (normalised_number(slot.spec, moved), boxes) if sorted(boxes) == sorted(base) else (share, base)


def box_metric(text: str, layout: OutputLayout, schemas: Mapping[str, Schema]) -> tuple[np.ndarray, np.ndarray]:
    """(head indices [K] of the record's numbers, metric M [K, K]) of one parameter text."""
    params = parse_parameters(text, schemas)
    slots = [s for s in layout.numbers if s.category == params.category]
    base = _boxes(params)
    ids = sorted(base)
    corners = np.stack([base[i] for i in ids])  # [P, 2, 3]
    weight = 1.0 / np.maximum(corners[:, 1] - corners[:, 0], MIN_EXTENT)  # [P, 3]
    columns = []
    for s in slots:
        value = params[s.spec.name] if s.slot is None else params[s.spec.name][s.slot]
        share = normalised_number(s.spec, value)
        (s_hi, b_hi), (s_lo, b_lo) = (_end(params, s, share, t, base) for t in (share + STEP, share - STEP))
        if s_hi == s_lo:
            columns.append(np.zeros(corners.size))
            continue
        diff = np.stack([b_hi[i] - b_lo[i] for i in ids]) / (s_hi - s_lo)  # [P, 2, 3]
        columns.append((diff * weight[:, None, :]).ravel())
    jac = np.stack(columns, axis=1) if columns else np.zeros((corners.size, 0))
    return np.array([s.index for s in slots], np.int32), (jac.T @ jac / len(ids)).astype(np.float32)


def _one(args: tuple[str, OutputLayout, Mapping[str, Schema]]) -> tuple[np.ndarray, np.ndarray]:
    return box_metric(*args)


def box_metrics(texts: Sequence[str], layout: OutputLayout, schemas: Mapping[str, Schema], width: int,
                workers: int = 1, cache: Path | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Index [B, width] (-1 where none) and metric [B, width, width] of each text; distinct texts are
    computed once (two views of one object share theirs), over ``workers`` processes, and kept in
    ``cache`` (JSON lines, text -> metric) when given, so a later run reads them back."""
    known: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if cache is not None and cache.exists():
        for line in cache.read_text(encoding="utf-8").splitlines():
            row = json.loads(line)
            known[row["text"]] = (np.asarray(row["index"], np.int32), np.asarray(row["metric"], np.float32))
    todo = sorted(set(texts) - set(known))
    if todo:
        jobs = [(t, layout, schemas) for t in todo]
        if workers > 1:
            with ProcessPoolExecutor(workers) as pool:
                found = list(pool.map(_one, jobs, chunksize=64))
        else:
            found = [_one(j) for j in jobs]
        known.update(zip(todo, found))
        if cache is not None:
            with cache.open("a", encoding="utf-8") as f:
                for t, (index, metric) in zip(todo, found):
                    f.write(json.dumps({"text": t, "index": index.tolist(),
                                        "metric": np.round(metric, 5).tolist()}, separators=(",", ":")) + "\n")
    index = np.full((len(texts), width), -1, np.int32)
    metric = np.zeros((len(texts), width, width), np.float32)
    for i, t in enumerate(texts):
        k_index, k_metric = known[t]
        if len(k_index) > width:
            raise ValueError(f"a record has {len(k_index)} numbers, more than the metric's width {width}")
        index[i, :len(k_index)] = k_index
        metric[i, :len(k_index), :len(k_index)] = k_metric
    return index, metric
