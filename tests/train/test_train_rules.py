"""One sharding rules table per run: TrainConfig.sharding_rules sets it, the batch layout and the
LM-head loss read their mesh axes from it, and a dimension its mesh axes do not divide is a
logged warning, never a silent replication."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest
from jax.sharding import PartitionSpec as P

from jax3dc import sharding
from train.config import ConfigError, TrainConfig, apply_overrides, sharding_rules, validate

ROOT = Path(__file__).resolve().parents[2]


def test_config_overrides_rows_of_the_table():
    cfg = apply_overrides(TrainConfig(data="synthetic"), ["sharding_rules=batch=fsdp,vocab=,mlp=tensor+fsdp"])
    table = dict(sharding_rules(cfg))
    assert table["batch"] == "fsdp" and table["vocab"] is None and table["mlp"] == ("tensor", "fsdp")
    assert table["embed"] == dict(sharding.LOGICAL_RULES)["embed"]  # rows not named keep their default
    assert dict(sharding_rules(TrainConfig())) == dict(sharding.LOGICAL_RULES)


@pytest.mark.parametrize("rule,words", [("batch=dp", "not dp"), ("bacth=data", "logical one of"), ("batch", "expected")])
def test_bad_rules_are_config_errors(rule, words):
    with pytest.raises(ConfigError, match=words):
        validate(TrainConfig(data="synthetic", sharding_rules=(rule,)))


def test_dimension_that_does_not_divide_is_a_logged_warning(caplog):
    sharding.warn_replicated.cache_clear()
    mesh = {"data": 1, "fsdp": 4, "tensor": 2}
    with caplog.at_level(logging.WARNING, logger="jax3dc.sharding"):
        assert sharding.logical_to_spec(("embed", "kv_heads"), (2560, 3), mesh) == P("fsdp", None)
        sharding.logical_to_spec(("embed", "kv_heads"), (2560, 3), mesh)  # said once, not per parameter
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "'kv_heads' of size 3" in lines[0] and "tensor" in lines[0], lines


SCRIPT = r"""
import logging
import numpy as np
import jax, jax.numpy as jnp
from jax.sharding import PartitionSpec as P
from jax3dc import sharding
from train.config import ConfigError, TrainConfig, sharding_rules
from train.loss import token_loss
from train.parallel import batch_sharding, build_mesh, global_batch

logging.basicConfig(level=logging.WARNING, format="WARN %(message)s")
cfg = TrainConfig(sharding_rules=("batch=fsdp",))
rules = sharding_rules(cfg)
mesh = build_mesh(cfg.mesh.__class__(data=2, fsdp=2, tensor=1))
assert batch_sharding(mesh, 3, True, rules).spec == P(None, "fsdp", None)
assert batch_sharding(mesh, 3, True, sharding.LOGICAL_RULES).spec == P(None, ("data", "fsdp"), None)
g = global_batch({"x": np.zeros((4, 8), np.int32)}, mesh, 1, rules)
assert g["x"].sharding.spec == P(None, "fsdp", None), g["x"].sharding.spec
try:
    global_batch({"x": np.zeros((3, 8), np.int32)}, mesh, 1, rules)
    raise SystemExit("3 rows over fsdp=2 should be a ConfigError")
except ConfigError as e:
    assert "fsdp = 2" in str(e), e

rng = np.random.default_rng(0)
def case(rows):
    hidden = jnp.asarray(rng.normal(size=(rows, 8, 16)), jnp.float32)
    head = jnp.asarray(rng.normal(size=(32, 16)), jnp.float32)
    labels = jnp.asarray(rng.integers(0, 32, size=(rows, 8)), jnp.int32)
    mask = jnp.ones((rows, 8), jnp.float32)
    return hidden, head, labels, mask
for rows in (4, 3):
    args = case(rows)
    want = jax.jit(lambda *a: token_loss(*a, chunk=4))(*args)
    for table in (rules, sharding.with_overrides(rules, ["vocab=data"])):
        with jax.set_mesh(mesh), sharding.use_rules(table):
            got = jax.jit(lambda *a: token_loss(*a, chunk=4))(*args)
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-5)
print("OK")
"""


def test_batch_and_loss_follow_the_rules_on_4_cpu_devices():
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4", JAX_PLATFORMS="cpu",
               PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-c", SCRIPT], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "OK" in r.stdout, r.stderr[-3000:]
    warnings = [line for line in r.stderr.splitlines() if line.startswith("WARN ")]
    # 3 rows over fsdp = 2 in the loss: said aloud, once, and the rows are scored whole
    assert len(warnings) == 1 and "loss rows of size 3 does not split over mesh axes fsdp (2 devices)" in warnings[0], \
        r.stderr[-2000:]
