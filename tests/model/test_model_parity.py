"""Our Qwen3-VL against transformers' (the reference), float32 at highest matmul precision.

A tiny random ``Qwen3VLForConditionalGeneration`` is saved with ``save_pretrained`` and loaded
through our real loader; then vision features, logits (text only, one image, two images of
different sizes in one sequence, left/right padded batches), multimodal position ids, loss and
gradients, KV-cache decoding and the reverse conversion are compared.
"""

from __future__ import annotations

import numpy as np
import pytest

import torch
import transformers

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from flax import nnx  # noqa: E402

from jax3dc.model.config import Qwen3VLConfig  # noqa: E402
from jax3dc.model.params import kernel_input_dims, load_pretrained, ours_to_hf_name, save_pretrained, to_hf  # noqa: E402
from jax3dc.model.rope import get_rope_index  # noqa: E402

TOL = 1e-4
PATCH_BUDGET = 64  # our pixel_values are padded to this many patches: one compile for all image tests
SEQ = 24


def rel_err(ours, ref, where=None) -> float:
    ours, ref = np.asarray(ours, np.float64), np.asarray(ref, np.float64)
    if where is not None:
        ours, ref = ours[where], ref[where]
    return float(np.abs(ours - ref).max() / np.abs(ref).max())


@pytest.fixture(autouse=True)
def highest_precision():
    with jax.default_matmul_precision("highest"):
        yield


def hf_config(cfg: Qwen3VLConfig):
    d = cfg.to_hf_dict()
    return transformers.Qwen3VLConfig(**{k: v for k, v in d.items() if k not in ("architectures", "model_type", "dtype")})


def random_hf_model(cfg: Qwen3VLConfig, seed: int = 0):
    torch.manual_seed(seed)
    hf = transformers.Qwen3VLForConditionalGeneration(hf_config(cfg)).eval()
    with torch.no_grad():  # norms start at 1 and biases at 0: perturb so their mapping is tested
        for name, p in hf.named_parameters():
            if "norm" in name or name.endswith("bias"):
                p.add_(0.2 * torch.randn_like(p))
    return hf


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    cfg = Qwen3VLConfig.tiny()
    hf = random_hf_model(cfg)
    path = tmp_path_factory.mktemp("hf_tiny")
    hf.save_pretrained(path)
    model, loaded_cfg = load_pretrained(path)
    assert loaded_cfg == cfg
    return hf, model, cfg


