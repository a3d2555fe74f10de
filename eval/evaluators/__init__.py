"""The accuracy evaluators, chosen by name: ``python3 -m eval.evaluate NAME [ARGS...]``.

Each evaluator measures how right the system is on a benchmark set (speed lives in ``bench/``). Its
module exposes ``main(argv)``: the arguments are its settings (``python3 -m eval.evaluate NAME
--help`` lists them) and it returns its results (what it also writes and prints). The registry
names the modules without importing them, so listing the evaluators loads neither jax nor a model.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Evaluator:
    """One evaluator: its name on the command line, its module, and a line saying what it measures."""

    name: str
    summary: str

    @property
    def module(self) -> str:
        return f"{__name__}.{self.name}"

    def run(self, argv: Sequence[str]) -> Any:
        """Run the evaluator with ``argv`` as its settings; returns its results."""
        return importlib.import_module(self.module).main(list(argv))


EVALUATORS: dict[str, Evaluator] = {e.name: e for e in (
    Evaluator("real_objects", "the release benchmark: held-out real objects beside procedural ones, each model "
              "beside the no-training baselines"),
    Evaluator("pixels_end_to_end", "from pixels per stage-1 backend (factory network, slots): RS-dgIoU, parts "
              "matched, extra parts, part kinds, joints right beside stage 2 on true parts"),
    Evaluator("physics_ground_truth", "the physics check's false alarms on ground truth and its mutation detection"),
    Evaluator("appearance_shift", "the shipped model on MuJoCo renders against Blender Cycles renders of the same "
              "records"),
    Evaluator("joint_grounding", "joint grounding on and off, step by step, on predictions already made"),
    Evaluator("scene_grouping", "scene grouping on predictions already made, and on built scenes"),
    Evaluator("verified_decoding", "verified decoding (best of K, repair) against greedy decoding"),
    Evaluator("size_sweep", "accuracy against model size and training steps"),
    Evaluator("learning_run", "does a model trained from scratch beat the no-training baselines"),
    Evaluator("image_check", "the no-object image check: every render accepted, blank and noise refused"),
)}


def evaluator(name: str) -> Evaluator:
    """The evaluator called ``name``; an unknown name is one error naming the known ones."""
    try:
        return EVALUATORS[name]
    except KeyError:
        raise SystemExit(f"unknown evaluator {name!r}; known: {', '.join(EVALUATORS)}") from None
