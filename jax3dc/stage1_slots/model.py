"""The slots network: image I -> K part slots, each a part the object may have.

The encoder is the stage-1 image network's (``jax3dc.stage1_net.model.ConvBlock`` stacks, the same
preprocessing), so the two read pixels alike. Its last feature map becomes tokens (with a learned
position each) and K learned slot queries read them in a small transformer decoder: cross-attention
to the image, then self-attention among the slots (so two slots can agree not to write the same
part), then an MLP. Each slot's heads give

* ``exists``: one logit, the slot holds a part;
* ``boxes``: centre (3, in [-0.5, 0.5]) and extent (3, in [0, 1]) in the object's normalised frame
  (bounding box centred, largest extent 1), the frame and units of a record's ``meta["boxes"]``;
* ``kinds``: logits over ``jax3dc.stage1_slots.kinds.KINDS``;
* ``parents``: logits over the K slots (its own masked out) and, last, "root": a bilinear score of
  the slot's query against every other slot's key, so the pointer follows slots, not positions.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from flax import nnx

from jax3dc.stage1_net.model import ConvBlock
from jax3dc.stage1_slots.kinds import KINDS


@dataclass(frozen=True)
class SlotsNetConfig:
    """Encoder shape, decoder width and slot count; ``tiny()`` is the CPU smoke-test size."""

    slots: int = 24
    kinds: int = len(KINDS)
    image_size: int = 128
    widths: tuple[int, ...] = (32, 64, 128, 192)
    blocks: int = 2  # residual blocks per width: the first halves the map, the others keep it
    dim: int = 192  # slot and token width
    heads: int = 6
    layers: int = 3  # decoder layers (cross-attention, self-attention, MLP)

    def __post_init__(self) -> None:
        if self.slots < 1 or self.blocks < 1 or not self.widths or self.dim % self.heads:
            raise ValueError(f"a slots network needs slots >= 1, widths, blocks >= 1 and dim divisible by heads, "
                             f"got slots={self.slots}, widths={self.widths}, blocks={self.blocks}, "
                             f"dim={self.dim}, heads={self.heads}")

    @classmethod
    def tiny(cls, slots: int = 8) -> "SlotsNetConfig":
        """Small enough to train a few steps on two CPU cores in seconds (tests, smoke runs)."""
        return cls(slots=slots, image_size=32, widths=(8, 16), blocks=1, dim=32, heads=2, layers=1)

    @property
    def side(self) -> int:
        """Side of the token map: the stem and each width halve the image."""
        side = self.image_size
        for _ in range(len(self.widths) + 1):
            side = -(-side // 2)
        return side

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "widths": list(self.widths)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "SlotsNetConfig":
        return cls(**{**data, "widths": tuple(data["widths"])})


class SlotOutputs(NamedTuple):
    """A batch of slots: exists [B, K], boxes [B, K, 6] (centre, extent), kinds [B, K, kinds],
    parents [B, K, K + 1] (the last column is "root")."""

    exists: jax.Array
    boxes: jax.Array
    kinds: jax.Array
    parents: jax.Array


class DecoderLayer(nnx.Module):
    """Slots read the image tokens, then each other, then think alone (pre-norm residuals)."""

    def __init__(self, dim: int, heads: int, rngs: nnx.Rngs):
        self.norm_cross = nnx.LayerNorm(dim, rngs=rngs)
        self.cross = nnx.MultiHeadAttention(heads, dim, decode=False, keep_rngs=False, rngs=rngs)
        self.norm_self = nnx.LayerNorm(dim, rngs=rngs)
        self.attend = nnx.MultiHeadAttention(heads, dim, decode=False, keep_rngs=False, rngs=rngs)
        self.norm_mlp = nnx.LayerNorm(dim, rngs=rngs)
        self.up = nnx.Linear(dim, 2 * dim, rngs=rngs)
        self.down = nnx.Linear(2 * dim, dim, rngs=rngs)

    def __call__(self, slots: jax.Array, tokens: jax.Array) -> jax.Array:
        slots = slots + self.cross(self.norm_cross(slots), tokens, tokens)
        x = self.norm_self(slots)
        slots = slots + self.attend(x, x, x)
        return slots + self.down(nnx.gelu(self.up(self.norm_mlp(slots))))


class SlotsNet(nnx.Module):
    """Image [B, S, S, 3] in [0, 1] -> SlotOutputs."""

    def __init__(self, config: SlotsNetConfig, rngs: nnx.Rngs):
        self.config = config
        w = config.widths
        self.stem = nnx.Conv(3, w[0], (4, 4), strides=2, padding="SAME", rngs=rngs)
        self.blocks = nnx.List([ConvBlock(a if k == 0 else b, b, 2 if k == 0 else 1, rngs)
                                for a, b in zip((w[0],) + w[:-1], w) for k in range(config.blocks)])
        self.tokens = nnx.Linear(w[-1], config.dim, rngs=rngs)
        self.position = nnx.Param(jax.random.normal(rngs.params(), (config.side * config.side, config.dim)) * 0.02)
        self.queries = nnx.Param(jax.random.normal(rngs.params(), (config.slots, config.dim)) * 0.02)
        self.layers = nnx.List([DecoderLayer(config.dim, config.heads, rngs) for _ in range(config.layers)])
        self.norm = nnx.LayerNorm(config.dim, rngs=rngs)
        self.exists = nnx.Linear(config.dim, 1, rngs=rngs)
        self.box = nnx.Linear(config.dim, 6, rngs=rngs)
        self.kind = nnx.Linear(config.dim, config.kinds, rngs=rngs)
        self.parent_query = nnx.Linear(config.dim, config.dim, rngs=rngs)
        self.parent_key = nnx.Linear(config.dim, config.dim, rngs=rngs)
        self.root = nnx.Linear(config.dim, 1, rngs=rngs)

    def __call__(self, images: jax.Array) -> SlotOutputs:
        x = nnx.relu(self.stem(images * 2.0 - 1.0))
        for block in self.blocks:
            x = block(x)
        b = x.shape[0]
        tokens = self.tokens(x.reshape(b, -1, x.shape[-1])) + self.position[...][None]
        slots = jnp.broadcast_to(self.queries[...][None], (b, *self.queries.shape))
        for layer in self.layers:
            slots = layer(slots, tokens)
        slots = self.norm(slots)
        raw = self.box(slots)
        boxes = jnp.concatenate([0.5 * jnp.tanh(raw[..., :3]), nnx.sigmoid(raw[..., 3:] - 1.0)], axis=-1)
        k = self.config.slots
        scores = jnp.einsum("bid,bjd->bij", self.parent_query(slots), self.parent_key(slots)) / jnp.sqrt(
            float(self.config.dim))
        scores = jnp.where(jnp.eye(k, dtype=bool)[None], -1e9, scores)
        parents = jnp.concatenate([scores, self.root(slots)], axis=-1)
        return SlotOutputs(self.exists(slots)[..., 0], boxes, self.kind(slots), parents)


def forward(model: SlotsNet, images: jax.Array) -> SlotOutputs:
    """The jitted call the reader and evaluation share (float32 images in [0, 1], [B, H, W, 3])."""
    return _forward(model, jnp.asarray(images, jnp.float32))


@nnx.jit
def _forward(model: SlotsNet, images: jax.Array) -> SlotOutputs:
    return model(images)
