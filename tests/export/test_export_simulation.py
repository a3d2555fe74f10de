"""The exported MJCF is a simulation model: for every factory category and the PartNet-Mobility
samples it loads in MuJoCo, stands on a floor under gravity (a mounted object is held) with its
joints held at rest, each joint reaches both limits under its position servo, and the physics
checks run on the same bodies, masses, joints and collision pieces.

Each object is exported once (module-scoped fixture: the convex decomposition is most of the cost)
and shared by the tests; the rollouts use the checks' settle time and tolerances.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from data_pipeline.importers.source import import_object
from jax3dc.factories.registry import FACTORIES, generate_object
from jax3dc.physics.cpu_backend import final_qpos
from jax3dc.physics.dynamics import SETTLE_STEPS
from jax3dc.physics.sim_model import SimOptions, build_sim_model
from jax3dc.physics.tolerances import (DETACH_TOL_NU, GRAVITY_DRIFT_NU, GRAVITY_JOINT_DRIFT, GRAVITY_TILT_RAD,
                                       LIMIT_TOL_HINGE_RAD, LIMIT_TOL_SLIDE_NU)
from export_cases import CASES
from jax3dc.cli import main
from jax3dc.export.files import write_files
from jax3dc.export.mjcf import export_mjcf
from jax3dc.export.simulation import TIMESTEP_S, ModelOptions, SimulationMJCF, joint_inertia, simulation_mjcf
from jax3dc.geometry.parts import load_parts, save_parts
from jax3dc.mounted import is_mounted
from jax3dc.structure import to_json
from jax3dc.structure.schema import Structure
from tests.shared_fixtures import PARTNET_MOBILITY, partnet_object

SEED = 0
STAND_S = 2.0
PARTNET = sorted(p.name for p in PARTNET_MOBILITY.iterdir() if (p / "mobility.urdf").is_file())
OBJECTS = [f"factory-{c}" for c in sorted(FACTORIES)] + [f"partnet-{n}" for n in PARTNET]


@dataclass
class Exported:
    """One object's export with servos (loaded from its files) and what the tests compare it with."""

    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    scale: float
    mounted: bool
    sim: SimulationMJCF
    model: mujoco.MjModel


def _source(name: str) -> tuple[Structure, dict[int, trimesh.Trimesh], float, bool]:
    kind, key = name.split("-", 1)
    if kind == "factory":
        obj = generate_object(key, SEED)
        return obj.structure, obj.parts, obj.scale_m_per_nu, FACTORIES[key].mounted
    imported = import_object(partnet_object(key))
    return imported.structure, imported.parts, imported.meta["scale"], is_mounted(imported.meta.get("category"))


@pytest.fixture(scope="module", params=OBJECTS)
def exported(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Exported:
    structure, parts, scale, mounted = _source(request.param)
    sim = simulation_mjcf(structure, parts, scale, ModelOptions(actuators=True))
    path = write_files(tmp_path_factory.mktemp(request.param), "object.xml", sim.xml, sim.files)
    return Exported(structure, parts, scale, mounted, sim, mujoco.MjModel.from_xml_path(str(path)))


def test_loads_with_the_structures_joints_and_a_servo_each(exported: Exported) -> None:
    model, joints = exported.model, exported.structure.joints()
    assert sorted(model.joint(j).name for j in range(model.njnt)) == sorted(f"joint_{p}" for p in joints)
    assert sorted(model.actuator(a).name for a in range(model.nu)) == sorted(f"servo_{p}" for p in joints)
    assert np.all(model.body_mass[1:] > 0)


def _full_turn(model: mujoco.MjModel, j: int) -> bool:
    """A hinge whose range is a whole turn: every angle is a pose of the object (a wheel rolled by settling)."""
    lo, hi = model.jnt_range[j]
    return int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE) and hi - lo >= 2 * np.pi - LIMIT_TOL_HINGE_RAD


