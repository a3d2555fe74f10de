"""`predict --candidates K --repair`: the winner is parsed once (the choice hands its structure on)
and no structure's physics verdict is computed twice (one cache serves the choice, the repair and
physics.json). The model is a stand-in that answers the same structure twice, once fenced."""

from __future__ import annotations

import json

from jax3dc.decoding import DecodeOptions, Decoding
from jax3dc.predict import pipeline
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.structure import to_json
from jax3dc.verify import verdicts
from predict_cases import CAMERA, target_json, write_glb, write_image


def test_the_winner_is_parsed_once_and_each_verdict_computed_once(tmp_path, monkeypatch):
    target = target_json()
    replies = [(f"```json\n{target}\n```", -2.0), (target, -1.0)]
    monkeypatch.setattr(pipeline.Checkpoints, "get", lambda self, folder: None)
    monkeypatch.setattr(pipeline, "structure_candidates", lambda *args, **kwargs: (lambda prompt: replies))
    parsed_again = []
    monkeypatch.setattr(pipeline, "parse_structure", lambda *args, **kwargs: parsed_again.append(args))
    checked = []
    real = verdicts.Physics.verdicts  # what the cache asks for each batch of unseen structures
    monkeypatch.setattr(verdicts.Physics, "verdicts", lambda self, ss: checked.extend(to_json(s) for s in ss) or real(self, ss))

    out = tmp_path / "out"
    config = pipeline.PredictConfig(Stage1Config(f"mesh:{write_glb(tmp_path / 'object.glb')}"), "stand-in",
                                    decoding=Decoding(DecodeOptions(candidates=2), repair=True), camera=CAMERA)
    result = pipeline.predict(write_image(tmp_path / "image.png"), config, out)

    assert parsed_again == []  # the structure is the one the choice parsed
    assert len(checked) == len(set(checked)) == 1  # both candidates, the repair and physics.json: one verdict
    choice = json.loads((out / "candidates.json").read_text())
    assert choice["winner"] == 1 and choice["reason"] == "highest log-likelihood among equals"
    assert json.loads((out / "repairs.json").read_text()) == []
    assert json.loads((out / "physics.json").read_text())["ok"] == result.verdict.ok
    assert (out / "object.xml").is_file() and to_json(result.structure) == (out / "structure.json").read_text()
