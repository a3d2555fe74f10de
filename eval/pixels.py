"""From pixels: a record's image alone through ``predict`` (stage 1 from the image, then stage 2),
scored against the record's reference by matched parts (issue 49's end-to-end Table 1).

Stage 1 makes its own parts, so ids and count differ from the reference's; each prediction's parts
are paired one-to-one with the reference's by box overlap (``match_bounds``) and its structure is
renamed onto the reference ids (``eval.metrics.relabel``: unmatched predicted parts dropped,
missing reference parts added as rigid roots), then scored as ``eval run --predictions`` scores.
A ``predict`` that fails (Jax3dcError) is a parse failure with its message.

Stage 1's parts are also scored as boxes (``score_boxes``: RS-dgIoU, parts matched at IoU >= 0.5,
extra parts, part-kind accuracy; eval.metrics.part_boxes), whichever backend made them, the parts of
a prediction that stopped after stage 1 included: a stage 1 that reads the image badly and one whose
stage 2 then fails are told apart.
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

from PIL import Image

from data_pipeline.record import Record
from eval.metrics.cases import Reference, build_cases
from eval.metrics.parameters import ParametersScore, score_parameters
from eval.metrics.part_boxes import PartBoxScore, score_part_boxes
from eval.metrics.part_matching import box_bounds, match_bounds
from eval.metrics.relabel import relabel
from eval.metrics.score import Case, Evaluation, evaluate
from jax3dc.decoding import Decoding
from jax3dc.errors import Jax3dcError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import load_parts, part_boxes
from jax3dc.predict.outputs import ObjectContext
from jax3dc.predict.pipeline import Checkpoints, PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.release import default_structure_model
from jax3dc.stage1_slots.kinds import kind_of
from jax3dc.structure import Box, to_dict

PREDICT_FAILED = "predict"  # the failure rule of a record whose prediction raised


@dataclass(frozen=True)
class PixelsResult:
    """One record predicted from its image: the structure renamed onto the reference ids (None when
    predict failed: ``failure`` says why), how its parts paired, stage 1's own scores, and the
    seconds predict took (both stages, exports, physics, report)."""

    key: str
    structure: dict[str, Any] | None
    matched: int
    extra: int  # predicted parts without a reference partner (dropped)
    missing: int  # reference parts without a predicted partner (added as rigid roots)
    stage1: ParametersScore | None  # None when the record has no parameters text or stage 1 failed
    seconds: float
    failure: str | None = None
    physics_ok: bool | None = None
    parts: PartBoxScore | None = None  # stage 1's parts as boxes (score_boxes); a predict that made none scores empty


def score_boxes(record: Record, reference: Reference, boxes: Mapping[int, Box],
                names: Mapping[int, str]) -> PartBoxScore:
    """Stage 1's parts (``boxes`` in the normalised frame, ``names`` by part id) against the record's
    reference parts, as eval.metrics.part_boxes scores them. Kinds on both sides are the part names
    read through jax3dc.stage1_slots.kinds: the slots backend names each part by its kind, the
    factory network's parts carry their factory's semantic names (``freezer_door``: a door; a name
    with no word the table knows is ``other``), the reference its meta["part_names"]; a reference
    part without a name has no kind and its pair is left out of kind accuracy. The boxes are the
    record's view's, so a view with a joint moved is not at rest: callers pass rest views."""
    reference_names = record.meta.get("part_names") or {}
    ref_ids, pred_ids = sorted(reference.boxes), sorted(boxes)
    ref_bounds, pred_bounds = box_bounds(reference.boxes), box_bounds(boxes)
    return score_part_boxes(record.key, [ref_bounds[i] for i in ref_ids],
                            [kind_of(reference_names[str(i)]) if str(i) in reference_names else None for i in ref_ids],
                            [pred_bounds[i] for i in pred_ids], [kind_of(names.get(i)) for i in pred_ids])


def _written_parts(out: Path, written: Mapping[str, Path]) -> tuple[dict[int, Box], dict[int, str]]:
    """The boxes and names of the parts this prediction wrote before it failed (none when it
    stopped in stage 1); ``written`` is what predict announced, so an earlier run's files in
    ``out`` are never read."""
    if "parts" not in written or "context" not in written:
        return {}, {}
    return part_boxes(load_parts(written["parts"])), ObjectContext.read(out).names


def predict_record(record: Record, reference: Reference, out: Path, stage1: Stage1Config,
                   checkpoints: Checkpoints, max_new_tokens: int = 1024,
                   structure_model: str | Path | None = None) -> PixelsResult:
    """``predict`` on the record's image alone (no camera, no parts: stage 1 reads the image as
    ``stage1`` says, e.g. ``Stage1Config(read_parameters=reader)`` or ``Stage1Config(backend="slots",
    slots_model_dir=DIR)``), with ``structure_model`` (default: the shipped one), into ``out``, then
    matched to ``reference``."""
    started = time.perf_counter()
    written: dict[str, Path] = {}
    try:
        config = PredictConfig(stage1, structure_model or default_structure_model(),
                               decoding=Decoding(max_new_tokens=max_new_tokens))
        result = predict(Image.open(io.BytesIO(record.image_png)), config, out, on_output=written.__setitem__,
                         checkpoints=checkpoints)
    except Jax3dcError as e:
        seconds = time.perf_counter() - started
        return PixelsResult(record.key, None, 0, 0, len(reference.boxes), None, seconds, str(e),
                            parts=score_boxes(record, reference, *_written_parts(out, written)))
    seconds = time.perf_counter() - started
    stage1 = None
    text = out / "parameters.txt"
    if record.parameters and text.is_file():
        stage1 = score_parameters(record.key, record.parameters, text.read_text(encoding="utf-8"), SCHEMAS,
                                  run_parameters)
    pairs = match_bounds(box_bounds(reference.boxes), box_bounds(part_boxes(result.stage1.parts)))
    renamed = relabel(result.structure, {pred: ref for ref, pred, _ in pairs}, reference.boxes)
    ok = result.verdict.ok if result.verdict else None
    parts = score_boxes(record, reference, part_boxes(result.stage1.parts), result.stage1.names)
    return PixelsResult(record.key, to_dict(renamed), len(pairs), len(result.stage1.parts) - len(pairs),
                        len(reference.boxes) - len(pairs), stage1, seconds, None, ok, parts)


def pixels_cases(references: Sequence[Reference], results: Sequence[PixelsResult]) -> list[Case]:
    """The scoring cases of the renamed predictions against ``references`` (a reference without a
    result is a parse failure, as ``eval run`` scores a missing prediction; a failed predict is one
    with its message)."""
    by_key = {r.key: r for r in results}
    cases = build_cases(references, {r.key: r.structure for r in results if r.structure is not None})
    return [replace(c, failure_rule=PREDICT_FAILED, failure=by_key[c.key].failure)
            if c.key in by_key and by_key[c.key].failure else c for c in cases]


def score_pixels(references: Sequence[Reference], results: Sequence[PixelsResult]) -> Evaluation:
    """Table 1 of ``pixels_cases``."""
    return evaluate(pixels_cases(references, results))
