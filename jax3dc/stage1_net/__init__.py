"""Stage 1 from one image: a small image network that writes a factory's category and parameters.

Image I -> category and that category's parameter entries (``jax3dc.parameters``): Numbers
regressed in their range, Counts / Chances / Choices classified, decoded into the one-line
parameter text that the factory runs into parts with clean ids (issue 49). Small enough to train on
two CPU cores in minutes and to ship beside the structure model within the package's 24 MiB (the
shipped network's size is in its model card, ``jax3dc/release/stage1/MODEL_CARD.md``); the
training recipe is ``recipes/stage1_net.py``. A folder holds ``stage1_net.json`` (config and the
schemas decoding needs) and ``model.safetensors``; ``load_reader(folder)`` gives ``image -> text``.
"""

from jax3dc.stage1_net.folder import (MARKER, Stage1Network, decode_parameters, decode_text, load_network, load_reader,
                                      normalised_number, save_network)
from jax3dc.stage1_net.image import ImageInputError, network_image
from jax3dc.stage1_net.layout import OutputLayout, schemas_from_json, schemas_to_json
from jax3dc.stage1_net.model import Stage1Net, Stage1NetConfig, forward

__all__ = [
    "MARKER", "ImageInputError", "OutputLayout", "Stage1Net", "Stage1NetConfig", "Stage1Network", "decode_parameters",
    "decode_text", "forward", "load_network", "load_reader", "network_image", "normalised_number", "save_network",
    "schemas_from_json", "schemas_to_json",
]