def make_batch(cfg: Qwen3VLConfig, rows: list[list], pad: str = "left", seed: int = 0):
    """rows: per row a list of ints (text length) and (h, w) tuples (an image of h x w patches).
    Returns ids, mask [B, SEQ], pixel_values [n, D] (unpadded), grid [n_images, 3]."""
    rng = np.random.default_rng(seed)
    m = cfg.vision.spatial_merge_size
    ids = np.zeros((len(rows), SEQ), np.int64)
    mask = np.zeros((len(rows), SEQ), np.int64)
    grids = []
    for r, row in enumerate(rows):
        toks: list[int] = []
        for part in row:
            if isinstance(part, int):
                toks += list(rng.integers(0, cfg.vision_start_token_id, part))
            else:
                h, w = part
                grids.append((1, h, w))
                toks += [cfg.vision_start_token_id] + [cfg.image_token_id] * (h * w // m**2) + [cfg.vision_end_token_id]
        assert len(toks) <= SEQ
        sl = slice(SEQ - len(toks), SEQ) if pad == "left" else slice(0, len(toks))
        ids[r, sl] = toks
        mask[r, sl] = 1
    grid = np.array(grids, np.int64).reshape(-1, 3)
    pixels = rng.standard_normal((int(grid.prod(-1).sum()), cfg.vision.patch_dim)).astype(np.float32)
    return ids, mask, pixels, grid


def hf_logits(hf, ids, mask=None, pixels=None, grid=None):
    kw = {}
    if pixels is not None:
        kw = dict(pixel_values=torch.tensor(pixels), image_grid_thw=torch.tensor(grid),
                  mm_token_type_ids=torch.tensor((ids == hf.config.image_token_id).astype(np.int64)))
    if mask is not None:
        kw["attention_mask"] = torch.tensor(mask)
    with torch.no_grad():
        return hf(input_ids=torch.tensor(ids), **kw).logits.numpy()


@nnx.jit
def _forward_images(model, ids, mask, pixels, grid):
    return model(ids, attention_mask=mask, pixel_values=pixels, image_grid_thw=grid)


def our_logits(model, ids, mask, pixels, grid):
    padded = np.zeros((PATCH_BUDGET, pixels.shape[1]), np.float32)
    padded[: len(pixels)] = pixels
    return np.asarray(_forward_images(model, jnp.asarray(ids, jnp.int32), jnp.asarray(mask, jnp.int32),
                                      jnp.asarray(padded), jnp.asarray(grid, jnp.int32)))


def test_vision_tower_and_deepstack_match(pair):
    hf, model, cfg = pair
    _, _, pixels, grid = make_batch(cfg, [[(4, 4), (6, 2)]])
    with torch.no_grad():
        out = hf.model.visual(torch.tensor(pixels), grid_thw=torch.tensor(grid))
    padded = np.zeros((PATCH_BUDGET, pixels.shape[1]), np.float32)
    padded[: len(pixels)] = pixels
    tokens, deepstack = nnx.jit(lambda m, p, g: m.visual(p, g))(model, jnp.asarray(padded), jnp.asarray(grid))
    n = len(pixels) // cfg.vision.spatial_merge_size**2
    err = rel_err(tokens[:n], out.pooler_output.numpy())
    print(f"rel err {err:.2e}")
    assert err < TOL, err
    assert len(deepstack) == len(out.deepstack_features) == len(cfg.vision.deepstack_visual_indexes)
    for level, (ours, ref) in enumerate(zip(deepstack, out.deepstack_features)):
        err = rel_err(ours[:n], ref.numpy())
        print(f"deepstack level {level} rel err {err:.2e}")
        assert err < TOL, f"deepstack level {level}: rel err {err:.2e}"


def test_windowed_vision_attention_matches(pair):
    """Images of different sizes, each attending in its own 24-slot window, padded patch budget."""
    hf, model, cfg = pair
    _, _, pixels, grid = make_batch(cfg, [[(4, 4), (2, 6), (4, 6)]])
    padded = np.zeros((PATCH_BUDGET, pixels.shape[1]), np.float32)
    padded[: len(pixels)] = pixels
    tokens, deepstack = nnx.jit(lambda m, p, g: m.visual(p, g, window=24))(model, jnp.asarray(padded), jnp.asarray(grid))
    with torch.no_grad():
        out = hf.model.visual(torch.tensor(pixels), grid_thw=torch.tensor(grid))
    n = len(pixels) // cfg.vision.spatial_merge_size**2
    err = max(rel_err(tokens[:n], out.pooler_output.numpy()),
              *(rel_err(a[:n], b.numpy()) for a, b in zip(deepstack, out.deepstack_features)))
    print(f"windowed vision rel err {err:.2e}")
    assert err < TOL, err
    with pytest.raises(ValueError, match="image tokens"):
        model(jnp.full((1, 5), cfg.image_token_id), pixel_values=jnp.asarray(padded), image_grid_thw=grid)
    with pytest.raises(ValueError, match="window"):
        model.visual(jnp.asarray(padded), grid, window=16)  # a 24-patch image does not fit


def test_text_only_logits_match(pair):
    hf, model, cfg = pair
    ids = np.random.default_rng(1).integers(0, cfg.vision_start_token_id, (2, 12))
    ours = nnx.jit(lambda m, x: m(x))(model, jnp.asarray(ids, jnp.int32))
    err = rel_err(ours, hf_logits(hf, ids))
    print(f"rel err {err:.2e}")
    assert err < TOL, err


@pytest.mark.parametrize("rows", [
    pytest.param([[3, (4, 4), 5], [12]], id="one-image"),
    pytest.param([[2, (4, 4), 3, (6, 2), 2], [1, (2, 8), 4]], id="two-images-of-different-sizes"),
])
def test_image_logits_match(pair, rows):
    hf, model, cfg = pair
    ids, mask, pixels, grid = make_batch(cfg, rows)
    mask[:] = 1  # no padding: pad tokens are ordinary text here
    err = rel_err(our_logits(model, ids, mask, pixels, grid), hf_logits(hf, ids, mask, pixels, grid))
    print(f"rel err {err:.2e}")
    assert err < TOL, err


@pytest.mark.parametrize("pad", ["left", "right", "right-no-mask"])
def test_padded_batch_logits_match(pair, pad):
    """Real tokens match; right padding also without a mask (the training layout)."""
    hf, model, cfg = pair
    ids, mask, pixels, grid = make_batch(cfg, [[1, (4, 4), 2, (2, 4), 1], [2, (6, 2), 6]], pad=pad.split("-")[0])
    assert (mask == 0).any()
    if pad == "right-no-mask":
        padded = np.zeros((PATCH_BUDGET, pixels.shape[1]), np.float32)
        padded[: len(pixels)] = pixels
        ours = np.asarray(nnx.jit(lambda m, *a: m(a[0], pixel_values=a[1], image_grid_thw=a[2]))(
            model, jnp.asarray(ids, jnp.int32), jnp.asarray(padded), jnp.asarray(grid, jnp.int32)))
    else:
        ours = our_logits(model, ids, mask, pixels, grid)
    err = rel_err(ours, hf_logits(hf, ids, mask, pixels, grid), where=mask.astype(bool))
    print(f"rel err {err:.2e}")
    assert err < TOL, err


def test_rope_index_matches_transformers(pair):
    hf, _, cfg = pair
    for seed, pad in [(0, "left"), (1, "right")]:
        ids, mask, _, grid = make_batch(cfg, [[2, (4, 4), 1, (6, 2)], [3, (2, 6), 1], [9]], pad=pad, seed=seed)
        mm = (ids == cfg.image_token_id).astype(np.int64)
        ref_pos, ref_delta = hf.model.get_rope_index(torch.tensor(ids), torch.tensor(mm), torch.tensor(grid),
                                                     attention_mask=torch.tensor(mask))
        pos, delta = get_rope_index(jnp.asarray(ids), jnp.asarray(grid), cfg.image_token_id,
                                    cfg.vision.spatial_merge_size, jnp.asarray(mask))
        np.testing.assert_array_equal(np.asarray(pos), ref_pos.numpy())
        np.testing.assert_array_equal(np.asarray(delta), ref_delta.numpy()[:, 0])


def test_given_position_ids_equal_computed_ones(pair):
    """The training pipeline may precompute the multimodal ids ([3, B, L]) outside the step."""
    hf, model, cfg = pair
    ids, mask, pixels, grid = make_batch(cfg, [[1, (4, 4), 2, (2, 4), 1], [2, (6, 2), 6]], pad="right")
    pos, _ = get_rope_index(jnp.asarray(ids), jnp.asarray(grid), cfg.image_token_id,
                            cfg.vision.spatial_merge_size, jnp.asarray(mask))
    ours = nnx.jit(lambda m, *a: m(a[0], attention_mask=a[1], pixel_values=a[2], image_grid_thw=a[3], position_ids=a[4]))(
        model, jnp.asarray(ids, jnp.int32), jnp.asarray(mask), jnp.asarray(pixels), jnp.asarray(grid, jnp.int32), pos)
    err = rel_err(ours, hf_logits(hf, ids, mask, pixels, grid), where=mask.astype(bool))
    print(f"rel err {err:.2e}")
    assert err < TOL, err


@pytest.mark.slow
def test_loss_and_gradients_match_torch(pair):
    hf, model, cfg = pair
    ids, mask, pixels, grid = make_batch(cfg, [[1, (4, 4), 2, (2, 4), 1], [2, (6, 2), 6]], pad="left")
    labels = np.roll(ids, -1, axis=1)
    weight = (mask * np.roll(mask, -1, axis=1)).astype(np.float32)
    weight[:, -1] = 0
    weight[ids == cfg.image_token_id] = 0

    hf.zero_grad()
    logits = hf(input_ids=torch.tensor(ids), attention_mask=torch.tensor(mask), pixel_values=torch.tensor(pixels),
                image_grid_thw=torch.tensor(grid),
                mm_token_type_ids=torch.tensor((ids == cfg.image_token_id).astype(np.int64))).logits
    nll = torch.nn.functional.cross_entropy(logits.reshape(-1, logits.shape[-1]), torch.tensor(labels).reshape(-1),
                                            reduction="none")
    ref_loss = (nll * torch.tensor(weight).reshape(-1)).sum() / weight.sum()
    ref_loss.backward()
    ref_grads = {n: p.grad.numpy() for n, p in hf.named_parameters() if p.grad is not None}

    padded = np.zeros((PATCH_BUDGET, pixels.shape[1]), np.float32)
    padded[: len(pixels)] = pixels

    def loss_fn(m):
        lg = m(jnp.asarray(ids, jnp.int32), attention_mask=jnp.asarray(mask), pixel_values=jnp.asarray(padded),
               image_grid_thw=jnp.asarray(grid, jnp.int32))
        lp = jax.nn.log_softmax(lg, axis=-1)
        tok = jnp.take_along_axis(lp, jnp.asarray(labels)[..., None], axis=-1)[..., 0]
        return -(tok * weight).sum() / weight.sum()

    loss, grads = nnx.jit(nnx.value_and_grad(loss_fn))(model)
    assert abs(float(loss) - float(ref_loss.detach())) / float(ref_loss.detach()) < TOL
    n_in = kernel_input_dims(model)
    worst = 0.0
    seen = 0
    for path, g in nnx.to_flat_state(grads):
        ours_name = ".".join(str(p) for p in path)
        hf_name, kind = ours_to_hf_name(ours_name)
        ours_g = to_hf(np.asarray(g.get_value()), kind, n_in.get(ours_name, 1), cfg)
        ref = ref_grads[hf_name]
        assert ours_g.shape == ref.shape, hf_name
        scale = np.abs(ref).max()
        if scale > 0:
            worst = max(worst, float(np.abs(ours_g - ref).max() / scale))
        seen += 1
    assert seen == len(ref_grads)
    print(f"loss rel err {abs(float(loss) - float(ref_loss.detach())) / float(ref_loss.detach()):.2e}, "
          f"worst gradient rel err {worst:.2e} over {seen} tensors")
    assert worst < 1e-3, worst  # per-tensor relative error of gradients


def test_saved_checkpoint_loads_in_transformers(pair, tmp_path):
    hf, model, cfg = pair
    save_pretrained(model, cfg, tmp_path)
    back = transformers.Qwen3VLForConditionalGeneration.from_pretrained(tmp_path).eval()
    ref_state = hf.state_dict()
    for name, tensor in back.state_dict().items():
        np.testing.assert_array_equal(tensor.numpy(), ref_state[name].numpy(), err_msg=name)
    ids, mask, pixels, grid = make_batch(cfg, [[3, (4, 4), 5], [12]])
    mask[:] = 1
    err = rel_err(hf_logits(back, ids, mask, pixels, grid), our_logits(model, ids, mask, pixels, grid))
    print(f"rel err {err:.2e}")
    assert err < TOL, err


def test_kv_cache_decoding_matches_full_forward_and_transformers_generate(pair):
    hf, model, cfg = pair
    ids, mask, pixels, grid = make_batch(cfg, [[1, (4, 4), 2, (2, 4), 1], [2, (6, 2), 3]], pad="left")
    ids, mask = ids[:, 6:], mask[:, 6:]  # prompt of 18 columns, left padded
    new = 4
    mm = (ids == cfg.image_token_id).astype(np.int64)
    with torch.no_grad():
        ref = hf.generate(input_ids=torch.tensor(ids), attention_mask=torch.tensor(mask),
                          pixel_values=torch.tensor(pixels), image_grid_thw=torch.tensor(grid),
                          mm_token_type_ids=torch.tensor(mm), max_new_tokens=new, min_new_tokens=new,
                          do_sample=False, pad_token_id=0).numpy()[:, ids.shape[1]:]

    padded = np.zeros((PATCH_BUDGET, pixels.shape[1]), np.float32)
    padded[: len(pixels)] = pixels
    # prefill with per-image vision windows, the full forward below without: both paths agree
    prefill = nnx.jit(lambda m, *a: m.prefill(*a, max_length=ids.shape[1] + new, vision_window=16))
    decode = nnx.jit(lambda m, t, c, d: m.decode_step(t, c, d))
    logits, cache, deltas = prefill(model, jnp.asarray(ids, jnp.int32), jnp.asarray(mask),
                                    jnp.asarray(padded), jnp.asarray(grid, jnp.int32))
    tokens, step_logits = [], [logits]
    for _ in range(new):
        tok = jnp.argmax(logits, axis=-1).astype(jnp.int32)
        tokens.append(tok)
        logits, cache = decode(model, tok, cache, deltas)
        step_logits.append(logits)
    np.testing.assert_array_equal(np.stack(tokens, 1), ref)

    # teacher-forced full forward over prompt + generated tokens gives the same logits
    full_ids = np.concatenate([ids, np.stack(tokens, 1)], axis=1)
    full_mask = np.concatenate([mask, np.ones((2, new), np.int64)], axis=1)
    full = np.asarray(nnx.jit(lambda m, *a: m(a[0], attention_mask=a[1], pixel_values=a[2], image_grid_thw=a[3]))(
        model, jnp.asarray(full_ids, jnp.int32), jnp.asarray(full_mask), jnp.asarray(padded),
        jnp.asarray(grid, jnp.int32)))
    for k in range(new + 1):
        err = rel_err(step_logits[k], full[:, ids.shape[1] - 1 + k])
        print(f"decode step {k} rel err {err:.2e}")
        assert err < TOL, (k, err)
