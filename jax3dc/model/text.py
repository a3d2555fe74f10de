"""The Qwen3 decoder of Qwen3-VL: GQA attention with RMSNorm on each head's q and k, SwiGLU MLP.

Layers take precomputed rotary cos/sin (from the multimodal position ids) and a boolean
attention mask, and optionally one layer's slice of the KV cache (see qwen3_vl.py for the
cache layout): new keys/values are written at ``write_index``; a decode step then attends over
the whole cache, a prefill (``from_cache=False``) only over its own keys, which are all there is.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import nnx
from jax.ad_checkpoint import checkpoint_name

from jax3dc.model.config import TextConfig
from jax3dc.model.layers import Dense, RMSNorm, activation
from jax3dc.model.packed_attention import PackedRows, packed_attention
from jax3dc.model.rope import apply_rotary
from jax3dc.sharding import constrain

LayerCache = tuple[jax.Array, jax.Array]  # keys, values: [B, S_max, kv_heads, head_dim]


class TextAttention(nnx.Module):
    def __init__(self, cfg: TextConfig, *, rngs: nnx.Rngs, dtype, param_dtype, attention_impl):
        e, n, k, hd = cfg.hidden_size, cfg.num_attention_heads, cfg.num_key_value_heads, cfg.head_dim
        kw = dict(rngs=rngs, dtype=dtype, param_dtype=param_dtype, use_bias=cfg.attention_bias)
        self.q_proj = Dense((e,), (n, hd), ("embed",), ("heads", "head_dim"), **kw)
        self.k_proj = Dense((e,), (k, hd), ("embed",), ("kv_heads", "head_dim"), **kw)
        self.v_proj = Dense((e,), (k, hd), ("embed",), ("kv_heads", "head_dim"), **kw)
        self.o_proj = Dense((n, hd), (e,), ("heads", "head_dim"), ("embed",), **kw)
        self.q_norm = RMSNorm(hd, cfg.rms_norm_eps, "head_dim", dtype=dtype, param_dtype=param_dtype)
        self.k_norm = RMSNorm(hd, cfg.rms_norm_eps, "head_dim", dtype=dtype, param_dtype=param_dtype)
        self.attention_impl = attention_impl

    def __call__(self, x: jax.Array, cos: jax.Array, sin: jax.Array, mask: jax.Array | PackedRows | None,
                 cache: LayerCache | None = None,
                 write_index: jax.Array | None = None,
                 from_cache: bool = True) -> tuple[jax.Array, LayerCache | None]:
        # names for the `qkv` remat policy (layer_stack.py): the projections it keeps
        q = apply_rotary(self.q_norm(checkpoint_name(self.q_proj(x), "query_proj")), cos, sin)
        k = apply_rotary(self.k_norm(checkpoint_name(self.k_proj(x), "key_proj")), cos, sin)
        v = checkpoint_name(self.v_proj(x), "value_proj")
        # q, k and v sharded alike: cuDNN's partitioner refuses mixed shardings on a mesh
        q, k, v = (constrain(t, ("batch", "length", "act_heads", None)) for t in (q, k, v))
        if cache is not None:
            k_all = jax.lax.dynamic_update_slice_in_dim(cache[0], k.astype(cache[0].dtype), write_index, axis=1)
            v_all = jax.lax.dynamic_update_slice_in_dim(cache[1], v.astype(cache[1].dtype), write_index, axis=1)
            cache = (k_all, v_all)
            if from_cache:
                k, v = k_all.astype(q.dtype), v_all.astype(q.dtype)
        # a one-token decode query is memory-bound: fused kernels gain nothing there, use XLA's
        impl = self.attention_impl if q.shape[1] > 1 else None
        if isinstance(mask, PackedRows):
            out = packed_attention(q, k, v, mask, impl)
        else:
            out = jax.nn.dot_product_attention(q, k, v, mask=mask, is_causal=mask is None, implementation=impl)
        out = self.o_proj(out)
        return constrain(out, ("batch", "length", "act_embed")), cache


class TextMLP(nnx.Module):
    def __init__(self, cfg: TextConfig, *, rngs: nnx.Rngs, dtype, param_dtype):
        e, m = cfg.hidden_size, cfg.intermediate_size
        kw = dict(rngs=rngs, dtype=dtype, param_dtype=param_dtype, use_bias=False)
        self.gate_proj = Dense((e,), (m,), ("embed",), ("mlp",), **kw)
        self.up_proj = Dense((e,), (m,), ("embed",), ("mlp",), **kw)
        self.down_proj = Dense((m,), (e,), ("mlp",), ("embed",), **kw)
        self.act = activation(cfg.hidden_act)

    def __call__(self, x: jax.Array) -> jax.Array:
        h = constrain(self.act(self.gate_proj(x)) * self.up_proj(x), ("batch", "length", "act_mlp"))
        return constrain(self.down_proj(h), ("batch", "length", "act_embed"))


class DecoderLayer(nnx.Module):
    def __init__(self, cfg: TextConfig, *, rngs: nnx.Rngs, dtype, param_dtype, attention_impl):
        kw = dict(dtype=dtype, param_dtype=param_dtype)
        self.self_attn = TextAttention(cfg, rngs=rngs, attention_impl=attention_impl, **kw)
        self.mlp = TextMLP(cfg, rngs=rngs, **kw)
        self.input_layernorm = RMSNorm(cfg.hidden_size, cfg.rms_norm_eps, "norm", **kw)
        self.post_attention_layernorm = RMSNorm(cfg.hidden_size, cfg.rms_norm_eps, "norm", **kw)

    def __call__(self, x, cos, sin, mask, cache=None, write_index=None, from_cache=True):
        h, cache = self.self_attn(self.input_layernorm(x), cos, sin, mask, cache, write_index, from_cache)
        x = x + h
        return x + self.mlp(self.post_attention_layernorm(x)), cache


class TextModel(nnx.Module):
    """Token embedding, decoder layers and final norm; DeepStack injection happens in qwen3_vl.py
    between layers, so the layers are exposed as a list."""

    def __init__(self, cfg: TextConfig, *, rngs: nnx.Rngs, dtype=jnp.float32, param_dtype=jnp.float32,
                 attention_impl: str | None = None):
        self.cfg = cfg
        self.dtype = dtype
        self.embed_tokens = nnx.Param(
            (0.02 * jax.random.normal(rngs.params(), (cfg.vocab_size, cfg.hidden_size))).astype(param_dtype),
            logical_axes=("vocab", "embed"))
        self.layers = nnx.List([DecoderLayer(cfg, rngs=rngs, dtype=dtype, param_dtype=param_dtype,
                                             attention_impl=attention_impl)
                                for _ in range(cfg.num_hidden_layers)])
        self.norm = RMSNorm(cfg.hidden_size, cfg.rms_norm_eps, "norm", dtype=dtype, param_dtype=param_dtype)

    def embed(self, input_ids: jax.Array) -> jax.Array:
        x = jnp.take(self.embed_tokens.get_value(), input_ids, axis=0).astype(self.dtype)
        return constrain(x, ("batch", "length", "act_embed"))
