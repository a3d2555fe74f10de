"""Qwen3-VL configuration: frozen dataclasses, named presets, and the Hugging Face config.json mapping.

The field names follow transformers' ``Qwen3VLConfig`` so that a reader can hold the two side by
side; only what changes the computation is kept (dropout, initializer range and the like are not).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from jax3dc.errors import InputFileError

IMAGE_TOKEN_ID = 151655
VIDEO_TOKEN_ID = 151656
VISION_START_TOKEN_ID = 151652
VISION_END_TOKEN_ID = 151653
QWEN_VOCAB_SIZE = 151936


@dataclass(frozen=True)
class VisionConfig:
    """The ViT that turns patches into LLM-width tokens (one per ``spatial_merge_size**2`` patches)."""

    depth: int = 24
    hidden_size: int = 1024
    intermediate_size: int = 4096
    num_heads: int = 16
    out_hidden_size: int = 2560
    in_channels: int = 3
    patch_size: int = 16
    temporal_patch_size: int = 2
    spatial_merge_size: int = 2
    num_position_embeddings: int = 2304
    deepstack_visual_indexes: tuple[int, ...] = (5, 11, 17)
    hidden_act: str = "gelu_pytorch_tanh"
    rope_theta: float = 10000.0

    def __post_init__(self):
        side = math.isqrt(self.num_position_embeddings)
        if side * side != self.num_position_embeddings:
            raise ValueError(f"num_position_embeddings must be a perfect square, got {self.num_position_embeddings}")
        if self.hidden_size % self.num_heads:
            raise ValueError("vision hidden_size must be a multiple of num_heads")
        if any(not 0 <= i < self.depth for i in self.deepstack_visual_indexes):
            raise ValueError(f"deepstack_visual_indexes {self.deepstack_visual_indexes} outside depth {self.depth}")

    @property
    def head_dim(self) -> int:
        return self.hidden_size // self.num_heads

    @property
    def patch_dim(self) -> int:
        """Length of one flattened patch row of ``pixel_values`` (C * T * P * P)."""
        return self.in_channels * self.temporal_patch_size * self.patch_size**2

    @property
    def num_grid_per_side(self) -> int:
        return math.isqrt(self.num_position_embeddings)


@dataclass(frozen=True)
class TextConfig:
    """The Qwen3 decoder: GQA with per-head RMSNorm on q and k, SwiGLU MLP, interleaved M-RoPE."""

    vocab_size: int = QWEN_VOCAB_SIZE
    hidden_size: int = 2560
    intermediate_size: int = 9728
    num_hidden_layers: int = 36
    num_attention_heads: int = 32
    num_key_value_heads: int = 8
    head_dim: int = 128
    rms_norm_eps: float = 1e-6
    rope_theta: float = 5_000_000.0
    mrope_section: tuple[int, int, int] = (24, 20, 20)
    max_position_embeddings: int = 262144
    attention_bias: bool = False
    hidden_act: str = "silu"

    def __post_init__(self):
        if sum(self.mrope_section) != self.head_dim // 2:
            raise ValueError(f"mrope_section {self.mrope_section} must sum to head_dim/2 = {self.head_dim // 2}")
        if self.num_attention_heads % self.num_key_value_heads:
            raise ValueError("num_attention_heads must be a multiple of num_key_value_heads")


@dataclass(frozen=True)
class Qwen3VLConfig:
    """The whole model: vision tower, text decoder and the special token ids that join them."""

    vision: VisionConfig = field(default_factory=VisionConfig)
    text: TextConfig = field(default_factory=TextConfig)
    tie_word_embeddings: bool = True
    image_token_id: int = IMAGE_TOKEN_ID
    video_token_id: int = VIDEO_TOKEN_ID
    vision_start_token_id: int = VISION_START_TOKEN_ID
    vision_end_token_id: int = VISION_END_TOKEN_ID

    def __post_init__(self):
        if self.vision.out_hidden_size != self.text.hidden_size:
            raise ValueError("vision.out_hidden_size must equal text.hidden_size")
        if len(self.vision.deepstack_visual_indexes) > self.text.num_hidden_layers:
            raise ValueError("more DeepStack features than decoder layers")

    # ------------------------------------------------------------------ presets
    @classmethod
    def qwen3_vl_2b(cls) -> Qwen3VLConfig:
        return cls(
            vision=VisionConfig(depth=24, hidden_size=1024, intermediate_size=4096, num_heads=16,
                                out_hidden_size=2048, deepstack_visual_indexes=(5, 11, 17)),
            text=TextConfig(hidden_size=2048, intermediate_size=6144, num_hidden_layers=28,
                            num_attention_heads=16, num_key_value_heads=8, head_dim=128),
            tie_word_embeddings=True)

    @classmethod
    def qwen3_vl_4b(cls) -> Qwen3VLConfig:
        return cls(
            vision=VisionConfig(depth=24, hidden_size=1024, intermediate_size=4096, num_heads=16,
                                out_hidden_size=2560, deepstack_visual_indexes=(5, 11, 17)),
            text=TextConfig(hidden_size=2560, intermediate_size=9728, num_hidden_layers=36,
                            num_attention_heads=32, num_key_value_heads=8, head_dim=128),
            tie_word_embeddings=True)

    @classmethod
    def qwen3_vl_8b(cls) -> Qwen3VLConfig:
        return cls(
            vision=VisionConfig(depth=27, hidden_size=1152, intermediate_size=4304, num_heads=16,
                                out_hidden_size=4096, deepstack_visual_indexes=(8, 16, 24)),
            text=TextConfig(hidden_size=4096, intermediate_size=12288, num_hidden_layers=36,
                            num_attention_heads=32, num_key_value_heads=8, head_dim=128),
            tie_word_embeddings=False)

    @classmethod
    def small(cls, vocab_size: int = QWEN_VOCAB_SIZE) -> Qwen3VLConfig:
        """About 110 M parameters with the real Qwen vocabulary: for training from scratch on one GPU."""
        return cls(
            vision=VisionConfig(depth=6, hidden_size=384, intermediate_size=1536, num_heads=6,
                                out_hidden_size=512, num_position_embeddings=1024,
                                deepstack_visual_indexes=(1, 3)),
            text=TextConfig(vocab_size=vocab_size, hidden_size=512, intermediate_size=1536,
                            num_hidden_layers=8, num_attention_heads=8, num_key_value_heads=4,
                            head_dim=64, mrope_section=(12, 10, 10)),
            tie_word_embeddings=True)

    @classmethod
    def release(cls, vocab_size: int = 2048) -> Qwen3VLConfig:
        """The shipped default model: about 12 M parameters with a 2k BPE, so its bf16 weights
        stay under the 24 MiB the package may carry (SPEC §7). One KV head and a thin vision
        tower: the legend already gives every part's box, so the image mostly has to tell
        which part is which."""
        return cls(
            vision=VisionConfig(depth=4, hidden_size=192, intermediate_size=768, num_heads=3,
                                out_hidden_size=320, num_position_embeddings=256,
                                deepstack_visual_indexes=(1, 3)),
            text=TextConfig(vocab_size=vocab_size, hidden_size=320, intermediate_size=960,
                            num_hidden_layers=6, num_attention_heads=5, num_key_value_heads=1,
                            head_dim=64, mrope_section=(12, 10, 10)),
            tie_word_embeddings=True)

    @classmethod
    def mini(cls, vocab_size: int = 2048) -> Qwen3VLConfig:
        """About a third of ``release`` (4 decoder layers of 192): the small end of the size sweep
        (eval/evaluators/size_sweep.py) that chose the release size."""
        return cls(
            vision=VisionConfig(depth=2, hidden_size=128, intermediate_size=512, num_heads=2,
                                out_hidden_size=192, num_position_embeddings=256,
                                deepstack_visual_indexes=(0, 1)),
            text=TextConfig(vocab_size=vocab_size, hidden_size=192, intermediate_size=576,
                            num_hidden_layers=4, num_attention_heads=3, num_key_value_heads=1,
                            head_dim=64, mrope_section=(12, 10, 10)),
            tie_word_embeddings=True)

    @classmethod
    def tiny(cls, vocab_size: int = 128, tie_word_embeddings: bool = False) -> Qwen3VLConfig:
        """A few thousand parameters for tests. Special tokens sit inside the small vocabulary."""
        return cls(
            vision=VisionConfig(depth=3, hidden_size=32, intermediate_size=48, num_heads=2,
                                out_hidden_size=48, patch_size=4, num_position_embeddings=36,
                                deepstack_visual_indexes=(0, 2)),
            text=TextConfig(vocab_size=vocab_size, hidden_size=48, intermediate_size=64,
                            num_hidden_layers=3, num_attention_heads=4, num_key_value_heads=2,
                            head_dim=16, rope_theta=10000.0, mrope_section=(4, 2, 2),
                            max_position_embeddings=4096),
            tie_word_embeddings=tie_word_embeddings,
            image_token_id=vocab_size - 3, video_token_id=vocab_size - 2,
            vision_start_token_id=vocab_size - 5, vision_end_token_id=vocab_size - 4)

    # ------------------------------------------------------------------ Hugging Face config.json
    @classmethod
    def from_hf_dict(cls, d: dict[str, Any]) -> Qwen3VLConfig:
        """Reads a transformers ``Qwen3VLConfig`` dict (both the ``rope_parameters`` layout of
        transformers 5 and the ``rope_scaling`` + ``rope_theta`` layout of released checkpoints)."""
        if d.get("model_type") not in (None, "qwen3_vl"):
            raise InputFileError("config.json", f"model_type {d.get('model_type')!r} is not qwen3_vl")
        try:
            v, t = d["vision_config"], d["text_config"]
        except KeyError as e:
            raise InputFileError("config.json", f"missing {e.args[0]}") from None
        v_rope = v.get("rope_parameters") or {}
        t_rope = dict(t.get("rope_scaling") or {})
        t_rope.update(t.get("rope_parameters") or {})
        rope_type = t_rope.get("rope_type", t_rope.get("type", "default"))
        if rope_type != "default":
            raise InputFileError("config.json", f"text rope_type {rope_type!r} is not supported (only 'default')")
        if t_rope.get("mrope_interleaved", True) is False:
            raise InputFileError("config.json", "mrope_interleaved false (Qwen2-VL style) is not supported")
        if t.get("hidden_act", "silu") != "silu":
            raise InputFileError("config.json", f"text hidden_act {t['hidden_act']!r} is not supported")
        tie = d.get("tie_word_embeddings", t.get("tie_word_embeddings", False))
        vision = VisionConfig(
            depth=v["depth"], hidden_size=v["hidden_size"], intermediate_size=v["intermediate_size"],
            num_heads=v["num_heads"], out_hidden_size=v["out_hidden_size"],
            in_channels=v.get("in_channels", 3), patch_size=v["patch_size"],
            temporal_patch_size=v.get("temporal_patch_size", 2),
            spatial_merge_size=v.get("spatial_merge_size", 2),
            num_position_embeddings=v.get("num_position_embeddings", 2304),
            deepstack_visual_indexes=tuple(v.get("deepstack_visual_indexes", (8, 16, 24))),
            hidden_act=v.get("hidden_act", "gelu_pytorch_tanh"),
            rope_theta=float(v_rope.get("rope_theta", 10000.0)))
        text = TextConfig(
            vocab_size=t["vocab_size"], hidden_size=t["hidden_size"],
            intermediate_size=t["intermediate_size"], num_hidden_layers=t["num_hidden_layers"],
            num_attention_heads=t["num_attention_heads"],
            num_key_value_heads=t.get("num_key_value_heads") or t["num_attention_heads"],
            head_dim=t.get("head_dim") or t["hidden_size"] // t["num_attention_heads"],
            rms_norm_eps=t.get("rms_norm_eps", 1e-6),
            rope_theta=float(t_rope.get("rope_theta", t.get("rope_theta", 500000.0))),
            mrope_section=tuple(t_rope.get("mrope_section", (24, 20, 20))),
            max_position_embeddings=t.get("max_position_embeddings", 128000),
            attention_bias=t.get("attention_bias", False))
        return cls(vision=vision, text=text, tie_word_embeddings=bool(tie),
                   image_token_id=d.get("image_token_id", IMAGE_TOKEN_ID),
                   video_token_id=d.get("video_token_id", VIDEO_TOKEN_ID),
                   vision_start_token_id=d.get("vision_start_token_id", VISION_START_TOKEN_ID),
                   vision_end_token_id=d.get("vision_end_token_id", VISION_END_TOKEN_ID))

    def to_hf_dict(self, dtype: str = "float32") -> dict[str, Any]:
        """The config.json that transformers' ``Qwen3VLForConditionalGeneration`` loads."""
        v, t = self.vision, self.text
        return {
            "architectures": ["Qwen3VLForConditionalGeneration"],
            "model_type": "qwen3_vl",
            "dtype": dtype,
            "image_token_id": self.image_token_id,
            "video_token_id": self.video_token_id,
            "vision_start_token_id": self.vision_start_token_id,
            "vision_end_token_id": self.vision_end_token_id,
            "tie_word_embeddings": self.tie_word_embeddings,
            "text_config": {
                "model_type": "qwen3_vl_text",
                "vocab_size": t.vocab_size, "hidden_size": t.hidden_size,
                "intermediate_size": t.intermediate_size, "num_hidden_layers": t.num_hidden_layers,
                "num_attention_heads": t.num_attention_heads,
                "num_key_value_heads": t.num_key_value_heads, "head_dim": t.head_dim,
                "hidden_act": t.hidden_act, "rms_norm_eps": t.rms_norm_eps,
                "max_position_embeddings": t.max_position_embeddings,
                "attention_bias": t.attention_bias, "tie_word_embeddings": self.tie_word_embeddings,
                "rope_parameters": {"rope_type": "default", "rope_theta": t.rope_theta,
                                    "mrope_section": list(t.mrope_section), "mrope_interleaved": True},
            },
            "vision_config": {
                "model_type": "qwen3_vl_vision",
                "depth": v.depth, "hidden_size": v.hidden_size, "intermediate_size": v.intermediate_size,
                "num_heads": v.num_heads, "out_hidden_size": v.out_hidden_size,
                "in_channels": v.in_channels, "patch_size": v.patch_size,
                "temporal_patch_size": v.temporal_patch_size,
                "spatial_merge_size": v.spatial_merge_size,
                "num_position_embeddings": v.num_position_embeddings,
                "deepstack_visual_indexes": list(v.deepstack_visual_indexes),
                "hidden_act": v.hidden_act,
                "rope_parameters": {"rope_type": "axial", "rope_theta": v.rope_theta},
            },
        }


qwen3_vl_2b = Qwen3VLConfig.qwen3_vl_2b
qwen3_vl_4b = Qwen3VLConfig.qwen3_vl_4b
qwen3_vl_8b = Qwen3VLConfig.qwen3_vl_8b
small = Qwen3VLConfig.small
tiny = Qwen3VLConfig.tiny
