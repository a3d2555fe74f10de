"""`predict --mounted`: the physics check holds the root of an object fixed in place in use, and
object.xml, the model it judges, keeps its base fixed.

A faucet stood free on a floor falls over; predicted as mounted, its physics.json has no gravity
failure and its object.xml no free joint. The structure model is a stand-in that answers the
faucet's own target. (Without --mounted, object.xml's root is free: test_predict_output_path.)
"""

from __future__ import annotations

import json

import mujoco

from jax3dc.factories import generate_object
from jax3dc.physics.verdict import check_object
from jax3dc.predict import PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.geometry.parts import part_boxes, save_parts
from jax3dc.structure import canonicalize, parse_structure, to_json
from predict_cases import write_image


def test_mounted_prediction_holds_the_root_in_the_physics_check(tmp_path):
    faucet = generate_object("faucet", 0)
    save_parts(faucet.parts, tmp_path / "parts")
    target = to_json(canonicalize(faucet.structure, part_boxes(faucet.parts)))
    config = PredictConfig(Stage1Config(f"parts:{tmp_path / 'parts'}"), generate_structure=lambda prompt: target,
                           mounted=True)
    result = predict(write_image(tmp_path / "image.png"), config, tmp_path / "out")
    verdict = json.loads((tmp_path / "out" / "physics.json").read_text())
    assert verdict == result.verdict.to_json() and verdict["checks"]["gravity"] == []
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "object.xml"))
    assert model.njnt == len(faucet.structure.joints()) > 0
    assert mujoco.mjtJoint.mjJNT_FREE not in set(model.jnt_type)
    free = check_object(parse_structure(target, part_ids=faucet.parts), faucet.parts, 1.0)
    assert any(p.startswith("unstable under gravity") for p in free["checks"]["gravity"]), free["checks"]
