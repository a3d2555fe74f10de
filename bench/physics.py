"""Physics-check throughput: MJX (accelerator) against the fastest C MuJoCo path on all cores, same check.

The check is the interpenetration sweep: kinematics + collision per joint state, reduced to the
deepest contact per body pair (MJX: kinematics, an oriented-box broad phase and MJX's convex narrow
phase on the pairs it keeps, ``jax3dc.physics.mjx_backend``) — what ``jax3dc.physics`` evaluates for rest, sweep and random joint
combinations. Objects come from the procedural factories (convex pieces from
``jax3dc.geometry.convex_pieces``); states are uniform in the joint ranges. Printed per object
structure: MJX compile time and states/s; C states/s on one process (the per-state loop), on one
process per core (pool started and warmed before the clock: start-up printed apart) and by
threaded ``mujoco.rollout`` with a distance sensor per body pair (no GIL); the ratio is against
the faster all-core C figure; and whether MJX and C give the same penetration verdicts.

GPU:   python3 bench/physics.py --states 16384
CPU smoke (MJX compile on a small CPU is slow): python3 bench/physics.py --small
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np

from jax3dc.factories import generate_object
from jax3dc.physics.cpu_backend import PairDistancePool, RolloutDepths, pair_distances
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.tolerances import PENETRATION_TOL_NU


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--states", type=int, default=16384, help="joint states per object (default %(default)s)")
    parser.add_argument("--objects", default="cabinet:0,drawer_chest:0,microwave:0",
                        help="comma list of category:seed (default %(default)s)")
    parser.add_argument("--small", action="store_true", help="CPU smoke run: one small object, 256 states")
    parser.add_argument("--skip-mjx", action="store_true", help="C MuJoCo figures only")
    args = parser.parse_args()
    if args.small:
        args.objects, args.states = "laptop:0", 256
    warnings.filterwarnings("ignore")

    # lazy: the C pool's spawned workers re-import this module (their start-up is printed); jax costs each 0.34 s
    import jax
    import jax.numpy as jnp

    threads = os.cpu_count() or 1
    print(f"devices: {jax.devices()} | CPU processes for C: {threads}", flush=True)
    for spec in args.objects.split(","):
        category, seed = spec.split(":")
        obj = generate_object(category, int(seed))
        sim = build_sim_model(obj.structure, obj.parts, obj.scale_m_per_nu, SimOptions())
        m = sim.model
        rng = np.random.default_rng(0)
        qpos = np.repeat(m.qpos0[None], args.states, axis=0)
        qpos[:, sim.joint_qpos] = rng.uniform(sim.joint_range[:, 0], sim.joint_range[:, 1],
                                              size=(args.states, len(sim.joint_qpos)))
        tol = PENETRATION_TOL_NU * obj.scale_m_per_nu
        line = f"{obj.object_id}: bodies {m.nbody} geoms {m.ngeom} joints {len(sim.joint_qpos)} states {args.states}"
        pair_distances(m, qpos[:64])  # warm-up
        t0 = time.perf_counter()
        c1 = pair_distances(m, qpos[: min(len(qpos), 4096)], threads=1)
        c1_rate = len(c1) / (time.perf_counter() - t0)
        with PairDistancePool(sim.xml, sim.assets, threads) as pool:
            t0 = time.perf_counter()
            pool.start(qpos)
            start_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            c_all = pool.map(qpos)
            pool_rate = len(qpos) / (time.perf_counter() - t0)
        rollout_depths = RolloutDepths(sim.xml, sim.assets)  # compiled apart, like the pool's start
        rollout_depths(qpos[:256], threads)  # warm-up
        t0 = time.perf_counter()
        c_roll = rollout_depths(qpos, threads)
        roll_rate = len(qpos) / (time.perf_counter() - t0)
        c_rate = max(pool_rate, roll_rate)
        roll_agree = float(((c_all < -tol).any(axis=(1, 2)) == (c_roll < -tol).any(axis=(1, 2))).mean())
        line += (f" | C 1 process {c1_rate:,.0f} states/s | C {threads} processes {pool_rate:,.0f} states/s "
                 f"(pool start {start_s:.1f} s) | C rollout {threads} threads {roll_rate:,.0f} states/s "
                 f"(verdicts agree with the loop on {roll_agree:.4f})")
        if not args.skip_mjx:
            from jax3dc.physics.mjx_backend import compile_pair_distances  # lazy: as jax above (0.07 s more)
            t0 = time.perf_counter()
            fn = compile_pair_distances(m)
            q = jnp.asarray(qpos, dtype=jnp.float32)
            out = jax.block_until_ready(fn(q))
            compile_s = time.perf_counter() - t0
            kept = fn.survivors(q) / len(qpos)
            reps = 1 if args.small else 5
            t0 = time.perf_counter()
            for _ in range(reps):
                out = fn(q)
            jax.block_until_ready(out)
            g_rate = reps * len(qpos) / (time.perf_counter() - t0)
            pen_c = (c_all < -tol).any(axis=(1, 2))
            pen_g = (np.asarray(out) < -tol).any(axis=(1, 2))
            agree = float((pen_c == pen_g).mean())
            g = np.asarray(out, dtype=np.float64)
            both = np.isfinite(c_all) & np.isfinite(g)
            depth_gap_mm = 1e3 * float(np.abs(g[both] - c_all[both]).max()) if both.any() else 0.0
            line += (f" | MJX compile {compile_s:.1f} s | broad phase keeps {kept:.1f} of {len(fn.pairs)} geom pairs per state | MJX {g_rate:,.0f} states/s = {g_rate / c_rate:.2f}x the fastest C"
                     f" | verdict agreement {agree:.4f} (penetrating states C {int(pen_c.sum())} MJX {int(pen_g.sum())};"
                     f" contact depths within {depth_gap_mm:.2f} mm of C's)")
        print(line, flush=True)


if __name__ == "__main__":
    main()
