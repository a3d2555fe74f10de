"""The decoding flags, declared once for every command that decodes (`jax3dc predict`, `jax3dc eval
run`), and the values they become: ``DecodeOptions`` (how the sampler decodes one prompt) inside
``Decoding`` (with the token budget, the dtype and whether a flagged winner is repaired).

Declared twice, the flags drifted: one command's ``--repair`` help promised alternatives the
repair does not try. Here each flag's default is the dataclass field's, and its help says what the
code does. The module imports no jax: every `jax3dc` run (``--help`` included) builds the parsers
that call ``add_decoding_arguments``; ``jax3dc.sampler`` imports ``DecodeOptions`` from here.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from jax3dc.cli_args import positive_float, positive_int

if TYPE_CHECKING:
    from jax3dc.grounding import Grounding

DEFAULT_MAX_NEW_TOKENS = 2048
DTYPES = ("bfloat16", "float32")


@dataclass(frozen=True)
class DecodeOptions:
    """How one prompt is decoded (see ``jax3dc.sampler``)."""

    constrained: bool = True
    candidates: int = 1
    temperature: float = 0.8  # for the sampled candidates
    top_p: float = 0.95
    seed: int = 0
    # Structures: a parent edge the legend boxes show to join two separate objects of a scene is cut
    # (jax3dc.structure.scene_grouping); only where the output reads as a scene (several trees, two
    # bodies on the floor, or a support relation between two objects).
    scene_grouping: bool = True
    # The parameters task's grammar is built from the factories' schemas (category -> Schema): the
    # caller passes them (jax3dc.factories.registry.SCHEMAS).
    schemas: Any = None
    # Joints corrected by the legend boxes after decoding (jax3dc.grounding); None: as the model wrote them.
    grounding: Grounding | None = None

    def __post_init__(self):
        if self.candidates < 1:
            raise ValueError(f"candidates must be >= 1, got {self.candidates}")


@dataclass(frozen=True)
class Decoding:
    """The decoding flags as one value: the options of each decode, the most tokens a model may
    write per answer, the models' compute dtype, and whether the winner's flagged joints are repaired
    (``jax3dc.verify.repair``)."""

    options: DecodeOptions = field(default_factory=DecodeOptions)
    max_new_tokens: int = DEFAULT_MAX_NEW_TOKENS
    dtype: str = "bfloat16"
    repair: bool = False


_DEFAULTS = Decoding()


def add_decoding_arguments(parser: argparse.ArgumentParser, choice_file: str, repair_file: str) -> None:
    """Adds the decoding flags to ``parser``; ``choice_file`` / ``repair_file``: where the command
    writes which candidate won and why, and the repairs (the help names them)."""
    options = _DEFAULTS.options
    parser.add_argument("--max-new-tokens", type=positive_int, default=_DEFAULTS.max_new_tokens, metavar="N",
                        help="most tokens each model may write per answer; generation stops here at the latest "
                        "(default %(default)s)")
    parser.add_argument("--dtype", default=_DEFAULTS.dtype, choices=DTYPES,
                        help="model compute dtype (default %(default)s; float32 on CPU is slower but exact)")
    parser.add_argument("--unconstrained", action="store_true",
                        help="decode without the grammars (by default every answer parses: a structure against its "
                        "legend, a part program, a factory's category and parameters)")
    parser.add_argument("--candidates", type=positive_int, default=options.candidates, metavar="K",
                        help="K structures per image from one decode, the first greedy, the rest sampled "
                        f"(--temperature, --top-p, --seed); K > 1 lets the physics verdict choose, and {choice_file} "
                        "says which won and why (default %(default)s)")
    parser.add_argument("--repair", action="store_true",
                        help="move the pivot of each hinge of the chosen structure that the physics check flags to a "
                        f"line where child and parent meet, kept only when the verdict improves ({repair_file} lists "
                        "the repairs); only pivots move (jax3dc.verify.repair.DEFAULT_KINDS): axis flips and "
                        "hinge/slide swaps undid right joints on the test objects, so they are not tried")
    parser.add_argument("--ground-joints", action="store_true",
                        help="correct each decoded joint's type, axis and hinge line with the legend's part boxes "
                        "(jax3dc.grounding; off by default: on the release-3 benchmark it did not raise success on "
                        "held-out real objects, see docs/runs/grounding_20261128)")
    parser.add_argument("--scene-grouping", action=argparse.BooleanOptionalAction, default=options.scene_grouping,
                        help="in a scene (the model wrote several trees, the legend shows two bodies on the floor, or "
                        "the model wrote a support relation between two objects), cut each parent edge the legend "
                        "boxes show to join two separate objects, and hang a piece left without its parent from its "
                        "own object (jax3dc.structure.scene_grouping; default: on)")
    parser.add_argument("--temperature", type=positive_float, default=options.temperature, metavar="T",
                        help="sampling temperature of candidates 2..K (default %(default)s)")
    parser.add_argument("--top-p", type=positive_float, default=options.top_p, metavar="P",
                        help="nucleus of candidates 2..K (default %(default)s)")
    parser.add_argument("--seed", type=int, default=options.seed, metavar="N",
                        help="sampling seed (default %(default)s)")


def decoding_from_args(args: argparse.Namespace) -> Decoding:
    """The ``Decoding`` of the flags ``add_decoding_arguments`` declared."""
    grounding = None
    if args.ground_joints:
        from jax3dc.grounding import Grounding  # lazy: the structure package (0.1 s), only when asked for

        grounding = Grounding()
    options = DecodeOptions(constrained=not args.unconstrained, candidates=args.candidates,
                            temperature=args.temperature, top_p=args.top_p, seed=args.seed,
                            scene_grouping=args.scene_grouping, grounding=grounding)
    return Decoding(options, args.max_new_tokens, args.dtype, args.repair)
