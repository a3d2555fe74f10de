"""The decoding flags are declared once (jax3dc.decoding): `jax3dc predict` and `jax3dc eval run`
take the same ones with the same defaults, their defaults are the dataclasses', and the help of
``--repair`` says what the default repair kinds try."""

from __future__ import annotations

import argparse

import pytest

from jax3dc.cli import build_parser
from jax3dc.decoding import DecodeOptions, Decoding, add_decoding_arguments, decoding_from_args
from jax3dc.grounding import Grounding
from jax3dc.verify.repair import DEFAULT_KINDS, PIVOT


def _decoding_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser()
    add_decoding_arguments(parser, "chosen.json", "repaired.json")
    return parser


def _flags(parser: argparse.ArgumentParser) -> dict[str, tuple]:
    return {action.dest: (tuple(action.option_strings), action.default) for action in parser._actions}


def test_predict_and_eval_run_take_the_same_decoding_flags():
    commands = build_parser(["eval"])._subparsers._group_actions[0].choices
    predict = _flags(commands["predict"])
    run = _flags(commands["eval"].subcommands.choices["run"])
    declared = _flags(_decoding_parser())
    del declared["help"]
    assert {dest: predict[dest] for dest in declared} == declared == {dest: run[dest] for dest in declared}


def test_the_defaults_are_the_dataclasses_and_each_flag_lands_in_its_field():
    parser = _decoding_parser()
    assert decoding_from_args(parser.parse_args([])) == Decoding()
    args = parser.parse_args(["--max-new-tokens", "9", "--dtype", "float32", "--unconstrained", "--candidates", "3",
                              "--repair", "--ground-joints", "--no-scene-grouping", "--temperature", "0.5",
                              "--top-p", "0.7", "--seed", "4"])
    options = DecodeOptions(constrained=False, candidates=3, temperature=0.5, top_p=0.7, seed=4, scene_grouping=False,
                            grounding=Grounding())
    assert decoding_from_args(args) == Decoding(options, 9, "float32", True)


@pytest.mark.parametrize("argv", [["--candidates", "0"], ["--max-new-tokens", "0"], ["--top-p", "-1"]])
def test_counts_and_rates_out_of_range_are_refused(argv):
    with pytest.raises(SystemExit):
        _decoding_parser().parse_args(argv)


def test_the_repair_help_says_what_the_default_kinds_try():
    """The help was once copied into two commands and one copy promised axis flips and type swaps:
    this test fails when the default kinds change, so that the help is rewritten with them."""
    repair = next(a for a in _decoding_parser()._actions if a.dest == "repair")
    assert DEFAULT_KINDS == frozenset({PIVOT})
    assert "only pivots move" in repair.help and "are not tried" in repair.help
    assert "repaired.json" in repair.help
