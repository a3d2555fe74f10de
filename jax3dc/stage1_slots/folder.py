"""A slots-network folder: ``slots_net.json`` (format, config, kinds, notes), ``model.safetensors``
(float16 weights) and ``MODEL_CARD.md``; ``load_slots`` gives a reader from image to part slots.

The kinds travel with the weights, so a folder trained on another vocabulary is refused rather than
read with the wrong names. Loading is strict, as the stage-1 network's is: a missing, unexpected or
misshapen tensor raises InputFileError naming the file and the tensor.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from flax import nnx

from jax3dc.errors import InputFileError
from jax3dc.nnx_weights import load_params, save_params
from jax3dc.stage1_net.image import network_image
from jax3dc.stage1_slots.decode import PartSlot, decode_slots
from jax3dc.stage1_slots.kinds import KINDS
from jax3dc.stage1_slots.model import SlotsNet, SlotsNetConfig, forward

MARKER = "slots_net.json"
WEIGHTS = "model.safetensors"
CARD = "MODEL_CARD.md"
FORMAT = "jax3dc-stage1-slots/1"


@dataclass(frozen=True)
class SlotsNetwork:
    """A loaded slots network and the exists probability a slot needs to be kept."""

    model: SlotsNet
    threshold: float = 0.5

    def read(self, images: np.ndarray) -> list[list[PartSlot]]:
        """The part slots of a batch of network images ([B, size, size, 3] floats in [0, 1])."""
        outputs = [np.asarray(x) for x in forward(self.model, images)]
        return [decode_slots(*(x[i] for x in outputs), threshold=self.threshold) for i in range(len(images))]


def _card(model: SlotsNet, notes: dict, weights_bytes: int) -> str:
    c = model.config
    lines = [
        "# Slots network (stage 1, open-world parts)", "",
        "Reads one image and writes up to K part slots: exists probability, a box in the object's normalised "
        "frame (centre, extent; largest extent 1), a generic kind and a parent pointer. `jax3dc predict IMAGE "
        "--stage1 slots --slots-model DIR` turns the kept slots into box parts for stage 2.", "",
        f"- slots K: {c.slots}; image: {c.image_size} px; encoder widths {list(c.widths)} x {c.blocks} blocks; "
        f"decoder {c.layers} layers of width {c.dim}, {c.heads} heads",
        f"- kinds: {', '.join(KINDS)}",
        f"- weights: {weights_bytes / 2**20:.2f} MiB (float16)",
    ]
    lines += [f"- {key}: {value}" for key, value in notes.items()]
    return "\n".join(lines) + "\n"


def save_slots(folder: str | Path, model: SlotsNet, notes: dict | None = None) -> Path:
    """Writes the folder (created if needed); ``notes`` (the recipe, the data, the scores) go into the
    marker and the model card."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    save_params(model, folder / WEIGHTS)
    marker = {"format": FORMAT, "config": model.config.to_json(), "kinds": list(KINDS), "weights": WEIGHTS,
              **({"notes": notes} if notes else {})}
    (folder / MARKER).write_text(json.dumps(marker, indent=1) + "\n", encoding="utf-8")
    (folder / CARD).write_text(_card(model, notes or {}, (folder / WEIGHTS).stat().st_size), encoding="utf-8")
    return folder


def _read_marker(folder: Path) -> dict:
    path = folder / MARKER
    if not folder.is_dir():
        raise InputFileError(str(folder), f"not a folder (expected a slots-network folder holding {MARKER})")
    if not path.is_file():
        raise InputFileError(str(path), "missing: not a slots-network folder")
    try:
        marker = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as e:
        raise InputFileError(str(path), f"not valid JSON ({e})") from None
    if not isinstance(marker, dict) or marker.get("format") != FORMAT:
        raise InputFileError(str(path), f"format is not {FORMAT!r}")
    if marker.get("kinds") != list(KINDS):
        raise InputFileError(str(path), f"its kinds {marker.get('kinds')} are not this version's {list(KINDS)}")
    return marker


def load_slots(folder: str | Path, threshold: float = 0.5) -> SlotsNetwork:
    """The network a ``save_slots`` folder holds; see the module docstring for the errors."""
    folder = Path(folder)
    marker = _read_marker(folder)
    try:
        config = SlotsNetConfig.from_json(marker["config"])
    except (KeyError, TypeError, ValueError) as e:
        raise InputFileError(str(folder / MARKER), f"bad config ({e})") from None
    weights = folder / str(marker.get("weights", WEIGHTS))
    model = load_params(nnx.eval_shape(lambda: SlotsNet(config, nnx.Rngs(0))), weights)
    return SlotsNetwork(model, threshold)


def load_slots_reader(folder: str | Path, threshold: float = 0.5) -> Callable[[np.ndarray], list[PartSlot]]:
    """A function from an RGB uint8 image (any size, HxWx3) to its part slots; a bad image raises
    ImageInputError (jax3dc.stage1_net.image)."""
    network = load_slots(folder, threshold)
    size = network.model.config.image_size

    def read(image: np.ndarray) -> list[PartSlot]:
        return network.read(network_image(image, size)[None])[0]

    return read
