"""The output path of `predict`: with a perfect stand-in structure model, every output loads.

MJCF and URDF in MuJoCo, the GLB in trimesh, structure.json validates and equals the object's
canonical target, parts/ holds the stage-1 parts, seg.png matches a direct render, and the
physics verdict of a factory object passes. Tiny trained models are the lead's test.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from jax3dc.render import mujoco, png_array  # mujoco imported after render chose the GL backend
from jax3dc.predict import PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.geometry.parts import load_parts
from jax3dc.prompt import CODE_PROMPT, LEGEND_HEADER
from jax3dc.structure import parse_structure, to_json
from predict_cases import CAMERA, direct_render, factory_object, target_json, write_glb, write_image

OUTPUTS = ("structure.json", "seg.png", "parts", "object.urdf", "object.xml", "object.usda", "object.glb", "object_blender.py",
           "physics.json", "report.html", "report.png")


def stand_in(stage1: str) -> PredictConfig:
    """Stage 1 from ``stage1``, the image's camera, and the object's own target as the structure model."""
    return PredictConfig(Stage1Config(stage1), generate_structure=lambda prompt: target_json(), camera=CAMERA)


@pytest.fixture(scope="module")
def mesh_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mesh_run")
    prompts, listed = [], []
    config = PredictConfig(Stage1Config(f"mesh:{write_glb(folder / 'object.glb')}"),
                           generate_structure=lambda prompt: prompts.append(prompt) or target_json(), camera=CAMERA)
    result = predict(write_image(folder / "image.png"), config, folder / "out",
                     on_output=lambda name, path: listed.append(path))
    return result, prompts, listed


def test_predict_output_path_every_output_loads(mesh_run):
    result, prompts, listed = mesh_run
    out, obj = result.out, factory_object()
    for name in OUTPUTS:
        assert (out / name).exists(), name
        assert out / name in listed, name  # the caller is told where each output is
    structure = parse_structure((out / "structure.json").read_text(), part_ids=obj.parts)
    assert to_json(structure) == target_json() == (out / "structure.json").read_text()
    joints = len(structure.joints())
    assert joints >= 1
    assert mujoco.MjModel.from_xml_path(str(out / "object.urdf")).njnt == joints
    model = mujoco.MjModel.from_xml_path(str(out / "object.xml"))  # the checked model: free on a floor, not mounted
    assert model.njnt == joints + 1 and list(model.jnt_type).count(mujoco.mjtJoint.mjJNT_FREE) == 1
    scene = trimesh.load(str(out / "object.glb"), force="scene")
    assert len(scene.graph.nodes_geometry) >= len(obj.parts)
    assert "import bpy" in (out / "object_blender.py").read_text()
    assert sorted(load_parts(out / "parts")) == sorted(obj.parts)
    verdict = json.loads((out / "physics.json").read_text())
    assert verdict["ok"] is True and set(verdict["joints"]) == {str(j) for j in structure.joints()}
    assert len(prompts) == 1 and LEGEND_HEADER in prompts[0]
    assert all(f"\n{pid}: #" in prompts[0] for pid in obj.parts)


def test_predict_seg_png_matches_a_direct_render(mesh_run):
    result = mesh_run[0]
    seg = png_array((result.out / "seg.png").read_bytes())
    _, want = direct_render(result.palette, size=seg.shape[0])
    assert np.mean(np.all(seg == want, axis=-1)) > 0.995


def test_predict_is_deterministic(mesh_run, tmp_path):
    first = mesh_run[0]
    predict(first.out.parent / "image.png", stand_in(f"mesh:{first.out.parent / 'object.glb'}"), tmp_path)
    for name in ("structure.json", "seg.png", "object.xml", "object.urdf", "physics.json"):
        assert (tmp_path / name).read_bytes() == (first.out / name).read_bytes(), name


def test_code_backend_runs_the_program_into_named_parts(tmp_path):
    obj = factory_object()
    asked = []
    program = Stage1Config("code", generate_program=lambda prompt: asked.append(prompt) or obj.program_text)
    config = PredictConfig(program, generate_structure=lambda prompt: target_json())
    result = predict(write_image(tmp_path / "image.png"), config, tmp_path / "out")
    assert asked == [CODE_PROMPT]
    assert (tmp_path / "out" / "program.txt").read_text() == obj.program_text
    assert result.stage1.names == obj.names
    assert sorted(result.stage1.parts) == sorted(obj.parts)
    assert mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "object.xml")).njnt == len(obj.structure.joints()) + 1  # + free root
    assert np.unique(png_array((tmp_path / "out" / "seg.png").read_bytes()).reshape(-1, 3), axis=0).shape[0] >= 3


def test_fenced_reply_with_end_marker_parses_and_seg_has_the_image_size(tmp_path):
    from PIL import Image

    wide = tmp_path / "wide.png"
    Image.new("RGB", (120, 80), (40, 40, 40)).save(wide)
    reply = "```json\n" + target_json() + "\n```<|im_end|>"
    config = PredictConfig(Stage1Config(f"mesh:{write_glb(tmp_path / 'object.glb')}"),
                           generate_structure=lambda prompt: reply, camera=CAMERA)
    result = predict(wide, config, tmp_path / "out")
    assert (tmp_path / "out" / "structure.json").read_text() == target_json()
    assert result.raw_text == reply
    assert png_array((tmp_path / "out" / "seg.png").read_bytes()).shape == (80, 120, 3)


def test_obj_groups_give_the_same_outputs_as_the_glb(mesh_run, tmp_path):
    from predict_cases import write_obj_groups

    first = mesh_run[0]
    predict(first.out.parent / "image.png", stand_in(f"mesh:{write_obj_groups(tmp_path / 'object.obj')}"),
            tmp_path / "out")
    assert (tmp_path / "out" / "prompt.txt").read_text() == (first.out / "prompt.txt").read_text()
    seg, want = (png_array((folder / "seg.png").read_bytes()) for folder in (tmp_path / "out", first.out))
    assert np.mean(np.all(seg == want, axis=-1)) > 0.999
    for name in ("structure.json", "physics.json"):
        assert (tmp_path / "out" / name).read_text() == (first.out / name).read_text(), name


def test_parts_dir_backend_reads_a_previous_prediction(mesh_run, tmp_path):
    first = mesh_run[0]
    again = predict(first.out.parent / "image.png", stand_in(f"parts:{first.out / 'parts'}"), tmp_path)
    assert sorted(again.stage1.parts) == sorted(first.stage1.parts)
    for name in ("prompt.txt", "structure.json", "physics.json"):
        assert (tmp_path / name).read_text() == (first.out / name).read_text(), name



def test_transparent_image_is_on_white_like_the_processor(mesh_run, tmp_path):
    from PIL import Image

    rgba = Image.new("RGBA", (64, 64), (200, 10, 10, 0))  # transparent red: white once composited
    rgba.paste((10, 10, 200, 255), (16, 16, 48, 48))
    predict(rgba, stand_in(f"mesh:{mesh_run[0].out.parent / 'object.glb'}"), tmp_path)
    report = np.asarray(Image.open(tmp_path / "report.png").convert("RGB"))
    assert report[0, 0].tolist() == [255, 255, 255]  # the I panel's corner
    assert report[256, 256].tolist() == [10, 10, 200]  # its opaque middle
