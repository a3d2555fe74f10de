"""The private MJX functions we use (``mujoco.mjx._src``), in one place, behind a version check.

``geom_pairs`` is MJX's own candidate-pair filter (contype/conaffinity, parent filtering, explicit
pairs, excludes): using it keeps our broad phase on exactly the pairs ``mjx.collision`` would test.
It is not public API and may move or change in any release, so only the mujoco-mjx versions the
physics tests ran on are accepted; any other is a SetupError naming the installed version, raised
on import, instead of a wrong pair list or an AttributeError deep in a check.
"""

from __future__ import annotations

from importlib import metadata

from jax3dc.errors import SetupError

SUPPORTED_MJX = ((3, 17), (3, 18))
"""mujoco-mjx releases [first, last) whose private ``geom_pairs`` the physics tests cover."""


def check_mjx_version(version: str) -> None:
    """Raise SetupError unless ``version`` (as pip reports it) lies in SUPPORTED_MJX."""
    first, last = SUPPORTED_MJX
    try:
        release = tuple(int(part) for part in version.split(".")[:2])
    except ValueError:
        release = None
    if release is None or not first <= release < last:
        raise SetupError(
            f"mujoco-mjx {version} is not supported by the MJX physics backend (it uses MJX internals "
            f"tested on {first[0]}.{first[1]}.x only): pip install 'mujoco-mjx>={first[0]}.{first[1]},"
            f"<{last[0]}.{last[1]}', or check with the C backend (--backend c)")


check_mjx_version(metadata.version("mujoco-mjx"))

from mujoco.mjx._src.collision_driver import geom_pairs  # noqa: E402,F401  (after the version check)
