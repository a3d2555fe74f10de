"""The joint states each kinematic check visits, as one batch (so one vmapped call covers them).

Row 0 is the rest pose; then ``SWEEP_STEPS`` states per joint sweeping it from lo to hi with every
other joint at rest; then ``RANDOM_COMBINATIONS`` states with all joints drawn uniformly in their
ranges. Values are in model units (rad / metres) at the model's qpos addresses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jax3dc.physics.sim_model import SimModel
from jax3dc.physics.tolerances import RANDOM_COMBINATIONS, SWEEP_STEPS


@dataclass(frozen=True)
class StateBatch:
    qpos: np.ndarray  # [S, nq]
    joint: np.ndarray  # [S] the swept joint index, -1 for rest, -2 for a random combination
    value: np.ndarray  # [S] the swept joint's value (model units), 0 otherwise


def check_states(sim: SimModel, steps: int = SWEEP_STEPS, combinations: int = RANDOM_COMBINATIONS,
                 seed: int = 0) -> StateBatch:
    rest = sim.model.qpos0.copy()
    rows, joints, values = [rest], [-1], [0.0]
    for k, adr in enumerate(sim.joint_qpos):
        for v in np.linspace(sim.joint_range[k, 0], sim.joint_range[k, 1], steps):
            q = rest.copy()
            q[adr] = v
            rows.append(q)
            joints.append(k)
            values.append(float(v))
    if len(sim.joint_qpos) > 1:
        rng = np.random.default_rng(seed)
        for _ in range(combinations):
            q = rest.copy()
            q[sim.joint_qpos] = rng.uniform(sim.joint_range[:, 0], sim.joint_range[:, 1])
            rows.append(q)
            joints.append(-2)
            values.append(0.0)
    return StateBatch(np.asarray(rows), np.asarray(joints), np.asarray(values))
