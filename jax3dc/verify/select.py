"""Best of K (SPEC §7 decoding): the physics verdict chooses among candidate texts for one object.

Candidates are ranked, best first: parses (and validates against the legend's part ids) > the
object's verdict passes > fewer flagged joints > higher log-likelihood. The model's likelihood only
breaks ties because it is what sampled the wrong candidates in the first place; the verdict is
evidence from outside the model. Candidates are parsed and canonicalised as the metrics do
(``eval.metrics.cases``), so identical structures (same canonical JSON) are checked once.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass

from jax3dc.errors import StructureError
from jax3dc.physics.findings import Verdict
from jax3dc.structure import Box, Structure, canonicalize, parse_structure
from jax3dc.structure.validate import json_text
from jax3dc.verify.verdicts import VerdictCache


@dataclass(frozen=True)
class Candidate:
    text: str
    logprob: float  # sum of the token log-probabilities of the generated text


@dataclass(frozen=True)
class Row:
    """How one candidate fared: a parse failure carries the broken rule, a parsed one its verdict."""

    parsed: bool
    rule: str | None
    ok: bool | None
    flagged: int | None
    logprob: float
    verdict: Verdict | None


@dataclass(frozen=True)
class Choice:
    index: int  # of the winner in the candidates
    structure: Structure | None  # the winner, canonical; None when no candidate parses
    rows: tuple[Row, ...]  # one per candidate, in candidate order
    reason: str  # one line: why the winner won


def parse_candidate(text: str, part_ids: Collection[int], boxes: Mapping[int, Box]) -> Structure:
    """A candidate validated against the part ids and canonicalised with the boxes (StructureError)."""
    return canonicalize(parse_structure(json_text(text), part_ids), boxes)


def choose(candidates: Sequence[Candidate], boxes: Mapping[int, Box], check: VerdictCache) -> Choice:
    """The best candidate by the order of the module docstring (ties: the earlier candidate).

    ``boxes``: the legend's part boxes, whose ids a candidate must name exactly and with which it is
    canonicalised; ``check``: the caller's cache of these parts' verdicts (it holds the meshes and
    how they are checked), passed in so later steps (the repair) reuse the winner's verdict."""
    if not candidates:
        raise ValueError("choose needs at least one candidate")
    parsed = [_parsed(candidate.text, boxes.keys(), boxes) for candidate in candidates]
    structures = [structure for structure, _ in parsed]
    verdicts = iter(check.many([s for s in structures if s is not None]))  # together: one MJX launch
    rows = [Row(False, rule, None, None, c.logprob, None) if structure is None else
            _row(c.logprob, next(verdicts)) for c, (structure, rule) in zip(candidates, parsed)]
    ranked = sorted(range(len(rows)), key=lambda i: rank(rows[i]), reverse=True)
    return Choice(ranked[0], structures[ranked[0]], tuple(rows), _reason(rows, ranked))


def _parsed(text: str, part_ids: Collection[int], boxes: Mapping[int, Box]) -> tuple[Structure | None, str | None]:
    """The candidate's structure, or None and the rule it breaks."""
    try:
        return parse_candidate(text, part_ids, boxes), None
    except StructureError as e:
        return None, e.rule


def _row(logprob: float, verdict: Verdict) -> Row:
    return Row(True, None, verdict.ok, verdict.flagged, logprob, verdict)


def rank(row: Row) -> tuple:
    """A candidate's merit, higher first: it parses, then its verdict's merit, then its
    log-likelihood. Public so that an evaluator picking among the first K rows ranks as ``choose``."""
    if not row.parsed:
        return (False, False, 0, row.logprob)
    return (True, *row.verdict.merit(), row.logprob)


def _reason(rows: list[Row], ranked: list[int]) -> str:
    """Why the winner beat the runner-up: the first criterion on which they differ."""
    win = rows[ranked[0]]
    if len(rows) == 1:
        return "the only candidate" + ("" if win.parsed else " (it does not parse)")
    if not win.parsed:
        return "no candidate parses; highest log-likelihood"
    runner = rows[ranked[1]]
    if not runner.parsed:
        return "only candidate that parses"
    if win.ok and not runner.ok:
        failing = sum(1 for i in ranked[1:] if rows[i].parsed and not rows[i].ok)
        return f"passes the physics check; {failing} other{'s fail' if failing != 1 else ' fails'}"
    if win.flagged != runner.flagged:
        return f"fewest flagged joints ({win.flagged} vs {runner.flagged})"
    return "highest log-likelihood among equals"
