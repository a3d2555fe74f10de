"""Qwen3-VL configs: presets, the config.json mapping both ways, and parameter counts without
allocating (checked against transformers' model built on the meta device)."""

from __future__ import annotations

import pytest

from jax3dc.errors import InputFileError
from jax3dc.model.config import Qwen3VLConfig, VisionConfig
from jax3dc.model.params import abstract_model, param_count

PRESETS = ["qwen3_vl_2b", "qwen3_vl_4b", "qwen3_vl_8b", "small", "release", "tiny"]


def hf_kwargs(cfg: Qwen3VLConfig) -> dict:
    return {k: v for k, v in cfg.to_hf_dict().items() if k not in ("architectures", "model_type", "dtype")}


@pytest.mark.parametrize("name", PRESETS)
def test_preset_round_trips_through_transformers_config(name):
    import transformers
    cfg = getattr(Qwen3VLConfig, name)()
    assert Qwen3VLConfig.from_hf_dict(cfg.to_hf_dict()) == cfg
    hf = transformers.Qwen3VLConfig(**hf_kwargs(cfg))
    assert Qwen3VLConfig.from_hf_dict(hf.to_dict()) == cfg


def test_released_checkpoint_layout_with_rope_scaling():
    """Released Qwen3-VL config.json files keep rope_theta and mrope_section in the older
    rope_scaling layout and torch_dtype; the 4B one must read as our 4B preset."""
    d = {
        "architectures": ["Qwen3VLForConditionalGeneration"], "model_type": "qwen3_vl",
        "image_token_id": 151655, "video_token_id": 151656, "vision_start_token_id": 151652,
        "vision_end_token_id": 151653, "tie_word_embeddings": True,
        "text_config": {
            "model_type": "qwen3_vl_text", "vocab_size": 151936, "hidden_size": 2560,
            "intermediate_size": 9728, "num_hidden_layers": 36, "num_attention_heads": 32,
            "num_key_value_heads": 8, "head_dim": 128, "hidden_act": "silu", "rms_norm_eps": 1e-6,
            "max_position_embeddings": 262144, "rope_theta": 5000000, "tie_word_embeddings": True,
            "rope_scaling": {"mrope_interleaved": True, "mrope_section": [24, 20, 20], "rope_type": "default"},
            "torch_dtype": "bfloat16",
        },
        "vision_config": {
            "model_type": "qwen3_vl", "depth": 24, "hidden_size": 1024, "hidden_act": "gelu_pytorch_tanh",
            "intermediate_size": 4096, "num_heads": 16, "in_channels": 3, "patch_size": 16,
            "spatial_merge_size": 2, "temporal_patch_size": 2, "out_hidden_size": 2560,
            "num_position_embeddings": 2304, "deepstack_visual_indexes": [5, 11, 17],
        },
    }
    assert Qwen3VLConfig.from_hf_dict(d) == Qwen3VLConfig.qwen3_vl_4b()


def test_bad_configs_raise_typed_errors():
    d = Qwen3VLConfig.tiny().to_hf_dict()
    with pytest.raises(InputFileError, match="model_type"):
        Qwen3VLConfig.from_hf_dict({**d, "model_type": "llava"})
    with pytest.raises(InputFileError, match="rope_type"):
        bad = {**d, "text_config": {**d["text_config"], "rope_parameters": {"rope_type": "yarn", "rope_theta": 1.0}}}
        Qwen3VLConfig.from_hf_dict(bad)
    with pytest.raises(InputFileError, match="mrope_interleaved"):
        rope = {**d["text_config"]["rope_parameters"], "mrope_interleaved": False}
        Qwen3VLConfig.from_hf_dict({**d, "text_config": {**d["text_config"], "rope_parameters": rope}})
    with pytest.raises(InputFileError, match="vision_config"):
        Qwen3VLConfig.from_hf_dict({k: v for k, v in d.items() if k != "vision_config"})
    with pytest.raises(ValueError, match="perfect square"):
        VisionConfig(num_position_embeddings=2300)
    with pytest.raises(ValueError, match="out_hidden_size"):
        Qwen3VLConfig(vision=VisionConfig(out_hidden_size=100))


def test_4b_parameter_count_without_allocating():
    cfg = Qwen3VLConfig.qwen3_vl_4b()
    model = abstract_model(cfg)  # ShapeDtypeStructs only
    total, vision = param_count(model), param_count(model, "visual")
    assert round(total / 1e9, 2) == 4.44
    assert round((total - vision) / 1e9, 2) == 4.02
    assert round(vision / 1e9, 2) == 0.42
    import torch
    import transformers
    with torch.device("meta"):
        hf = transformers.Qwen3VLForConditionalGeneration(transformers.Qwen3VLConfig(**hf_kwargs(cfg)))
    assert total == sum(p.numel() for p in hf.parameters())
    assert vision == sum(p.numel() for p in hf.model.visual.parameters())


def test_small_preset_is_sized_for_training_from_scratch():
    n = param_count(abstract_model(Qwen3VLConfig.small()))
    assert 50e6 <= n <= 150e6


def test_release_preset_fits_the_package_weight_budget():
    """bf16 weights of the shipped model (2k BPE vocabulary) must stay under 24 MiB."""
    n = param_count(abstract_model(Qwen3VLConfig.release()))
    assert 2 * n <= 24 * 2**20, n
