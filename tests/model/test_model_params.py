"""HF checkpoint conversion: every tensor mapped or a typed error, sharded (index) checkpoints,
bfloat16 files, tied embeddings, and loading onto a mesh."""

from __future__ import annotations

import json
import shutil

import jax
import jax.numpy as jnp
import ml_dtypes
import numpy as np
import pytest
from flax import nnx

from jax3dc.errors import InputFileError
from jax3dc.model import Qwen3VL, Qwen3VLConfig, load_pretrained, save_pretrained
from jax3dc.model.params import PARAM_TABLE, hf_to_ours_name
from jax3dc.model.safetensors_io import iter_tensors, write_safetensors
from jax3dc.sharding import make_mesh


def flat_params(model) -> dict[str, np.ndarray]:
    return {".".join(map(str, p)): np.asarray(v.get_value())
            for p, v in nnx.to_flat_state(nnx.state(model, nnx.Param))}


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    cfg = Qwen3VLConfig.tiny()
    model = Qwen3VL(cfg, rngs=nnx.Rngs(3))
    path = tmp_path_factory.mktemp("ours")
    save_pretrained(model, cfg, path)
    return model, cfg, path


def test_round_trip_is_exact_and_every_name_is_in_the_table(saved):
    model, cfg, path = saved
    names = [name for name, _ in iter_tensors(path)]
    assert all(hf_to_ours_name(n) is not None for n in names)
    assert "lm_head.weight" in names and not cfg.tie_word_embeddings
    back, cfg2 = load_pretrained(path)
    assert cfg2 == cfg
    a, b = flat_params(model), flat_params(back)
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_sharded_checkpoint_with_index(saved, tmp_path):
    model, cfg, _ = saved
    save_pretrained(model, cfg, tmp_path, max_shard_bytes=40_000)
    index = json.loads((tmp_path / "model.safetensors.index.json").read_text())
    files = set(index["weight_map"].values())
    assert len(files) > 2 and not (tmp_path / "model.safetensors").exists()
    back, _ = load_pretrained(tmp_path)
    a, b = flat_params(model), flat_params(back)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_bfloat16_checkpoint_loads_as_rounded_float32(saved, tmp_path):
    model, cfg, _ = saved
    save_pretrained(model, cfg, tmp_path, dtype=ml_dtypes.bfloat16)
    assert json.loads((tmp_path / "config.json").read_text())["dtype"] == "bfloat16"
    back, _ = load_pretrained(tmp_path, dtype=jnp.float32)
    for k, v in flat_params(model).items():
        expect = v.astype(ml_dtypes.bfloat16).astype(np.float32)
        np.testing.assert_array_equal(flat_params(back)[k], expect, err_msg=k)
    bf, _ = load_pretrained(tmp_path, dtype=jnp.bfloat16)
    assert all(v.dtype == jnp.bfloat16 for v in flat_params(bf).values())


def _rewrite(src, dst, edit):
    shutil.copytree(src, dst)
    tensors = dict(iter_tensors(src))
    edit(tensors)
    write_safetensors(dst / "model.safetensors", tensors)


def test_unmapped_missing_and_misshapen_tensors_raise(saved, tmp_path):
    _, _, path = saved
    _rewrite(path, tmp_path / "extra", lambda t: t.update({"model.visual.extra.weight": np.zeros(3, np.float32)}))
    with pytest.raises(InputFileError, match="model.visual.extra.weight"):
        load_pretrained(tmp_path / "extra")
    _rewrite(path, tmp_path / "missing", lambda t: t.pop("model.language_model.layers.1.mlp.up_proj.weight"))
    with pytest.raises(InputFileError, match="missing"):
        load_pretrained(tmp_path / "missing")
    name = "model.language_model.layers.0.self_attn.q_proj.weight"
    _rewrite(path, tmp_path / "shape", lambda t: t.update({name: t[name][:-1]}))
    with pytest.raises(InputFileError, match="q_proj"):
        load_pretrained(tmp_path / "shape")
    # a deeper model than the config: layer 3 has no place in a 3-layer model
    extra = "model.language_model.layers.3.input_layernorm.weight"
    _rewrite(path, tmp_path / "deep", lambda t: t.update({extra: np.ones(48, np.float32)}))
    with pytest.raises(InputFileError, match="no room"):
        load_pretrained(tmp_path / "deep")
    with pytest.raises(InputFileError, match="config.json"):
        load_pretrained(tmp_path / "nowhere")


