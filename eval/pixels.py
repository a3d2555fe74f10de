"""From pixels: a record's image alone through ``predict`` (stage 1 from the image, then stage 2),
scored against the record's reference by matched parts (issue 49's end-to-end Table 1).

Stage 1 makes its own parts, so ids and count differ from the reference's; each prediction's parts
are paired one-to-one with the reference's by box overlap (``match_bounds``) and its structure is
renamed onto the reference ids (``eval.metrics.relabel``: unmatched predicted parts dropped,
missing reference parts added as rigid roots), then scored as ``eval run --predictions`` scores.
A ``predict`` that fails (Jax3dcError) is a parse failure with its message.
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Sequence

from PIL import Image

from data_pipeline.record import Record
from eval.metrics.cases import Reference, build_cases
from eval.metrics.parameters import ParametersScore, score_parameters
from eval.metrics.part_matching import box_bounds, match_bounds
from eval.metrics.relabel import relabel
from eval.metrics.score import Evaluation, evaluate
from jax3dc.decoding import Decoding
from jax3dc.errors import Jax3dcError
from jax3dc.factories.registry import SCHEMAS, run_parameters
from jax3dc.geometry.parts import part_boxes
from jax3dc.predict.pipeline import Checkpoints, PredictConfig, predict
from jax3dc.predict.stage1 import Reader, Stage1Config
from jax3dc.release import default_structure_model
from jax3dc.structure import to_dict

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


def predict_record(record: Record, reference: Reference, out: Path, read_parameters: Reader,
                   checkpoints: Checkpoints, max_new_tokens: int = 1024) -> PixelsResult:
    """``predict`` on the record's image alone (no camera, no parts: the default stage 1 reads the
    image through ``read_parameters``), into ``out``, then matched to ``reference``."""
    started = time.perf_counter()
    try:
        config = PredictConfig(Stage1Config(read_parameters=read_parameters), default_structure_model(),
                               decoding=Decoding(max_new_tokens=max_new_tokens))
        result = predict(Image.open(io.BytesIO(record.image_png)), config, out, checkpoints=checkpoints)
    except Jax3dcError as e:
        return PixelsResult(record.key, None, 0, 0, len(reference.boxes), None, time.perf_counter() - started,
                            str(e))
    seconds = time.perf_counter() - started
    stage1 = None
    text = out / "parameters.txt"
    if record.parameters and text.is_file():
        stage1 = score_parameters(record.key, record.parameters, text.read_text(encoding="utf-8"), SCHEMAS,
                                  run_parameters)
    pairs = match_bounds(box_bounds(reference.boxes), box_bounds(part_boxes(result.stage1.parts)))
    renamed = relabel(result.structure, {pred: ref for ref, pred, _ in pairs}, reference.boxes)
    ok = result.verdict.ok if result.verdict else None
    return PixelsResult(record.key, to_dict(renamed), len(pairs), len(result.stage1.parts) - len(pairs),
                        len(reference.boxes) - len(pairs), stage1, seconds, None, ok)


def score_pixels(references: Sequence[Reference], results: Sequence[PixelsResult]) -> Evaluation:
    """Table 1 of the renamed predictions against ``references`` (a reference without a result is
    a parse failure, as ``eval run`` scores a missing prediction)."""
    by_key = {r.key: r for r in results}
    cases = build_cases(references, {r.key: r.structure for r in results if r.structure is not None})
    return evaluate([replace(c, failure_rule=PREDICT_FAILED, failure=by_key[c.key].failure)
                     if c.key in by_key and by_key[c.key].failure else c for c in cases])
