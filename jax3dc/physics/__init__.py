"""Physics plausibility checks of an articulated structure (SPEC §8, issue 8).

``check_object(structure, parts, scale)`` builds a simulation MJCF (``sim_model``), evaluates the
checks on batches of joint states (``states``) through C MuJoCo (``cpu_backend``, the default)
or MJX (``mjx_backend``, vmapped, for accelerators), and returns a per-joint / per-object verdict
with short reasons (``verdict``). The checks are small functions chosen by name
(``verdict.CHECKS``); their findings make a typed ``findings.Verdict``, JSON only at the edges.
Each check uses only the simulator stages it needs: the
interpenetration and attachment checks are kinematics + collision (or distance) only; stability
and limit reachability are short dynamics rollouts. Tolerances live in ``tolerances``.
"""

from jax3dc.physics.verdict import check_object

__all__ = ["check_object"]
