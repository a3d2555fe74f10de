"""Many images, one run: `jax3dc predict IMG [IMG ...] --out DIR` and `jax3dc predict FOLDER --out DIR`.

The models load once (one ``Checkpoints`` serves every ``predict``). Each image gets its own
folder in DIR, named from its file name (``folder_name``: letters, digits, ``. _ -``; never a
path, a hidden name or markup), and DIR/index.html shows them all (``jax3dc.predict.gallery``),
rewritten after each image so a long run can be watched.

A run can be killed and run again: an image whose folder holds ``done.json`` for the same input
bytes is skipped (its card shows the folder as it is now, edits by hand included). done.json is written last, after every output of the prediction, so a folder
without it is a prediction cut short, which is removed and done again. An image whose prediction
fails has no done.json: the gallery shows its error (and its report, when stage 1 gave parts),
and the next run tries it again, since the cause may be outside the image (a model folder, a flag).
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from jax3dc.errors import InputFileError, Jax3dcError
from jax3dc.predict.gallery import ERROR, FAILS, GALLERY_FILE, PASSES, WAITING, Card, write_gallery
from jax3dc.predict.pipeline import Checkpoints, PredictConfig, predict

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".webp", ".bmp", ".gif", ".tif", ".tiff")
DONE_FILE = "done.json"
MAX_NAME = 64  # characters of a folder name
RESERVED = {GALLERY_FILE.lower()}
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def batch_images(paths: Sequence[str | Path]) -> list[Path]:
    """The images of ``paths`` in order: a file as given, a folder's image files (by suffix, not
    its subfolders) sorted by name. A missing path, or a folder with no image, stops the run before
    any model loads."""
    images: list[Path] = []
    for path in map(Path, paths):
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)
            if not found:
                raise InputFileError(path, f"no image files ({' '.join(IMAGE_SUFFIXES)}) in the folder")
            images += found
        elif path.is_file():
            images.append(path)
        else:
            raise InputFileError(path, "not found")
    return images


def folder_name(filename: str) -> str:
    """A safe folder name from a file name, which may come from anywhere (an upload): its last path
    component without the suffix, every run of other characters than letters, digits, ``. _ -`` made
    one ``_``, no leading or trailing ``. _ -`` (no ``..``, no hidden folder), at most MAX_NAME
    characters; "image" when nothing is left."""
    base = re.split(r"[\\/]", filename)[-1]
    stem, dot, _suffix = base.rpartition(".")
    name = _UNSAFE.sub("_", stem if dot and stem else base).strip("._-")
    return name[:MAX_NAME].rstrip("._-") or "image"


def folder_names(images: Sequence[Path]) -> list[str]:
    """``folder_name`` of each image, made unique (``-2``, ``-3``, ... in input order, ignoring case
    for file systems that do) and never the gallery's own file name."""
    taken: set[str] = set(RESERVED)
    names = []
    for image in images:
        base = folder_name(image.name)
        name, k = base, 1
        while name.lower() in taken:
            k += 1
            name = f"{base}-{k}"
        taken.add(name.lower())
        names.append(name)
    return names


@dataclass(frozen=True)
class BatchItem:
    """What happened to one image of the batch."""

    image: Path
    folder: Path
    card: Card
    skipped: bool = False  # done by an earlier run


def image_digest(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as e:
        raise InputFileError(path, f"cannot read: {e.strerror or e}") from None


def _card(folder: Path, image: str) -> Card:
    """A completed folder's card from its files as they are now (an edit by hand, jax3dc.edits, may
    have changed its joints and verdict since it was predicted)."""
    nodes = json.loads((folder / "structure.json").read_text(encoding="utf-8"))["nodes"]
    ok = json.loads((folder / "physics.json").read_text(encoding="utf-8"))["ok"]
    joints = sum("joint" in node for node in nodes.values())
    return Card(folder.name, image, PASSES if ok else FAILS, f"{len(nodes)} parts, {joints} joints")


def done_card(folder: Path, digest: str | None = None) -> Card | None:
    """The card of a folder an earlier run completed (for these input bytes, when ``digest`` is
    given), else None; `jax3dc serve` shows the folders it finds done in its --out as done jobs."""
    try:
        done = json.loads((folder / DONE_FILE).read_text(encoding="utf-8"))
        return _card(folder, str(done["image"])) if digest is None or done["image_sha256"] == digest else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def predict_one(image: Path, name: str, digest: str, config: PredictConfig, out: Path,
                checkpoints: Checkpoints) -> Card:
    """Predicts ``image`` (of sha256 ``digest``) into ``out``/``name`` from scratch and writes
    done.json last; its card, with the error when it failed. The batch and `jax3dc serve`'s worker
    predict each image through it."""
    folder = out / name
    if folder.exists():
        shutil.rmtree(folder)  # a prediction cut short, or of other input bytes: done again from scratch
    try:
        predict(image, config, folder, checkpoints=checkpoints)
    except Jax3dcError as e:
        return Card(name, image.name, ERROR, str(e))
    done = {"image": image.name, "image_sha256": digest}
    (folder / DONE_FILE).write_text(json.dumps(done, indent=1) + "\n", encoding="utf-8")
    return _card(folder, image.name)


def predict_batch(images: Sequence[Path], config: PredictConfig, out: str | Path,
                  checkpoints: Checkpoints | None = None, progress: bool = False,
                  on_item: Callable[[BatchItem], None] | None = None) -> list[BatchItem]:
    """Predicts each of ``images`` (``batch_images``) into its folder of ``out`` with the models
    loaded once, skipping those an earlier run completed, and keeps ``out``/index.html current
    (module docstring). ``progress``: a bar on stderr when it is a terminal; ``on_item`` is told
    each image's outcome as it is known (the CLI prints it)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    checkpoints = checkpoints if checkpoints is not None else Checkpoints(config.decoding.dtype)
    names = folder_names(images)
    cards = [Card(name, image.name, WAITING) for image, name in zip(images, names)]
    items = []
    write_gallery(cards, out)
    bar = tqdm(total=len(images), desc="predict", unit="image", disable=None if progress else True)
    try:
        for k, (image, name) in enumerate(zip(images, names)):
            bar.set_postfix_str(name)
            digest = image_digest(image)
            done = done_card(out / name, digest)
            cards[k] = done or predict_one(image, name, digest, config, out, checkpoints)
            item = BatchItem(image, out / name, cards[k], skipped=done is not None)
            items.append(item)
            write_gallery(cards, out)
            if on_item is not None:
                on_item(item)
            bar.update()
    finally:
        bar.close()
    return items
