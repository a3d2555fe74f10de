"""ProgramWriter.turn: a quarter turn about X, Y or Z moves every part's mesh and every joint alike."""

import numpy as np
import pytest
import trimesh

from jax3dc.factories.writer import JointSpec, ProgramWriter


def written(turns: int, axis: str):
    w = ProgramWriter()
    m = w.material("Wood", "pine")
    body = w.part("body", w.box((0.4, 0.2, 0.1), (0.2, 0.1, 0.05)), m)
    w.part("lid", w.box((0.1, 0.05, 0.02), (0.3, 0.15, 0.11)), m, parent=body,
           joint=JointSpec("hinge", (1.0, 0.0, 0.0), (0.25, 0.2, 0.1), (0.0, 1.2)))
    w.turn(turns, axis)
    return w.finish()


@pytest.mark.parametrize("axis", ["x", "y", "z"])
@pytest.mark.parametrize("turns", [1, 2, 3])
def test_quarter_turns_move_parts_and_joints_together(axis, turns):
    flat, turned = written(0, axis), written(turns, axis)
    k = "xyz".index(axis)
    rot = trimesh.transformations.rotation_matrix(np.pi / 2 * turns, np.eye(3)[k])[:3, :3]
    # Both are normalised (centred, scaled by the largest side); a quarter turn keeps the sides' set,
    # so the turned object is the flat one rotated about its own centre.
    for pid, mesh in flat.result.parts.items():
        np.testing.assert_allclose(np.sort(turned.result.parts[pid].vertices, axis=0),
                                   np.sort(mesh.vertices @ rot.T, axis=0), atol=2e-4)
    a, b = flat.structure.nodes[2].joint, turned.structure.nodes[2].joint
    np.testing.assert_allclose(b.axis, rot @ np.asarray(a.axis), atol=1e-12)
    np.testing.assert_allclose(b.pivot, rot @ np.asarray(a.pivot), atol=2e-4)
    assert b.range == a.range and all(v in (-1.0, 0.0, 1.0) for v in b.axis)


def test_unknown_axis_refused():
    w = ProgramWriter()
    with pytest.raises(ValueError, match="x, y or z"):
        w.turn(1, "w")
