"""Stage 1 for any image (issue 64): a network that writes the object's parts as slots, no category.

Image I -> K slots, each an exists logit, a box in the object's normalised frame, a generic kind
(``kinds.KINDS``) and a parent pointer (``model``); ``decode`` keeps the slots that exist and makes
their pointers a forest; a folder (``folder``: ``slots_net.json`` + ``model.safetensors`` +
``MODEL_CARD.md``) carries a trained network. The training recipe is ``recipes/stage1_slots.py``;
predict reads it as ``--stage1 slots --slots-model DIR``.
"""

from jax3dc.stage1_slots.decode import PartSlot, decode_slots
from jax3dc.stage1_slots.folder import MARKER, SlotsNetwork, load_slots, load_slots_reader, save_slots
from jax3dc.stage1_slots.kinds import KINDS, kind_index, kind_of
from jax3dc.stage1_slots.model import SlotOutputs, SlotsNet, SlotsNetConfig, forward

__all__ = ["KINDS", "MARKER", "PartSlot", "SlotOutputs", "SlotsNet", "SlotsNetConfig", "SlotsNetwork", "decode_slots",
           "forward", "kind_index", "kind_of", "load_slots", "load_slots_reader", "save_slots"]
