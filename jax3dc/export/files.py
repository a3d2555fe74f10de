"""Writing an export: one main file plus the files it refers to, under one output directory."""

from __future__ import annotations

import re
from pathlib import Path

from jax3dc.errors import InputFileError

_SAFE_FILE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def check_file_stem(stem: str) -> str:
    """``stem`` if it is a plain file name (letters, digits, ``_.-``); it names the main file."""
    if not _SAFE_FILE_NAME.fullmatch(stem) or ".." in stem:
        raise ValueError(f"model name {stem!r} must be a plain file name of letters, digits, '_', '.', '-'")
    return stem


def write_files(out_dir: Path, main_name: str, main: str | bytes, files: dict[str, bytes]) -> Path:
    """Write ``main`` as ``out_dir/main_name`` and each of ``files`` at its relative path."""
    check_file_stem(main_name)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        for relative, data in sorted(files.items()):
            path = out_dir / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        main_path = out_dir / main_name
        if isinstance(main, str):
            main_path.write_text(main, encoding="utf-8")
        else:
            main_path.write_bytes(main)
    except OSError as e:
        raise InputFileError(out_dir, f"cannot write the export: {e.strerror or e}") from None
    return main_path
