"""Typed errors. Each names the problem and where it is; the CLI catches them once."""

from __future__ import annotations


class Jax3dcError(Exception):
    """Base of every error a user can cause with bad input.

    The CLI prints ``str(error)`` on one line and exits 1. Subclasses whose constructor takes other
    arguments than the message say how to rebuild them (``__reduce__``), so an error raised in a
    worker process (data build, physics sweep) reaches the parent intact instead of breaking the pool.
    """


class StructureError(Jax3dcError):
    """A structure document breaks a rule of SPEC §2.

    ``rule`` is a short stable name of the broken rule (tests and metrics key on it);
    ``where`` says which node / relation / field (e.g. ``"node 3 joint.axis"``).
    """

    def __init__(self, rule: str, where: str, message: str):
        self.rule = rule
        self.where = where
        self.message = message
        super().__init__(f"{where}: {message} [{rule}]" if where else f"{message} [{rule}]")

    def __reduce__(self):
        return type(self), (self.rule, self.where, self.message)


class EditError(StructureError):
    """An edit patch (jax3dc.edits) is malformed, or its result breaks a rule of SPEC §2: ``where``
    names the place in the patch (``part``, ``ops[2].value``), so the person who wrote it can find
    it; a StructureError, since an edited structure is validated like any other."""


class FolderBusyError(Jax3dcError):
    """Another edit of the same folder is running (an edit holds the folder's lock from reading
    structure.json to writing the last file; a second one waits for nobody and says so)."""


class InputFileError(Jax3dcError):
    """A file given to us is missing, unreadable or malformed (mesh, PNG, URDF, boxes...)."""

    def __init__(self, path: str, message: str):
        self.path = str(path)
        self.message = message
        super().__init__(f"{path}: {message}")

    def __reduce__(self):
        return type(self), (self.path, self.message)


class ProgramError(Jax3dcError):
    """A part program is rejected or fails; ``line`` is 1-based in the program text."""

    def __init__(self, line: int | None, message: str):
        self.line = line
        self.message = message
        super().__init__(f"line {line}: {message}" if line is not None else message)

    def __reduce__(self):
        return type(self), (self.line, self.message)


class SetupError(Jax3dcError):
    """The machine lacks something a command needs (a system library, an OpenGL context); the
    message says what to install or set."""


MAX_MESSAGE_CHARS = 400
"""Longest message the CLI prints; a hostile argument (a 500,000-character path) is cut in the middle."""


def shorten(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` on one line and at most about ``limit`` characters: the start and end are kept,
    since a message names the problem first and often the file last."""
    text = " ".join(str(text).split())
    if len(text) <= limit:
        return text
    head, tail = (limit * 2) // 3, limit // 3
    return f"{text[:head]} ...[{len(text) - head - tail} characters cut]... {text[-tail:]}"
