"""The logical-axis rules table, the mesh helper, and a sharded forward pass on 8 simulated
CPU devices that must equal the single-device one."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import pytest
from flax import nnx
from jax.sharding import PartitionSpec as P

from jax3dc.model import Qwen3VLConfig
from jax3dc.model.params import abstract_model
from jax3dc.sharding import LOGICAL_RULES, constrain, logical_to_spec, make_mesh, state_shardings

MESH = {"data": 2, "fsdp": 4, "tensor": 2}


def test_rules_map_logical_axes_to_mesh_axes():
    assert logical_to_spec(("embed", "mlp"), (2560, 9728), MESH) == P("fsdp", "tensor")
    assert logical_to_spec(("vocab", "embed"), (151936, 2560), MESH) == P("tensor", "fsdp")
    assert logical_to_spec(("batch", "length", "act_embed"), (16, 8192, 2560), MESH) == P(("data", "fsdp"), None, None)


def test_rules_fall_back_to_replication_when_a_dimension_does_not_split():
    # 3 kv heads cannot be split 2 ways; a batch of 4 cannot be split over data x fsdp = 8
    assert logical_to_spec(("embed", "kv_heads", "head_dim"), (2560, 3, 128), MESH) == P("fsdp", None, None)
    assert logical_to_spec(("batch", "length"), (4, 16), MESH) == P(None, None)
    # mesh axes of size 1 and axes already used by an earlier dimension are dropped
    assert logical_to_spec(("embed", "mlp"), (8, 8), {"data": 8, "fsdp": 1, "tensor": 1}) == P(None, None)
    assert logical_to_spec(("mlp", "heads"), (8, 8), MESH) == P("tensor", None)
    # another table changes the layout without touching the model
    rules = tuple((k, None) if k == "embed" else (k, v) for k, v in LOGICAL_RULES)
    assert logical_to_spec(("embed", "mlp"), (16, 16), MESH, rules) == P(None, "tensor")


def test_every_parameter_of_the_4b_model_has_logical_axes():
    model = abstract_model(Qwen3VLConfig.qwen3_vl_4b())
    names = dict(LOGICAL_RULES)
    for path, v in nnx.to_flat_state(nnx.state(model, nnx.Param)):
        axes = v.logical_axes
        assert len(axes) == len(v.get_value().shape), path
        assert all(a in names for a in axes), (path, axes)


def test_make_mesh_and_state_shardings_on_available_devices():
    mesh = make_mesh()
    assert mesh.axis_names == ("data", "fsdp", "tensor") and mesh.size == len(jax.devices())
    with pytest.raises(ValueError):
        make_mesh(data=len(jax.devices()) + 1, fsdp=1)
    model = abstract_model(Qwen3VLConfig.tiny())
    shardings = state_shardings(nnx.state(model), mesh)
    assert all(isinstance(s.get_value(), jax.sharding.NamedSharding)
               for _, s in nnx.to_flat_state(shardings))
    x = jnp.ones((2, 3))
    assert constrain(x, ("batch", "length")) is x  # no mesh set: no-op


SCRIPT = textwrap.dedent("""
    import jax, jax.numpy as jnp, numpy as np
    from flax import nnx
    from jax3dc.model import Qwen3VL, Qwen3VLConfig, load_pretrained, save_pretrained
    from jax3dc.sharding import make_mesh
    jax.config.update("jax_default_matmul_precision", "highest")
    assert len(jax.devices()) == 8
    cfg = Qwen3VLConfig.tiny()
    save_pretrained(Qwen3VL(cfg, rngs=nnx.Rngs(0)), cfg, "ckpt")
    ids = jnp.asarray(np.random.default_rng(0).integers(0, 100, (4, 16)), jnp.int32)
    fwd = nnx.jit(lambda m, x: m(x))
    single, _ = load_pretrained("ckpt")
    ref = np.asarray(fwd(single, ids))
    mesh = make_mesh(data=2, fsdp=2, tensor=2)
    model, _ = load_pretrained("ckpt", mesh=mesh)
    spec = model.language_model.layers[0].mlp.gate_proj.kernel.get_value().sharding.spec
    assert tuple(spec) == ("fsdp", "tensor"), spec
    with jax.set_mesh(mesh):
        out = fwd(model, ids)
    err = float(np.abs(np.asarray(out) - ref).max() / np.abs(ref).max())
    print("sharded rel err", err)
    assert err < 1e-5, err
""")


@pytest.mark.slow
def test_sharded_forward_on_8_cpu_devices_equals_single_device(tmp_path):
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=8", JAX_PLATFORMS="cpu",
               PYTHONPATH=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    r = subprocess.run([sys.executable, "-c", SCRIPT], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    print(r.stdout.strip())
