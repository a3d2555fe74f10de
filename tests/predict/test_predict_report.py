"""report.html / report.png: the image, S, every part (id, name, colour) with its joint, and the verdict."""

from __future__ import annotations

import re

import numpy as np
import pytest
from PIL import Image

from jax3dc.physics.findings import WARNING, Finding, Verdict
from jax3dc.predict import PredictConfig, predict
from jax3dc.predict.stage1 import Stage1Config
from jax3dc.predict.report import PANEL
from jax3dc.palette import hex_colour, part_colour
from predict_cases import factory_object, target_json, write_image


@pytest.fixture(scope="module")
def code_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("code_run")
    config = PredictConfig(Stage1Config("code", generate_program=lambda prompt: factory_object().program_text),
                           generate_structure=lambda prompt: target_json())
    return predict(write_image(folder / "image.png"), config, folder / "out")


def test_html_names_every_part_with_its_colour_and_joint(code_run):
    page = (code_run.out / "report.html").read_text()
    structure = code_run.structure
    for pid, name in factory_object().names.items():
        item = re.search(rf'<li[^>]*><span class="sw" style="background:(#[0-9a-f]{{6}})"></span>{pid} {name}\b[^<]*</li>',
                         page)
        assert item, (pid, name)
        assert item.group(1) == hex_colour(part_colour(code_run.palette, pid))
        joint = structure.nodes[pid].joint
        if joint is None:
            assert " axis " not in item.group(0)
        else:
            assert f"{joint.type} axis" in item.group(0) and "physics: ok" in item.group(0)
    assert "physics: PASS" in page
    assert page.count("data:image/png;base64,") == 2  # I and S are embedded: the page stands alone


def test_tree_indents_children_under_their_parents(code_run):
    page = (code_run.out / "report.html").read_text()
    depth = {int(pid): float(em) for em, pid in re.findall(r'margin-left:([\d.]+)em"><span[^>]*></span>(\d+) ', page)}
    structure = code_run.structure
    assert set(depth) == set(structure.nodes)
    for pid, node in structure.nodes.items():
        assert depth[pid] == (0.0 if node.parent is None else depth[node.parent] + 1.5)


def test_png_has_image_seg_and_text_panels(code_run):
    with Image.open(code_run.out / "report.png") as image:
        assert image.width > 2 * PANEL and image.height >= PANEL
        rgb = image.convert("RGB")
        # S panel: every visible part's colour appears
        colours = {c for _, c in rgb.crop((PANEL, 0, 2 * PANEL, PANEL)).getcolors(maxcolors=1 << 16)}
    visible = [pid for pid in factory_object().parts if part_colour(code_run.palette, pid) in colours]
    assert len(visible) >= 3


def test_joints_go_on_s_without_the_image_camera(code_run, tmp_path):
    from jax3dc.predict.report import panels
    from predict_cases import CAMERA

    captions = [caption for caption, _ in panels(_inputs(code_run, camera_given=False))]
    assert "with the predicted joints" in captions[1] and "joints" not in captions[0]
    captions = [caption for caption, _ in panels(_inputs(code_run, camera_given=True, camera=CAMERA.to_dict()))]
    assert "with the predicted joints" in captions[0] and "joints" not in captions[1]
    page = (code_run.out / "report.html").read_text()  # the code run had no --camera
    assert "segmentation S with the predicted joints" in page


def _inputs(result, camera_given, camera=None):
    from jax3dc.predict.report import ReportInputs
    from jax3dc.geometry.parts import part_boxes

    return ReportInputs(Image.open(result.out.parent / "image.png"), np.asarray(Image.open(result.out / "seg.png")),
                        result.palette, result.stage1.names, part_boxes(result.stage1.parts),
                        camera or result.camera.to_dict(), camera_given, result.structure, result.verdict, None)


def test_relations_are_listed(code_run):
    page = (code_run.out / "report.html").read_text()
    relations = code_run.structure.relations
    assert relations  # the cabinet's two doors (and handles) mirror each other
    for rel in relations:
        assert f"{rel.type} {rel.a}-{rel.b}" + (f" ({rel.plane})" if rel.plane else "") in page


def test_a_joint_warning_is_written_beside_its_passing_verdict(code_run):
    """A verdict's warning (a limit past contact, say) shows in the part list and does not fail it."""
    from jax3dc.predict.report import ReportInputs, tree_lines

    structure = code_run.structure
    jointed = next(pid for pid, node in structure.nodes.items() if node.joint is not None)
    verdict = Verdict((jointed,), (Finding("limit", WARNING, joints=(jointed,), reachable=1.2, limit="hi"),))
    inputs = ReportInputs(image=None, seg=None, palette=code_run.palette, names={}, boxes={}, camera={},
                          camera_given=False, structure=structure, verdict=verdict, error=None)
    text = dict((pid, t) for _, pid, t in tree_lines(inputs))[jointed]
    assert text.endswith("physics: ok (warning: limit past contact: hi (stops at q=1.200))")