def _servo_targets(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    """The control that holds every joint at its value in ``qpos``."""
    return np.array([qpos[model.jnt_qposadr[model.actuator_trnid[a, 0]]] for a in range(model.nu)])


def _standing(case: Exported) -> mujoco.MjModel:
    """The export on a floor plane under its lowest point, each root free to fall unless mounted."""
    spec = mujoco.MjSpec.from_string(case.sim.xml)
    spec.assets = case.sim.files  # from_string's own assets argument does not reach the mesh files
    if not case.mounted:
        for body in spec.worldbody.bodies:
            body.add_freejoint()
    lowest = min(float(np.asarray(mesh.vertices)[:, 2].min()) for mesh in case.parts.values()) * case.scale
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1], pos=[0, 0, lowest])
    return spec.compile()


def test_stands_under_gravity_with_joints_held(exported: Exported) -> None:
    """2 s on a floor with the servos holding the rest pose: the root neither walks nor tips over (the
    physics checks' gravity tolerances), a mounted one stays fixed, and no held joint sags."""
    model = _standing(exported)
    rest = model.qpos0.copy()
    final = final_qpos(model, rest[None], _servo_targets(model, rest)[None], round(STAND_S / TIMESTEP_S), threads=1)[0]
    free = [j for j in range(model.njnt) if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
    assert len(free) == (0 if exported.mounted else len(exported.structure.roots()))
    for j in free:
        adr = model.jnt_qposadr[j]
        drift = float(np.linalg.norm(final[adr:adr + 3] - rest[adr:adr + 3])) / exported.scale
        tilt = float(np.arccos(np.clip(Rotation.from_quat(final[adr + 3:adr + 7], scalar_first=True).as_matrix()[2, 2], -1, 1)))
        assert drift <= GRAVITY_DRIFT_NU and tilt <= GRAVITY_TILT_RAD, (drift, tilt)
    for j in range(model.njnt):
        if j in free or _full_turn(model, j):
            continue
        unit = 1.0 if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE) else exported.scale
        moved = abs(final[model.jnt_qposadr[j]] - rest[model.jnt_qposadr[j]]) / unit
        assert moved <= GRAVITY_JOINT_DRIFT, (model.joint(j).name, moved)


def test_each_joint_reaches_both_limits_under_its_servo(exported: Exported) -> None:
    """From rest, one servo at a time driven to a limit (the others hold rest) gets there within the
    checks' limit tolerance in their settle time."""
    model = exported.model
    rest = model.qpos0.copy()
    rows, targets = [], []
    for a in range(model.nu):
        j = model.actuator_trnid[a, 0]
        for end in (0, 1):
            ctrl = _servo_targets(model, rest)
            ctrl[a] = model.jnt_range[j, end]
            rows.append((j, end))
            targets.append(ctrl)
    if not rows:
        return
    final = final_qpos(model, np.repeat(rest[None], len(rows), axis=0), np.asarray(targets), SETTLE_STEPS, threads=1)
    missed = []
    for (j, end), q in zip(rows, final):
        hinge = int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        tol = LIMIT_TOL_HINGE_RAD if hinge else LIMIT_TOL_SLIDE_NU * exported.scale
        if abs(q[model.jnt_qposadr[j]] - model.jnt_range[j, end]) > tol:
            missed.append(f"{model.joint(j).name} {('lo', 'hi')[end]}: {q[model.jnt_qposadr[j]]:.3f} "
                          f"of {model.jnt_range[j, end]:.3f}")
    assert not missed, missed


def test_checks_run_on_the_exported_bodies_joints_and_collision(exported: Exported) -> None:
    """The physics checks' kinematic model is the export less its visual geoms, with their own
    contact settings: the same masses, inertias, joints (and their damping, friction, armature) and
    the same collision pieces, compiled."""
    check = build_sim_model(exported.structure, exported.parts, exported.scale,
                            SimOptions(margin_m=DETACH_TOL_NU * exported.scale), exported.sim.pieces).model
    model = exported.model
    for field in ("body_parentid", "body_pos", "body_mass", "body_ipos", "body_iquat", "body_inertia", "jnt_type",
                  "jnt_pos", "jnt_axis", "jnt_range", "dof_damping", "dof_frictionloss", "dof_armature"):
        np.testing.assert_array_equal(getattr(check, field), getattr(model, field), err_msg=field)
    collision = [g for g in range(model.ngeom) if model.geom_group[g] == 3]
    assert len(collision) == check.ngeom
    for field in ("geom_bodyid", "geom_pos", "geom_quat", "geom_size", "geom_friction"):
        np.testing.assert_array_equal(getattr(check, field), getattr(model, field)[collision], err_msg=field)
    for g, e in enumerate(collision):
        np.testing.assert_array_equal(_vertices(check, g), _vertices(model, e), err_msg=check.geom(g).name)


