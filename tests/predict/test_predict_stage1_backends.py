"""Stage-1 backends by name: one registered beside the built-in ones is what `--stage1 NAME` runs
and `jax3dc predict --help` lists, with no edit to the pipeline; an unknown name or a missing
argument is one error line naming the choices, before anything is written."""

from __future__ import annotations

import re

import pytest

from jax3dc.cli import main
from jax3dc.factories import generate_object
from jax3dc.geometry.parts import load_parts
from jax3dc.predict.stage1 import BACKENDS, Stage1, Stage1Backend, Stage1Image, Stage1Settings, register_backend
from predict_cases import write_image

SUMMARY = "a factory object of the category named, as a network that writes parts would give them"


@pytest.fixture
def factory_backend():
    """``factory:CATEGORY``, registered for the test: the factory's object (seed 0) as the parts,
    and each call's image and settings."""
    calls: list[tuple[Stage1Image, Stage1Settings]] = []

    def run(image: Stage1Image, settings: Stage1Settings) -> Stage1:
        calls.append((image, settings))
        obj = generate_object(settings.argument, 0)
        return Stage1(obj.parts, dict(obj.names), obj.scale_m_per_nu, "factory", category=obj.category)

    register_backend(Stage1Backend("factory", SUMMARY, run, argument="CATEGORY", reads_image=True))
    yield calls
    del BACKENDS["factory"]


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    return write_image(tmp_path_factory.mktemp("inputs") / "image.png")


def test_a_registered_backend_is_listed_in_the_help(factory_backend, capsys):
    with pytest.raises(SystemExit) as e:
        main(["predict", "--help"])
    assert e.value.code == 0
    page = capsys.readouterr().out
    assert re.search(rf"^  factory:CATEGORY +{re.escape(SUMMARY)}$", page, re.M)
    for backend in BACKENDS.values():  # each backend on one line of its own
        assert len(re.findall(rf"^  {re.escape(backend.usage)} +\S", page, re.M)) == 1, backend.name
    assert "--stage1 parameters|code|mesh:FILE|parts:DIR|slots|factory:CATEGORY" in " ".join(page.split())


def test_stage1_runs_a_registered_backend(factory_backend, image, tmp_path, capsys):
    out = tmp_path / "out"
    missing = tmp_path / "no_structure_model"  # stage 2 stops the run: stage 1's outputs are what is tested
    assert main(["predict", str(image), "--stage1", "factory:bucket", "--structure-model", str(missing),
                 "--max-new-tokens", "7", "--out", str(out)]) == 1
    assert str(missing) in capsys.readouterr().err
    (seen, settings), = factory_backend
    assert seen.where == str(image) and seen.rgb.shape == (96, 96, 3) and seen.png == (out / "image.png").read_bytes()
    assert settings.argument == "bucket" and settings.decoding.max_new_tokens == 7
    assert sorted(load_parts(out / "parts")) == sorted(generate_object("bucket", 0).parts)


@pytest.mark.parametrize("spec", ["nope", "factory", "factory:", "code:x"])
def test_an_unknown_backend_or_a_missing_argument_is_one_line_naming_the_choices(factory_backend, image, tmp_path,
                                                                                  capsys, spec):
    out = tmp_path / "out"
    assert main(["predict", str(image), "--stage1", spec, "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"jax3dc predict: error: {spec}: --stage1 must be "), err
    for backend in BACKENDS.values():
        assert f"`{backend.usage}`" in err[0]
    assert not out.exists() and factory_backend == []


@pytest.mark.parametrize("name", ["code", "mesh:x", ""])
def test_a_taken_or_malformed_name_is_refused(name):
    with pytest.raises(ValueError):
        register_backend(Stage1Backend(name, "another", lambda image, settings: None))
    assert [b.name for b in BACKENDS.values()][:5] == ["parameters", "code", "mesh", "parts", "slots"]
