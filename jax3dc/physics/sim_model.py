"""The simulation model the physics checks run on: the exported MJCF (``jax3dc.export.simulation``)
with the extras each check asks for, compiled, and the maps between parts, bodies and joints.

The checks differ from the exported file only by these options: no visual geoms, an explicit set
of excluded part pairs (none by default: the checks measure the contacts that the export leaves
out, ``travel_contacts``), and optionally a floor plane under the object, a free joint on each root
(gravity test), parts touching only the floor (one hull each), frictionless contacts or only
chosen contact pairs (reachability), a contact margin (proximity) and a position servo on every joint.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np
import trimesh

from jax3dc.export.assembly import ExportPart
from jax3dc.export.simulation import ModelOptions, simulation_mjcf
from jax3dc.structure.schema import Structure

MODEL_NAME = "physics_check"


@dataclass(frozen=True)
class SimOptions:
    """Which extras the model carries; each check asks only for what it needs."""

    floor: bool = False
    free_root: bool = False
    actuators: bool = False
    visual: bool = False
    exclude: frozenset[tuple[int, int]] = frozenset()  # part pairs (a < b) never in contact
    frictionless: bool = False  # condim 1: only collisions block motion (reachability)
    floor_contacts_only: bool = False  # parts touch the floor (one hull each) and other objects of a scene, not their own object (gravity test)
    margin_m: float = 0.0  # contacts of moving parts are reported up to this distance apart (proximity)
    # only these collision geom pairs (names) collide, through explicit frictionless pairs (requires
    # ``frictionless``): MJX compiles one collision function per distinct mesh pair it may test
    contact_pairs: frozenset[tuple[str, str]] | None = None

    def model_options(self) -> ModelOptions:
        return ModelOptions(**{f: getattr(self, f) for f in self.__dataclass_fields__})


@dataclass
class SimModel:
    """A compiled model and the maps between parts, bodies, geoms and joints."""

    xml: str
    assets: dict[str, bytes]
    model: mujoco.MjModel
    scale: float  # metres per nu
    part_body: dict[int, int]  # part id -> body id
    joint_parts: list[int]  # jointed parts in tree order; joint k moves part joint_parts[k]
    joint_qpos: np.ndarray  # [J] qpos address of each structure joint
    joint_type: list[str]  # "hinge" / "slide"
    joint_range: np.ndarray  # [J, 2] model units (rad / m)
    group_of_body: np.ndarray  # [nbody] rigid group: bodies welded together share one id (world: -1)
    moved_by: np.ndarray  # [J, nbody] bool: body moves when joint k moves (the child's subtree)
    parent_body: np.ndarray  # [J] body id of the moving part's parent
    pieces: dict[int, list[np.ndarray]] = field(default_factory=dict)  # part -> hull vertices (part frame, m)


def build_sim_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float,
                    options: SimOptions = SimOptions(), pieces: dict[int, list[np.ndarray]] | None = None) -> SimModel:
    """Compile the simulation model. ``pieces`` (from an earlier build) skips the decomposition."""
    built = simulation_mjcf(structure, parts, scale, options.model_options(), model_name=MODEL_NAME, pieces=pieces)
    model = built.compile()
    part_body = {p.part_id: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, p.label) for p in built.parts}
    return _sim_model(structure, built.parts, model, part_body, built.xml, built.files, scale, built.pieces)


def _sim_model(structure: Structure, export: list[ExportPart], model: mujoco.MjModel, part_body: dict[int, int],
               xml: str, assets: dict[str, bytes], scale: float, pieces) -> SimModel:
    jointed = [p for p in export if p.joint is not None]
    joint_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"joint_{p.part_id}") for p in jointed]
    # rigid groups: a body without a joint of its own is welded to its parent (a free root starts a group)
    group = np.full(model.nbody, -1)
    for b in range(1, model.nbody):
        has_dof = model.body_jntnum[b] > 0
        group[b] = b if (has_dof or model.body_parentid[b] == 0) else group[model.body_parentid[b]]
    moved = np.zeros((len(jointed), model.nbody), dtype=bool)
    for k, part in enumerate(jointed):
        child = part_body[part.part_id]
        for b in range(1, model.nbody):
            a = b
            while a > 0 and a != child:
                a = model.body_parentid[a]
            moved[k, b] = a == child
    return SimModel(
        xml=xml, assets=assets, model=model, scale=scale, part_body=part_body,
        joint_parts=[p.part_id for p in jointed],
        joint_qpos=np.array([model.jnt_qposadr[j] for j in joint_ids], dtype=np.int64),
        joint_type=[p.joint.type for p in jointed],
        joint_range=np.array([p.range_si for p in jointed], dtype=np.float64).reshape(-1, 2),
        group_of_body=group, moved_by=moved,
        parent_body=np.array([part_body[p.parent] for p in jointed], dtype=np.int64),
        pieces=pieces,
    )
