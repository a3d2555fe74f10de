"""Every real import lands in the project frame (SPEC §2: +Z up, front -Y), checked over the whole
real training pool (../shared/real_train, skipped where absent) and the nine fixtures (issue 46).

Priors such as "lids hinge at the back" only transfer between objects in one shared frame, so
each category's frame facts are checked on every object: the base at the bottom, drawers sliding
out towards -Y, front doors in front of their body and swinging out in front of their hinge,
laptop / toilet / trash-can lids hinged about a horizontal axis at the back, caps, temples and
fridge doors turning about vertical axes. A fact that does not hold for an object is listed below
by object id with the reason found in its data (PartNet-Mobility has no frame errors that the
importer could fix here: every listed object is as its source models it).

Facts that do NOT hold widely enough to be priors, measured here at the time of writing: box lids
hinge at the back in 22 of 34 (a box has no defined front), stapler lids in 3 of 5, faucet
handles turn about a vertical axis in 17 of 24 (the rest are levers about a horizontal one).

Objects are imported with ``bounds_only`` (each mesh file read as its bounding box): the same
frames, joints and part boxes without building meshes, ~0.04 s of CPU per object.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from data_pipeline.importers.source import import_object
from tests.shared_fixtures import PARTNET_MOBILITY

POOL = Path(__file__).resolve().parents[3] / "shared" / "real_train" / "partnet_mobility"
TOLERANCE = 0.05
"""nu: how far a fact may miss (the object's largest extent is 1)."""
FRONT_OPENING = ("StorageFurniture", "Refrigerator", "Microwave", "Dishwasher", "Oven", "WashingMachine", "Safe",
                 "Table")
BACK_LIDS = {("Laptop", "screen"), ("Toilet", "lid"), ("TrashCan", "lid")}
HORIZONTAL_LIDS = {("Box", "rotation_lid"), ("Stapler", "lid"), ("Suitcase", "lid")} | BACK_LIDS
VERTICAL_AXES = {("Bottle", "rotation_lid"), ("Bottle", "translation_lid"), ("KitchenPot", "lid"),
                 ("Eyeglasses", "leg"), ("Faucet", "spout"), ("Knife", "rotation_blade"), ("Refrigerator", "door"),
                 ("Safe", "door"), ("Door", "rotation_door")}
HORIZONTAL_AXES = {("Bucket", "handle"), ("Dishwasher", "rotation_door"), ("Oven", "door"), ("Cart", "wheel")}
BELOW_THE_BASE = ("wheel", "caster", "leg")
"""Parts that may reach below an object's base (a cart's wheels, a chair's legs, folded temples)."""

QUIRKS = {
    "base at the bottom": {
        "oven_101808": "an edited copy turned 4 degrees about Z whose body hangs on a second, larger body link",
        "suitcase_move_101668": "the URDF roots the back shell; the front shell (labelled lid) reaches 0.05 lower",
        "suitcase_move_103755": "the URDF roots the back shell; the front shell (labelled lid) reaches 0.05 lower",
    },
    "drawer at the front, sliding out towards -Y": {
        "table_26387": "its three drawers are on the side PartNet-Mobility calls the back",
        "table_26608": "drawers on both sides: the four at the back slide out towards +Y",
        "table_33457": "one drawer sits in the table's end and slides along X",
        "drawer_29557": "the range runs into the body: the drawer rests open",
    },
    "door in front of its body, swinging out in front of its hinge": {
        "table_22433": "its three doors are flaps on the side PartNet-Mobility calls the back (+Y), hinged at the bottom",
        "table_23782": "its two doors are in the table's end (+X), not its front",
        "washing_machine_103508": "a top loader: its 'door' is a lid on top, hinged along one side",
    },
    "vertical axis": {
        "door_8867": "its handle is labelled rotation_door (a 0.06 nu part turning about a 45 degree axis)",
    },
    "horizontal axis": {
        "oven_101930": "an oven door hinged at its side",
    },
}


@dataclass(frozen=True)
class Motion:
    """One joint seen from the object's base: ``part`` moves against ``body`` (SPEC §2 units)."""

    object_id: str
    category: str
    name: str
    kind: str
    axis: np.ndarray
    pivot: np.ndarray
    range: tuple[float, float]
    part: tuple[np.ndarray, np.ndarray]  # the moving part's box: centroid, extent
    body: tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class Imported:
    object_id: str
    category: str
    base_bottom: float  # nu above the lowest part that is not a wheel, caster or leg
    motions: tuple[Motion, ...]


def _facts(folder: Path) -> Imported:
    """The frame facts of one object, as imported. Canonicalisation re-roots trees at the largest
    part, so each joint is turned back to the base's side: the part farther from the base moves."""
    obj = import_object(folder, bounds_only=True)
    nodes, boxes = obj.structure.nodes, obj.boxes
    box = {i: (np.asarray(b.centroid), np.asarray(b.extent)) for i, b in boxes.items()}
    (base,) = [i for i in nodes if str(i) not in obj.meta["source_joints"]]
    towards_base, node = set(), base
    while node is not None:
        towards_base.add(node)
        node = nodes[node].parent
    motions = []
    for child, n in nodes.items():
        if n.joint is None:
            continue
        lo, hi = n.joint.range
        part, body, rng = (n.parent, child, (-hi, -lo)) if child in towards_base else (child, n.parent, (lo, hi))
        motions.append(Motion(obj.meta["object_id"], obj.meta["category"], nodes[part].name, n.joint.type,
                              np.asarray(n.joint.axis), np.asarray(n.joint.pivot), rng, box[part], box[body]))
    bottoms = {i: c[2] - e[2] / 2 for i, (c, e) in box.items()}
    floor = min(z for i, z in bottoms.items() if not any(w in nodes[i].name for w in BELOW_THE_BASE) or i == base)
    return Imported(obj.meta["object_id"], obj.meta["category"], bottoms[base] - floor, tuple(motions))


@pytest.fixture(scope="module")
def imported() -> list[Imported]:
    fixtures = sorted(p for p in PARTNET_MOBILITY.iterdir() if (p / "mobility.urdf").is_file())
    assert len(fixtures) == 9, f"expected the nine fixtures in {PARTNET_MOBILITY}"
    pool = sorted(p for p in POOL.glob("*") if (p / "mobility.urdf").is_file()) if POOL.is_dir() else []
    if not pool:
        pytest.skip(f"the real training pool is not at {POOL}")
    return [_facts(folder) for folder in pool + fixtures]


def _open_extreme(motion: Motion) -> float:
    """The end of the range farther from the rest pose (the open end, where the rest is closed)."""
    lo, hi = motion.range
    return hi if abs(hi) >= abs(lo) else lo


def _in_front_half(m: Motion) -> bool:
    """The moving part's centre is not behind its body's (a drawer can run the body's depth)."""
    return m.part[0][1] <= m.body[0][1] + TOLERANCE


def _centroid_at(motion: Motion, angle: float) -> np.ndarray:
    turn = Rotation.from_rotvec(motion.axis * angle).as_matrix()
    return motion.pivot + turn @ (motion.part[0] - motion.pivot)


def _broken(imported: list[Imported], holds) -> set[str]:
    """Ids of the objects with a motion that breaks ``holds``."""
    return {m.object_id for obj in imported for m in obj.motions if not holds(m)}


def _check(broken: set[str], prior: str, checked: int) -> None:
    """The objects that break ``prior`` are exactly its listed quirks: an unlisted one is a frame
    error to fix, a listed one that now holds is a stale entry."""
    quirks = set(QUIRKS.get(prior, {}))
    assert checked > 0
    assert not broken - quirks, f"{prior}: broken by {sorted(broken - quirks)} (of {checked} checked)"
    assert not quirks - broken, f"{prior}: listed quirks that now hold: {sorted(quirks - broken)}"


def test_the_whole_pool_imports(imported):
    assert len(imported) == 337  # the pool's 328 objects and the nine fixtures
    assert len({o.object_id for o in imported}) == len(imported)


def test_base_at_the_bottom(imported):
    broken = {o.object_id for o in imported if o.base_bottom > TOLERANCE}
    _check(broken, "base at the bottom", len(imported))


def _drawer(m: Motion) -> bool:
    return m.kind == "slide" and "drawer" in m.name


def test_drawers_slide_out_towards_minus_y(imported):
    def holds(m: Motion) -> bool:
        out = m.axis * np.sign(_open_extreme(m))
        return not _drawer(m) or (out[1] < -0.9 and _in_front_half(m))

    checked = sum(_drawer(m) for o in imported for m in o.motions)
    _check(_broken(imported, holds), "drawer at the front, sliding out towards -Y", checked)


def _front_door(m: Motion) -> bool:
    return m.category in FRONT_OPENING and m.kind == "hinge" and "door" in m.name and "frame" not in m.name


def test_front_doors_swing_out_in_front_of_their_hinge(imported):
    def holds(m: Motion) -> bool:
        if not _front_door(m):
            return True
        # how far the door's centre lies behind its hinge line over the range: never farther than
        # at rest (a thick safe door hinged on its front face starts a little behind), and out in
        # front somewhere (a door resting open starts there)
        behind = [_centroid_at(m, a)[1] - m.pivot[1] for a in np.linspace(*m.range, 17)]
        at_rest = max(m.part[0][1] - m.pivot[1], 0.0)
        return _in_front_half(m) and max(behind) <= at_rest + TOLERANCE and min(behind) < -TOLERANCE

    checked = sum(_front_door(m) for o in imported for m in o.motions)
    _check(_broken(imported, holds), "door in front of its body, swinging out in front of its hinge", checked)


def test_lids_hinge_about_a_horizontal_axis_at_the_back(imported):
    def holds(m: Motion) -> bool:
        key = (m.category, m.name)
        if m.kind != "hinge" or key not in HORIZONTAL_LIDS:
            return True
        return abs(m.axis[2]) < 0.1 and (key not in BACK_LIDS or m.pivot[1] > m.body[0][1])

    checked = sum((m.category, m.name) in HORIZONTAL_LIDS for o in imported for m in o.motions)
    _check(_broken(imported, holds), "lid hinged at the back", checked)


@pytest.mark.parametrize("prior, members, holds", [
    ("vertical axis", VERTICAL_AXES, lambda m: abs(m.axis[2]) > 0.9),
    ("horizontal axis", HORIZONTAL_AXES, lambda m: abs(m.axis[2]) < 0.1),
])
def test_axes_by_category(imported, prior, members, holds):
    checked = sum((m.category, m.name) in members for o in imported for m in o.motions)
    _check(_broken(imported, lambda m: (m.category, m.name) not in members or holds(m)), prior, checked)


def test_bounds_only_import_matches_the_full_import():
    """The fast path the checks above use gives the full import's structure, joints and boxes."""
    for name in ("microwave_7119", "drawer_20453", "box_rotate_100189"):
        full, light = import_object(PARTNET_MOBILITY / name), import_object(PARTNET_MOBILITY / name, bounds_only=True)
        assert full.structure.nodes.keys() == light.structure.nodes.keys()
        for i, node in full.structure.nodes.items():
            other = light.structure.nodes[i]
            assert (node.parent, node.name) == (other.parent, other.name)
            assert (node.joint is None) == (other.joint is None)
            if node.joint is not None:
                for a, b in zip((node.joint.axis, node.joint.pivot, node.joint.range),
                                (other.joint.axis, other.joint.pivot, other.joint.range)):
                    np.testing.assert_allclose(a, b, atol=1e-9)
            np.testing.assert_allclose(full.boxes[i].centroid, light.boxes[i].centroid, atol=1e-9)
            np.testing.assert_allclose(full.boxes[i].extent, light.boxes[i].extent, atol=1e-9)
