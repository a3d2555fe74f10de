"""Rollout throughput of the dynamic checks: MJX (vmapped ``mjx.step``) against C MuJoCo's threaded rollouts.

Limit reachability and the gravity test (``jax3dc.physics.dynamics``) hold servo targets for
``SETTLE_STEPS`` steps from rest and read where the joints (and the free root) end. Per object
this bench builds both models exactly as the checks do (reachability: frictionless, contact only
between the part pairs that the kinematic sweeps bring together; gravity: free root on a floor,
parts touching only the floor), draws ``--rollouts`` servo targets uniform in the joint ranges,
and times ``cpu_backend.final_qpos`` (``mujoco.rollout``, one thread per core) against
``mjx_dynamics.mjx_final_qpos`` on the same rows. Printed: rollouts/s and steps/s of each, the
ratio, MJX's compile time (the first call), and how far the final joint values of the two are
apart (largest difference; share of rows within the reachability tolerance).

GPU:   python3 bench/physics_rollouts.py --rollouts 4096
CPU smoke: python3 bench/physics_rollouts.py --objects laptop:0 --rollouts 64
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import jax
import numpy as np

from jax3dc.factories import generate_object
from jax3dc.physics import cpu_backend
from jax3dc.physics.dynamics import SETTLE_STEPS, reachability_model, tolerated_pairs
from jax3dc.physics.mjx_dynamics import mjx_final_qpos
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.states import check_states
from jax3dc.physics.tolerances import (DETACH_TOL_NU, LIMIT_TOL_HINGE_RAD, LIMIT_TOL_SLIDE_NU,
                                      PENETRATION_TOL_NU, RECONTACT_DEPTH_NU)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rollouts", type=int, default=4096, help="rollouts per model (default %(default)s)")
    parser.add_argument("--objects", default="cabinet:0,microwave:0,dishwasher:0",
                        help="comma list of category:seed (default %(default)s)")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")

    threads = os.cpu_count() or 1
    print(f"devices: {jax.devices()} | C rollout threads: {threads} | {SETTLE_STEPS} steps per rollout", flush=True)
    rng = np.random.default_rng(0)
    for spec in args.objects.split(","):
        category, seed = spec.split(":")
        obj = generate_object(category, int(seed))
        scale = obj.scale_m_per_nu
        kinematic = build_sim_model(obj.structure, obj.parts, scale, SimOptions(margin_m=DETACH_TOL_NU * scale))
        states = check_states(kinematic)
        distances = cpu_backend.pair_distances(kinematic.model, states.qpos)
        exclude = tolerated_pairs(kinematic, distances, PENETRATION_TOL_NU * scale, states, RECONTACT_DEPTH_NU * scale)
        models = {
            "reachability": reachability_model(obj.structure, obj.parts, scale, exclude, kinematic.pieces),
            "gravity": build_sim_model(obj.structure, obj.parts, scale, SimOptions(
                floor=True, free_root=True, actuators=True, floor_contacts_only=True), kinematic.pieces),
        }
        for check, sim in models.items():
            m = sim.model
            start = np.repeat(m.qpos0[None], args.rollouts, axis=0)
            ctrl = rng.uniform(sim.joint_range[:, 0], sim.joint_range[:, 1], size=(args.rollouts, len(sim.joint_qpos)))
            cpu_backend.final_qpos(m, start[:threads], ctrl[:threads], SETTLE_STEPS, threads)  # warm-up
            t0 = time.perf_counter()
            c = cpu_backend.final_qpos(m, start, ctrl, SETTLE_STEPS, threads)
            c_rate = args.rollouts / (time.perf_counter() - t0)
            t0 = time.perf_counter()
            mjx_final_qpos(m, start, ctrl, SETTLE_STEPS)
            first_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            g = mjx_final_qpos(m, start, ctrl, SETTLE_STEPS)
            g_rate = args.rollouts / (time.perf_counter() - t0)
            gap = np.abs(g[:, sim.joint_qpos] - c[:, sim.joint_qpos])
            tol = np.array([LIMIT_TOL_HINGE_RAD if t == "hinge" else LIMIT_TOL_SLIDE_NU * scale for t in sim.joint_type])
            within = float((gap <= tol).all(axis=1).mean())
            print(f"{obj.object_id} {check}: bodies {m.nbody} geoms {m.ngeom} joints {len(sim.joint_qpos)} "
                  f"explicit contact pairs {m.npair} | tolerated pairs {len(exclude)} | C {c_rate:,.0f} rollouts/s "
                  f"({c_rate * SETTLE_STEPS:,.0f} steps/s) | MJX {g_rate:,.0f} rollouts/s "
                  f"({g_rate * SETTLE_STEPS:,.0f} steps/s) = {g_rate / c_rate:.2f}x C | MJX first call "
                  f"(compile + run) {first_s:.1f} s | final joint values: largest gap {gap.max():.4f}, "
                  f"rows within the limit tolerance {within:.4f}", flush=True)


if __name__ == "__main__":
    main()
