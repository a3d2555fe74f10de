"""The shipped recipes render the trainer commands their model cards give, and every evaluator
name reaches a module with ``main`` (read with ``ast``: nothing heavy is imported)."""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path

from eval.evaluate import main as evaluate
from eval.evaluators import EVALUATORS
from recipes.run import commands


def test_structure_release4_is_the_model_cards_command():
    [(trainer, argv)] = commands("structure_release4", Path("OUT"), Path("DATA"))
    assert trainer == "recipes.release_model"
    assert argv == ["--out", "OUT/release4", "--init", "mini", "--tokenizer", "jax3dc/release", "--objects", "8500",
                    "--scenes", "1500", "--views", "2", "--augment", "--appearance", "varied", "--real",
                    "DATA/real_train_v2", "--real-weight", "0.3", "--pivot-frame", "box", "--steps", "1400",
                    "--lr", "0.001"]


def test_stage1_release5_chains_its_calls():
    calls = commands("stage1_release5", Path("OUT"), Path("DATA"))
    assert [trainer for trainer, _ in calls] == ["recipes.stage1_net"] * 3
    c, d, release = (argv for _, argv in calls)
    assert c[c.index("--widths") + 1:c.index("--blocks")] == ["32", "64", "128", "256"]
    assert d[d.index("--init") + 1] == "OUT/c/stage1"
    assert release[release.index("--init") + 1] == release[release.index("--compare") + 1] == "OUT/d/stage1"
    assert release[release.index("--discrete-weight") + 1] == "3"
    assert {argv[argv.index("--box-cache") + 1] for argv in (c, d, release)} == {"OUT/metrics.jsonl"}


def test_every_evaluator_has_a_main():
    for e in EVALUATORS.values():
        spec = importlib.util.find_spec(e.module)
        assert spec is not None and spec.origin, e.name
        tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
        assert any(isinstance(n, ast.FunctionDef) and n.name == "main" for n in tree.body), e.name


def test_evaluate_lists_the_evaluators(capsys):
    assert evaluate([]) == 0
    listed = capsys.readouterr().out
    assert all(name in listed for name in EVALUATORS)


def test_structure_release5_repeats_its_mix_and_set_flags():
    """Shares and train overrides take their flag each (argparse's append), paths resolved under --data."""
    [(trainer, argv)] = commands("structure_release5", Path("OUT"), Path("DATA"))
    assert trainer == "recipes.release_model"
    assert argv[argv.index("--mix") + 1] == "DATA/composed=0.15" and argv.count("--mix") == 1
    assert argv[argv.index("--set") + 1] == "loader_workers=14"
    assert "--fuse-handles" in argv and argv[argv.index("--appearance") + 1] == "mixed"
    from recipes.release_model import mix_entry
    assert mix_entry(argv[argv.index("--mix") + 1]) == ("DATA/composed", 0.15)
