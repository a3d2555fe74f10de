"""Collective bandwidth between this host's GPUs, through jax (NCCL on GPU): all-gather,
reduce-scatter and all-reduce of bf16 buffers over an FSDP-like 1-D mesh.

    python3 bench/collectives.py [--mib 256] [--iters 10]

Prints algorithm bandwidth (bytes of the full buffer / time) and bus bandwidth (NCCL's
convention: the bytes each link carries, (n-1)/n of the buffer for gathers and scatters, twice
that for all-reduce). Why it exists: FSDP training moves every weight twice per step; if these
figures are far below the links' rate, scaling cannot be fixed in the training code.
"""

import argparse
import time

import jax
import jax.numpy as jnp
from jax.sharding import NamedSharding, PartitionSpec as P


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mib", type=int, default=256, help="size of the full (gathered) buffer")
    ap.add_argument("--iters", type=int, default=10)
    a = ap.parse_args()

    n = jax.device_count()
    mesh = jax.make_mesh((n,), ("fsdp",), axis_types=(jax.sharding.AxisType.Explicit,))
    elems = a.mib * 2**20 // 2 // n * n
    sharded, full = NamedSharding(mesh, P("fsdp")), NamedSharding(mesh, P())
    x = jax.device_put(jnp.ones((elems,), jnp.bfloat16), sharded)
    ops = {
        "all-gather": (jax.jit(lambda v: v * 1, out_shardings=full), x, (n - 1) / n),
        "reduce-scatter": (jax.jit(jax.shard_map(lambda v: jax.lax.psum_scatter(v, "fsdp", tiled=True),
                                                 mesh=mesh, in_specs=P(), out_specs=P("fsdp"))),
                           jax.device_put(jnp.ones((elems,), jnp.bfloat16), full), (n - 1) / n),
        "all-reduce": (jax.jit(jax.shard_map(lambda v: jax.lax.psum(v, "fsdp"), mesh=mesh,
                                             in_specs=P(), out_specs=P())),
                       jax.device_put(jnp.ones((elems,), jnp.bfloat16), full), 2 * (n - 1) / n),
    }
    print(f"devices: {n} x {jax.devices()[0].device_kind}, buffer {elems * 2 / 2**20:.0f} MiB bf16")
    for name, (fn, arg, bus) in ops.items():
        fn(arg).block_until_ready()
        t0 = time.perf_counter()
        for _ in range(a.iters):
            out = fn(arg)
        out.block_until_ready()
        dt = (time.perf_counter() - t0) / a.iters
        gbs = elems * 2 / dt / 1e9
        print(f"{name:15s} {dt * 1e3:8.2f} ms  algbw {gbs:7.1f} GB/s  busbw {gbs * bus:7.1f} GB/s")


if __name__ == "__main__":
    main()