def _vertices(model: mujoco.MjModel, g: int) -> np.ndarray:
    mesh = model.geom_dataid[g]
    return model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]


def test_checks_with_the_exports_options_write_the_exported_xml() -> None:
    """The checks' builder, given the export's options, writes the exported file byte for byte."""
    structure, parts = CASES["cabinet"]()
    sim = simulation_mjcf(structure, parts, 0.8, ModelOptions(actuators=True), model_name="physics_check")
    pairs = frozenset({(1, 3)})
    check = build_sim_model(structure, parts, 0.8, SimOptions(visual=True, actuators=True, exclude=pairs), sim.pieces)
    assert check.xml == simulation_mjcf(structure, parts, 0.8, ModelOptions(actuators=True, exclude=pairs),
                                        model_name="physics_check", pieces=sim.pieces).xml
    assert check.assets == sim.files


def test_joint_servos_match_the_joint_inertia() -> None:
    """Damping, friction and armature are the family's multiples of the joint's effective inertia,
    which is MuJoCo's joint-space inertia; the servos are critically damped for it plus armature."""
    structure, parts = CASES["chain"]()
    sim = simulation_mjcf(structure, parts, 0.8, ModelOptions(actuators=True))
    model = sim.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    inertia = joint_inertia(sim.parts)
    for part in (p for p in sim.parts if p.joint is not None):
        j = model.joint(f"joint_{part.part_id}")
        dof = int(j.dofadr[0])
        props = part.props
        assert full[dof, dof] == pytest.approx(inertia[part.part_id] * (1 + props.joint_armature), rel=1e-6)
        assert model.dof_damping[dof] == pytest.approx(inertia[part.part_id] / props.joint_decay_s, rel=1e-6)
        assert model.dof_frictionloss[dof] == pytest.approx(inertia[part.part_id] * props.joint_friction, rel=1e-6)
        servo = model.actuator(f"servo_{part.part_id}")
        kp, kv = servo.gainprm[0], -servo.biasprm[2]
        assert kv ** 2 == pytest.approx(4 * kp * full[dof, dof], rel=1e-6)  # critically damped


def test_cli_base_is_fixed_unless_free_and_mounted_keeps_it(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    structure, parts = CASES["cabinet"]()
    save_parts(parts, tmp_path / "parts")
    (tmp_path / "structure.json").write_text(to_json(structure, names=True))

    def free_joints(*flags: str, category: str | None = None) -> int:
        (tmp_path / "meta.json").write_text(json.dumps({"scale": 0.8, "category": category}))
        out = tmp_path / "out"
        assert main(["export", str(tmp_path / "structure.json"), "--parts", str(tmp_path / "parts"), "--format", "mjcf",
                     "--out", str(out), *flags]) == 0
        model = mujoco.MjModel.from_xml_path(str(out / "structure.xml"))
        return int(np.sum(model.jnt_type == int(mujoco.mjtJoint.mjJNT_FREE)))

    assert free_joints() == 0
    assert free_joints("--free") == 1 and "free base" in capsys.readouterr().out
    assert free_joints("--free", category="Toilet") == 0 and "mounted: category Toilet" in capsys.readouterr().out
    assert free_joints("--free", "--no-mounted", category="toilet") == 1
    assert free_joints("--free", "--mounted") == 0
    assert main(["export", str(tmp_path / "structure.json"), "--parts", str(tmp_path / "parts"), "--format", "urdf",
                 "--out", str(tmp_path / "u"), "--actuators"]) == 1
    api = export_mjcf(structure, load_parts(tmp_path / "parts"), tmp_path / "api", 0.8, free=True, mounted=True,
                      model_name="structure")
    assert api.read_text() == (tmp_path / "out" / "structure.xml").read_text()