def test_table_patterns_are_unambiguous():
    hf_names = [h for h, _, _ in PARAM_TABLE]
    ours = [o for _, o, _ in PARAM_TABLE]
    assert len(set(hf_names)) == len(hf_names) and len(set(ours)) == len(ours)


def test_tied_embeddings_match_transformers_and_save_without_lm_head(tmp_path):
    import torch
    import transformers
    cfg = Qwen3VLConfig.tiny(tie_word_embeddings=True)
    d = {k: v for k, v in cfg.to_hf_dict().items() if k not in ("architectures", "model_type", "dtype")}
    torch.manual_seed(1)
    hf = transformers.Qwen3VLForConditionalGeneration(transformers.Qwen3VLConfig(**d)).eval()
    hf.save_pretrained(tmp_path / "hf")
    model, _ = load_pretrained(tmp_path / "hf")
    assert model.lm_head is None
    ids = np.random.default_rng(0).integers(0, 100, (1, 9))
    with jax.default_matmul_precision("highest"):
        ours = np.asarray(nnx.jit(lambda m, x: m(x))(model, jnp.asarray(ids, jnp.int32)))
    with torch.no_grad():
        ref = hf(input_ids=torch.tensor(ids)).logits.numpy()
    assert np.abs(ours - ref).max() / np.abs(ref).max() < 1e-4
    save_pretrained(model, cfg, tmp_path / "ours")
    assert "lm_head.weight" not in dict(iter_tensors(tmp_path / "ours"))
    back = transformers.Qwen3VLForConditionalGeneration.from_pretrained(tmp_path / "ours")
    np.testing.assert_array_equal(back.lm_head.weight.detach().numpy(),
                                  hf.model.language_model.embed_tokens.weight.detach().numpy())


def test_load_onto_a_mesh_places_every_parameter(saved):
    _, _, path = saved
    mesh = make_mesh()
    model, _ = load_pretrained(path, mesh=mesh)
    for p, v in nnx.to_flat_state(nnx.state(model, nnx.Param)):
        arr = v.get_value()
        assert isinstance(arr.sharding, jax.sharding.NamedSharding) and arr.sharding.mesh == mesh, p


def test_bfloat16_compute_with_float32_parameters(saved):
    _, _, path = saved
    m32, _ = load_pretrained(path)
    m16, _ = load_pretrained(path, dtype=jnp.float32, compute_dtype=jnp.bfloat16)
    assert all(v.dtype == jnp.float32 for v in flat_params(m16).values())
    ids = jnp.asarray(np.random.default_rng(0).integers(0, 100, (2, 10)), jnp.int32)
    fwd = nnx.jit(lambda m, x: m(x))
    a, b = np.asarray(fwd(m32, ids)), fwd(m16, ids)
    assert b.dtype == jnp.bfloat16
    err = np.abs(a - np.asarray(b, np.float32)).max() / np.abs(a).max()
    assert 0 < err < 3e-2, err  # bf16 rounding shows, but stays small


def test_a_file_that_is_not_safetensors_is_an_input_error_naming_it(tmp_path):
    (tmp_path / "model.safetensors").write_bytes(b"not a checkpoint")
    with pytest.raises(InputFileError, match=r"model\.safetensors.*not a readable safetensors file"):
        dict(iter_tensors(tmp_path))
