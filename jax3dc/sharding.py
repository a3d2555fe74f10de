"""How arrays are laid out on a device mesh: ONE table from logical axis names to mesh axes.

Every parameter of the model carries logical axis names in its ``logical_axes`` metadata
(``embed``, ``mlp``, ``heads``, ``kv_heads``, ``vocab``, ``vision_embed``, …) and activations are
constrained at a few named points with :func:`constrain`. The mesh has three axes:

* ``data``   – pure data parallelism (parameters replicated),
* ``fsdp``   – data parallelism with parameters (and optimiser state) sharded along ``embed``,
* ``tensor`` – tensor parallelism inside a layer (heads, MLP width, vocabulary).

Changing the parallel layout means changing the table (a run sets it through
``TrainConfig.sharding_rules``, see :func:`with_overrides`) or the mesh shape, never model code.
The trainer's batch layout and the loss's shard_map read their mesh axes from the same table
(:func:`mesh_axes` of ``batch`` and ``vocab``). A logical axis whose size the mesh axes do not
divide is left replicated, so the same rules work for every model size and device count, and a
warning names it once (dimension, size, mesh axes): it is never replicated silently.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import logging
import math
from collections.abc import Iterator, Sequence
from typing import Any

import jax
from flax import nnx
from jax.sharding import Mesh, NamedSharding, PartitionSpec

MESH_AXES = ("data", "fsdp", "tensor")

MeshAxes = str | tuple[str, ...] | None
Rules = tuple[tuple[str, MeshAxes], ...]

LOGICAL_RULES: Rules = (
    # activations
    ("batch", ("data", "fsdp")),
    ("length", None),
    ("act_embed", None),
    ("act_heads", "tensor"),
    ("act_kv_heads", "tensor"),
    ("act_mlp", "tensor"),
    ("act_vocab", "tensor"),
    ("patches", None),
    # text decoder parameters
    ("vocab", "tensor"),
    ("embed", "fsdp"),
    ("mlp", "tensor"),
    ("heads", "tensor"),
    ("kv_heads", "tensor"),
    ("head_dim", None),
    ("norm", None),
    # vision tower parameters (frozen while fine-tuning: replicated over data, split over tensor)
    ("vision_patch", None),
    ("vision_embed", None),
    ("vision_heads", "tensor"),
    ("vision_mlp", "tensor"),
    ("vision_positions", None),
    ("vision_merged", "tensor"),
    ("qkv", None),
)

log = logging.getLogger(__name__)

_active_rules: contextvars.ContextVar[Rules] = contextvars.ContextVar("jax3dc_rules", default=LOGICAL_RULES)


def with_overrides(rules: Rules, overrides: Sequence[str]) -> Rules:
    """``rules`` with entries replaced by ``"logical=axis+axis"`` strings (``"logical="``: replicated).

    Raises ValueError naming an unknown logical or mesh axis, so a typo cannot pass as a layout.
    """
    table = dict(rules)
    for item in overrides:
        name, sep, axes_text = item.partition("=")
        name = name.strip()
        if not sep or name not in table:
            raise ValueError(f"sharding rule {item!r}: expected logical=axis[+axis] with logical one of "
                             f"{', '.join(table)}")
        axes = tuple(a.strip() for a in axes_text.split("+") if a.strip())
        unknown = [a for a in axes if a not in MESH_AXES]
        if unknown:
            raise ValueError(f"sharding rule {item!r}: mesh axes are {', '.join(MESH_AXES)}, not {', '.join(unknown)}")
        table[name] = None if not axes else axes[0] if len(axes) == 1 else axes
    return tuple(table.items())


def active_rules() -> Rules:
    """The table set by the innermost :func:`use_rules` (LOGICAL_RULES outside any)."""
    return _active_rules.get()


def mesh_axes(logical: str, mesh_shape: dict[str, int], rules: Rules) -> tuple[str, ...]:
    """The mesh axes (of size > 1 in this mesh) that ``logical`` maps to, in table order."""
    axes = dict(rules).get(logical)
    axes = () if axes is None else (axes,) if isinstance(axes, str) else tuple(axes)
    return tuple(a for a in axes if mesh_shape.get(a, 1) > 1)


@functools.cache
def warn_replicated(what: str, size: int, axes: tuple[str, ...], devices: int) -> None:
    """Log once that a dimension stays whole on every device because its mesh axes do not divide it."""
    log.warning("%s of size %d does not split over mesh axes %s (%d devices): replicated instead; "
                "change the sharding rules or the mesh shape to shard it", what, size, "x".join(axes), devices)


@contextlib.contextmanager
def use_rules(rules: Rules) -> Iterator[None]:
    """Makes ``rules`` the table that :func:`constrain` uses while tracing inside the block."""
    token = _active_rules.set(rules)
    try:
        yield
    finally:
        _active_rules.reset(token)


def make_mesh(data: int = 1, fsdp: int = -1, tensor: int = 1,
              devices: Sequence[jax.Device] | None = None) -> Mesh:
    """A (data, fsdp, tensor) mesh over ``devices`` (default: all); one size may be -1 = the rest."""
    devices = list(jax.devices() if devices is None else devices)
    shape = [data, fsdp, tensor]
    if shape.count(-1) > 1:
        raise ValueError("at most one mesh axis may be -1")
    known = math.prod(s for s in shape if s != -1)
    if -1 in shape:
        if len(devices) % known:
            raise ValueError(f"{len(devices)} devices do not split into {shape}")
        shape[shape.index(-1)] = len(devices) // known
    if math.prod(shape) != len(devices):
        raise ValueError(f"mesh {dict(zip(MESH_AXES, shape))} needs {math.prod(shape)} devices, "
                         f"have {len(devices)}")
    # Auto axes: the compiler propagates shardings from parameters and the few constraints
    return jax.make_mesh(tuple(shape), MESH_AXES, devices=devices,
                         axis_types=(jax.sharding.AxisType.Auto,) * len(MESH_AXES))


def _mesh_size(mesh_shape: dict[str, int], axes: MeshAxes) -> int:
    if axes is None:
        return 1
    axes = (axes,) if isinstance(axes, str) else axes
    return math.prod(mesh_shape.get(a, 1) for a in axes)


def logical_to_spec(logical_axes: Sequence[str | None], shape: Sequence[int] | None,
                    mesh_shape: dict[str, int], rules: Rules = LOGICAL_RULES) -> PartitionSpec:
    """PartitionSpec for an array with these logical axes. Mesh axes not in the mesh or already
    used by an earlier dimension are dropped; axes not dividing the dimension are dropped with a
    logged warning (:func:`warn_replicated`)."""
    table = dict(rules)
    used: set[str] = set()
    spec: list[MeshAxes] = []
    for i, name in enumerate(logical_axes):
        axes = table.get(name) if name is not None else None
        if axes is not None:
            axes_t = (axes,) if isinstance(axes, str) else tuple(axes)
            axes_t = tuple(a for a in axes_t if a in mesh_shape and mesh_shape[a] > 1 and a not in used)
            if shape is not None and axes_t and shape[i] % _mesh_size(mesh_shape, axes_t):
                warn_replicated(f"logical axis {name!r}", int(shape[i]), axes_t, _mesh_size(mesh_shape, axes_t))
                axes_t = ()
            used.update(axes_t)
            axes = (axes_t[0] if len(axes_t) == 1 else axes_t) if axes_t else None
        spec.append(axes)
    return PartitionSpec(*spec)


def constrain(x: jax.Array, logical_axes: Sequence[str | None]) -> jax.Array:
    """Pins an activation's layout when tracing under a mesh (``jax.set_mesh``); a no-op otherwise."""
    mesh = jax.sharding.get_abstract_mesh()
    if mesh.empty:
        return x
    spec = logical_to_spec(logical_axes, x.shape, dict(mesh.shape), active_rules())
    return jax.lax.with_sharding_constraint(x, spec)


def param_logical_axes(variable: Any) -> tuple[str | None, ...]:
    """The logical axes stored on an nnx Variable (``None`` everywhere if it has none)."""
    axes = getattr(variable, "logical_axes", None)
    if axes is None:
        return (None,) * len(variable.get_value().shape)
    return tuple(axes)


def state_shardings(state: Any, mesh: Mesh, rules: Rules = LOGICAL_RULES) -> Any:
    """A pytree like ``state`` (an nnx State, e.g. of ``nnx.eval_shape(...)``) holding the
    NamedSharding of each variable, computed from its logical axes and shape."""
    mesh_shape = dict(mesh.shape)

    def one(v):
        spec = logical_to_spec(param_logical_axes(v), v.get_value().shape, mesh_shape, rules)
        return v.replace(NamedSharding(mesh, spec))

    return jax.tree.map(one, state, is_leaf=lambda x: isinstance(x, nnx.Variable))


def model_shardings(abstract_model: Any, mesh: Mesh, rules: Rules = LOGICAL_RULES) -> Any:
    """NamedShardings of every parameter of an abstract (``nnx.eval_shape``) model, as an nnx State."""
    return state_shardings(nnx.state(abstract_model), mesh, rules)

