"""The stage-1 image network: a small convolutional encoder and three heads.

Image I (square RGB, ``image_size`` px, values in [0, 1]) -> a feature vector -> category logits,
one normalised value per ``Number`` (0 = the entry's lo, 1 = its hi) and padded class logits per
discrete value; ``OutputLayout`` says which outputs belong to which category. Sized to train on two
CPU cores in minutes and to ship beside the structure model within the package's 24 MiB (the
shipped network's size: its model card).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import jax
import jax.numpy as jnp
from flax import nnx

from jax3dc.stage1_net.layout import OutputLayout


@dataclass(frozen=True)
class Stage1NetConfig:
    """Encoder shape and head sizes (the head sizes come from the layout of the schemas)."""

    categories: int
    numbers: int
    discrete: int
    max_classes: int
    image_size: int = 96
    widths: tuple[int, ...] = (32, 48, 96, 128)
    reduced: int = 48
    hidden: int = 192
    blocks: int = 1  # residual blocks per width: the first halves the map, the others keep it

    def __post_init__(self) -> None:
        if self.blocks < 1 or not self.widths:
            raise ValueError(f"a stage-1 network needs widths and at least one block per width, got "
                             f"widths={self.widths}, blocks={self.blocks}")

    @classmethod
    def for_layout(cls, layout: OutputLayout, **overrides: Any) -> "Stage1NetConfig":
        return cls(len(layout.categories), max(len(layout.numbers), 1), max(len(layout.discrete), 1),
                   layout.max_classes, **overrides)

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "widths": list(self.widths)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Stage1NetConfig":
        """A marker's config; one written before ``blocks`` existed had one block per width."""
        return cls(**{"blocks": 1, **data, "widths": tuple(data["widths"])})


class ConvBlock(nnx.Module):
    """Two 3x3 convolutions (the first strided) with group norm and a residual path."""

    def __init__(self, cin: int, cout: int, stride: int, rngs: nnx.Rngs):
        self.conv1 = nnx.Conv(cin, cout, (3, 3), strides=stride, padding="SAME", rngs=rngs)
        self.norm1 = nnx.GroupNorm(cout, num_groups=8, rngs=rngs)
        self.conv2 = nnx.Conv(cout, cout, (3, 3), padding="SAME", rngs=rngs)
        self.norm2 = nnx.GroupNorm(cout, num_groups=8, rngs=rngs)
        self.skip = nnx.Conv(cin, cout, (1, 1), strides=stride, rngs=rngs)

    def __call__(self, x: jax.Array) -> jax.Array:
        y = nnx.relu(self.norm1(self.conv1(x)))
        y = self.norm2(self.conv2(y))
        return nnx.relu(y + self.skip(x))


class Stage1Net(nnx.Module):
    """Image -> (category logits [B, C], numbers [B, N], discrete logits [B, D, K])."""

    def __init__(self, config: Stage1NetConfig, rngs: nnx.Rngs):
        self.config = config
        w = config.widths
        self.stem = nnx.Conv(3, w[0], (4, 4), strides=2, padding="SAME", rngs=rngs)
        # one flat list (blocks.0, blocks.1, ...): with one block per width the tensor names are
        # those of the folders written before ``blocks`` existed
        self.blocks = nnx.List([ConvBlock(a if k == 0 else b, b, 2 if k == 0 else 1, rngs)
                                for a, b in zip((w[0],) + w[:-1], w) for k in range(config.blocks)])
        # no global pooling: a drawer count or a door's hinge side is where things are, so the last
        # map is narrowed per position and read whole
        self.reduce = nnx.Conv(w[-1], config.reduced, (1, 1), rngs=rngs)
        side = config.image_size
        for _ in range(len(w) + 1):
            side = -(-side // 2)
        self.hidden = nnx.Linear(config.reduced * side * side, config.hidden, rngs=rngs)
        self.category = nnx.Linear(config.hidden, config.categories, rngs=rngs)
        self.numbers = nnx.Linear(config.hidden, config.numbers, rngs=rngs)
        self.discrete = nnx.Linear(config.hidden, config.discrete * config.max_classes, rngs=rngs)

    def __call__(self, images: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
        x = nnx.relu(self.stem(images * 2.0 - 1.0))
        for block in self.blocks:
            x = block(x)
        x = nnx.relu(self.reduce(x))
        h = nnx.relu(self.hidden(x.reshape(x.shape[0], -1)))
        cfg = self.config
        return (self.category(h), self.numbers(h) + 0.5,
                self.discrete(h).reshape(h.shape[0], cfg.discrete, cfg.max_classes))


def forward(model: Stage1Net, images: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The jitted call the reader and evaluation share (float32 images in [0, 1], [B, H, W, 3])."""
    return _forward(model, jnp.asarray(images, jnp.float32))


@nnx.jit
def _forward(model: Stage1Net, images: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    return model(images)
