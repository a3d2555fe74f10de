"""Grammar-constrained decoding: outputs that always parse and validate against their prompt.

``structure_constraint`` gives the structure grammar (SPEC §2) for a batch of stage-2 prompts:
their part ids and joint counts set each row's registers; the tables are built once per tokenizer.
``program_constraint`` gives the part-program grammar (SPEC §6) for a batch of stage-1 code
prompts (the same for every row: a program depends on no prompt text).
Pass either to ``jax3dc.generate.decode(..., constraint=...)``.
"""

from __future__ import annotations

import re
from typing import NamedTuple, Sequence

from jax3dc.constrained import program, structure
from jax3dc.constrained.structure import ID_LIMIT, Rows, Tables, initial_rows, structure_tables
from jax3dc.errors import StructureError

_LEGEND_ID = re.compile(r"^(\d+): #[0-9a-fA-F]{6} \|", re.MULTILINE)
_JOINTS = re.compile(r"^Joints: (\d+)\s*$", re.MULTILINE)


class Constraint(NamedTuple):
    """A grammar on the device: its lifted tables and each row's state; defined here, beside the
    grammars that build it, so that ``jax3dc.generate`` imports this package and not the reverse."""

    tables: structure.Tables | program.Tables
    rows: structure.Rows | program.Rows


def prompt_counts(prompt: str, where: str = "prompt") -> tuple[int, int]:
    """(part count N, joint count or -1) of a SPEC §3 prompt, whose legend must list ids 1..N."""
    ids = [int(m) for m in _LEGEND_ID.findall(prompt)]
    if not ids:
        raise StructureError("part_ids", where, "the prompt has no part legend, so no grammar can be set for it")
    if sorted(ids) != list(range(1, len(ids) + 1)):
        raise StructureError("part_ids", where, f"legend ids {ids[:8]}{'...' if len(ids) > 8 else ''} are not 1..{len(ids)}")
    joints = _JOINTS.search(prompt)
    return len(ids), (int(joints[1]) if joints else -1)


def structure_constraint(tokenizer, vocab_size: int, prompts: Sequence[str], names: Sequence[str] | None = None):
    """The structure grammar for these prompts (one row each), as a ``Constraint``;
    ``names`` (e.g. record keys) say which prompt an error is about."""
    names = list(names) if names is not None else [f"prompt {i}" for i in range(len(prompts))]
    counts = [prompt_counts(p, name) for p, name in zip(prompts, names)]
    for (n, _), name in zip(counts, names):
        if n >= ID_LIMIT:
            raise StructureError("part_ids", name, f"{n} parts: the structure grammar takes at most {ID_LIMIT - 1} "
                                 "(decode this object with --unconstrained)")
    return Constraint(structure_tables(tokenizer, vocab_size), initial_rows([n for n, _ in counts], [j for _, j in counts]))


def program_constraint(tokenizer, vocab_size: int, rows: int):
    """The part-program grammar for ``rows`` rows, as a ``Constraint``."""
    return Constraint(program.program_tables(tokenizer, vocab_size), program.initial_rows(rows))


__all__ = ["Constraint", "Rows", "Tables", "program_constraint", "prompt_counts", "structure_constraint"]
