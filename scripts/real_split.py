"""The fixed held-out fifth of the real training pool, by object and stratified by category.

Real-object figures count only on objects never trained on (``shared/real_train/README.md``). Each
PartNet-Mobility category (``meta.json``'s ``model_cat``) gives ``round(n / 5)`` of its ``n`` objects
to the held-out set, the first ones in the order of SHA-256 of the folder name, so the split is the
same on every machine, never depends on a view or variant, and a category of one or two objects
stays in training (it cannot be held out and still be learned).

    python3 scripts/real_split.py ../shared/real_train/partnet_mobility --print heldout
"""

from __future__ import annotations

import argparse
import hashlib
import json
from collections import defaultdict
from pathlib import Path

HELDOUT_SHARE = 0.2


def category_of(folder: Path) -> str:
    """The object's PartNet-Mobility category (``meta.json``'s model_cat); the folder prefix if absent."""
    meta = folder / "meta.json"
    if meta.is_file():
        cat = json.loads(meta.read_text()).get("model_cat")
        if isinstance(cat, str) and cat:
            return cat
    return folder.name.rsplit("_", 1)[0]


def split_pool(pool: Path) -> dict[str, list[Path]]:
    """{"train": [...], "heldout": [...]} of the pool's object folders, each list sorted by name."""
    by_category: dict[str, list[Path]] = defaultdict(list)
    for folder in sorted(p for p in pool.iterdir() if (p / "mobility.urdf").is_file()):
        by_category[category_of(folder)].append(folder)
    out: dict[str, list[Path]] = {"train": [], "heldout": []}
    for folders in by_category.values():
        ranked = sorted(folders, key=lambda p: hashlib.sha256(p.name.encode()).hexdigest())
        k = round(len(ranked) * HELDOUT_SHARE)
        out["heldout"] += ranked[:k]
        out["train"] += ranked[k:]
    return {name: sorted(v) for name, v in out.items()}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("pool", type=Path, help="folder of PartNet-Mobility object folders")
    p.add_argument("--print", choices=("train", "heldout"), required=True, help="list this part's folders, one a line")
    a = p.parse_args()
    print("\n".join(str(f) for f in split_pool(a.pool)[a.print]))


if __name__ == "__main__":
    main()
