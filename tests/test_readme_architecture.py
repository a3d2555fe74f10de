"""The README's architecture section lists the path from `jax3dc predict` to `object.xml`: at
most 20 files, numbered in order, each one that exists in the core."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SECTION = "## Architecture: from `jax3dc predict` to `object.xml`"


def listed_files(readme: str) -> list[tuple[int, str]]:
    """(number, path) of the section's numbered list items."""
    section = readme[readme.index(SECTION):]
    section = section[:section.find("\n## ", 1)] if "\n## " in section[1:] else section
    return [(int(n), path) for n, path in re.findall(r"^(\d+)\. `([^`]+)`", section, re.M)]


def test_the_path_is_at_most_twenty_core_files_in_order():
    items = listed_files((ROOT / "README.md").read_text(encoding="utf-8"))
    assert 1 <= len(items) <= 20
    assert [n for n, _ in items] == list(range(1, len(items) + 1))
    paths = [p for _, p in items]
    assert len(set(paths)) == len(paths)
    for path in paths:
        assert path.startswith("jax3dc/") and (ROOT / path).is_file(), path


def test_the_check_reads_a_list():
    text = f"{SECTION}\n\n1. `jax3dc/cli.py` — a\n2. `jax3dc/nope.py` — b\n\n## Next\n3. `x`\n"
    assert listed_files(text) == [(1, "jax3dc/cli.py"), (2, "jax3dc/nope.py")]
