"""Grammar-constrained decoding: outputs that always parse and validate against their prompt.

``structure_constraint`` gives the structure grammar (SPEC §2) for a batch of stage-2 prompts:
their part ids and joint counts set each row's registers; the tables are built once per tokenizer.
``program_constraint`` gives the part-program grammar (SPEC §6) for a batch of stage-1 code
prompts (the same for every row: a program depends on no prompt text).
``parameters_constraint`` gives the grammar of factory parameter texts (jax3dc.parameters) for
a batch of stage-1 parameter prompts, from the schemas the caller passes (the same for every row).
Pass either to ``jax3dc.generate.decode(..., constraint=...)``. ``task_constraint`` picks among
them by the decode's task name.

The promise: for any model and any logits, a row given at least the shortest document's tokens
stops on a document that parses and validates against its prompt (see ``structure`` and
``program`` for how each grammar keeps it).
"""

from __future__ import annotations

import re
from typing import NamedTuple, Sequence

import numpy as np

from jax3dc.constrained import parameters, program, structure
from jax3dc.constrained.structure import ID_LIMIT, Rows, Tables, initial_rows, min_tokens, structure_tables
from jax3dc.errors import StructureError

_LEGEND_ID = re.compile(r"^(\d+): #[0-9a-fA-F]{6} \|", re.MULTILINE)
_JOINTS = re.compile(r"^Joints: (\d+)\s*$", re.MULTILINE)


class Constraint(NamedTuple):
    """A grammar on the device: its lifted tables and each row's state; defined here, beside the
    grammars that build it, so that ``jax3dc.generate`` imports this package and not the reverse."""

    tables: structure.Tables | program.Tables | parameters.Tables
    rows: structure.Rows | program.Rows | parameters.Rows


def prompt_counts(prompt: str, where: str = "prompt") -> tuple[int, int]:
    """(part count N, joint count or -1) of a SPEC §3 prompt, whose legend must list ids 1..N."""
    ids = [int(m) for m in _LEGEND_ID.findall(prompt)]
    if not ids:
        raise StructureError("part_ids", where, "the prompt has no part legend, so no grammar can be set for it")
    if sorted(ids) != list(range(1, len(ids) + 1)):
        raise StructureError("part_ids", where, f"legend ids {ids[:8]}{'...' if len(ids) > 8 else ''} are not 1..{len(ids)}")
    joints = _JOINTS.search(prompt)
    return len(ids), (int(joints[1]) if joints else -1)


def _room(room: int | Sequence[int] | None, rows: int) -> list[int] | None:
    if room is None:
        return None
    out = [int(room)] * rows if isinstance(room, (int, np.integer)) else [int(x) for x in room]
    if len(out) != rows:
        raise ValueError(f"room has {len(out)} entries for {rows} rows")
    return out


def structure_constraint(tokenizer, vocab_size: int, prompts: Sequence[str], names: Sequence[str] | None = None,
                         room: int | Sequence[int] | None = None):
    """The structure grammar for these prompts (one row each), as a ``Constraint``;
    ``names`` (e.g. record keys) say which prompt an error is about. ``room`` (one for all rows, or
    one per row): the most new tokens a row may write, stop token included (the smaller of
    max_new_tokens and the model's context minus the prompt); a row whose room cannot hold the
    shortest document for its prompt is an error naming it."""
    names = list(names) if names is not None else [f"prompt {i}" for i in range(len(prompts))]
    counts = [prompt_counts(p, name) for p, name in zip(prompts, names)]
    for (n, _), name in zip(counts, names):
        if n >= ID_LIMIT:
            raise StructureError("part_ids", name, f"{n} parts: the structure grammar takes at most {ID_LIMIT - 1} "
                                 "(decode this object with --unconstrained)")
    room = _room(room, len(prompts))
    tables = structure_tables(tokenizer, vocab_size)
    rows = initial_rows([n for n, _ in counts], [j for _, j in counts], room)
    if room is not None:
        need = min_tokens(tables, rows)
        for name, have, needed in zip(names, room, need):
            if have < needed:
                raise StructureError("max_new_tokens", name, f"room for {have} new tokens cannot hold the shortest "
                                     f"structure for this prompt ({needed} tokens): raise --max-new-tokens, or use a "
                                     "model with a longer context")
    return Constraint(tables, rows)


def program_constraint(tokenizer, vocab_size: int, rows: int, room: int | Sequence[int] | None = None):
    """The part-program grammar for ``rows`` rows, as a ``Constraint``; ``room`` as for
    ``structure_constraint``."""
    return Constraint(program.program_tables(tokenizer, vocab_size), program.initial_rows(rows, _room(room, rows)))


def parameters_constraint(schemas, tokenizer, vocab_size: int, rows: int):
    """The parameter-text grammar of ``schemas`` (category -> Schema) for ``rows`` rows, as a
    ``Constraint``."""
    return Constraint(parameters.parameters_tables(schemas, tokenizer, vocab_size), parameters.initial_rows(rows))


__all__ = ["Constraint", "Rows", "Tables", "min_tokens", "parameters_constraint", "program_constraint", "prompt_counts",
           "structure_constraint"]


def task_constraint(task: str, tokenizer, vocab_size: int, prompts: Sequence[str], names: Sequence[str],
                    room: Sequence[int], schemas=None) -> Constraint:
    """The grammar of a batch of one ``task`` (the sampler's task names): "structure" (SPEC §2, set by
    each row's prompt), "code" (part programs) or "parameters" (factory parameter texts of
    ``schemas``, category -> Schema, which the caller must pass). ``prompts``, ``names`` and
    ``room`` have one entry per row; the grammars that need no prompt read only their count."""
    if task == "structure":
        return structure_constraint(tokenizer, vocab_size, prompts, names, room)
    if task == "code":
        return program_constraint(tokenizer, vocab_size, len(prompts), room)
    if task == "parameters":
        if schemas is None:
            raise ValueError("the parameters grammar needs DecodeOptions.schemas (the factories' schemas)")
        return parameters_constraint(schemas, tokenizer, vocab_size, len(prompts))
    raise ValueError(f"no grammar for task {task!r}: one of structure, code, parameters")
