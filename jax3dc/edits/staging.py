"""Replacing a folder's files all together or not at all: an edit never leaves half its files.

``staged(folder)`` hands out an empty folder inside ``folder`` to write the new files into; only
when every one is written does each replace the entry of the same name in ``folder`` (a rename,
atomic per entry; an entry that fails to move puts back the ones moved before it). An error while
writing removes the stage and leaves ``folder`` as it was, byte for byte.

``folder_lock(folder)`` makes edits of one folder take turns: the command line and the local app
may edit the same object at once, and two stages swapped in turn would mix two structures' files.
The lock is an advisory ``flock`` on the folder itself (no lock file: a refused edit leaves the
folder as it was), so a killed process releases it; a second editor is told at once
(FolderBusyError) rather than queued behind an edit it cannot see.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from jax3dc.errors import FolderBusyError

STAGE_PREFIX = ".edit-"
REPLACED = ".replaced"  # inside a stage: the entries its files replaced, until the swap is complete


@contextmanager
def folder_lock(folder: Path) -> Iterator[None]:
    """Holds ``folder``'s edit lock for the block; FolderBusyError if another editor holds it.
    Stages a killed editor left behind are removed once the lock is held (nobody else writes them)."""
    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise FolderBusyError(f"{folder}: another edit of this folder is running; try again when it is done") from None
        for stale in folder.glob(STAGE_PREFIX + "*"):
            shutil.rmtree(stale, ignore_errors=True)
        yield
    finally:
        os.close(fd)  # releases the lock


def _swap(stage: Path, folder: Path) -> None:
    """Moves every entry of ``stage`` into ``folder``, the entries they replace into the stage's
    REPLACED; on a failure, moves back what was moved and re-raises."""
    replaced = stage / REPLACED
    replaced.mkdir()
    moved: list[tuple[str, bool]] = []  # (name, whether it replaced an entry)
    try:
        for entry in sorted(p for p in stage.iterdir() if p.name != REPLACED):
            target = folder / entry.name
            had = target.exists() or target.is_symlink()
            if had:
                os.rename(target, replaced / entry.name)
            moved.append((entry.name, had))
            os.rename(entry, target)
    except OSError:
        for name, had in reversed(moved):
            target = folder / name
            if target.exists() or target.is_symlink():
                os.rename(target, stage / name)
            if had:
                os.rename(replaced / name, target)
        raise


@contextmanager
def staged(folder: Path) -> Iterator[Path]:
    """An empty folder inside ``folder`` for the block to write into; its entries replace
    ``folder``'s when the block ends without an error (module docstring)."""
    stage = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=folder))
    try:
        yield stage
        _swap(stage, folder)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
