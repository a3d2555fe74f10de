"""A jointed part that another joint's sweep carries into a third part is blamed (jax3dc.physics.verdict)."""

from __future__ import annotations

from eval.verdict_accuracy.ground_truth import changes_motion
from eval.verdict_accuracy.mutations import mutations_of
from jax3dc.factories import generate_object
from jax3dc.physics.verdict import check_object


def test_rack_hung_on_the_dishwasher_door_is_swung_through_the_tub():
    dishwasher = generate_object("dishwasher", 0)
    nodes = dishwasher.structure.nodes
    rack = next(p for p, n in nodes.items() if n.name == "rack")
    mutation = next(m for m in mutations_of(dishwasher.structure, dishwasher.parts)
                    if m.kind == "attached to a far part" and m.part == rack)
    door = mutation.structure.nodes[rack].parent  # the door's handle, welded to the door
    while nodes[door].joint is None:
        door = nodes[door].parent
    assert nodes[door].name == "door"  # its sweep now carries the rack
    assert changes_motion(dishwasher.structure, mutation, dishwasher.parts)
    reasons = check_object(mutation.structure, dishwasher.parts, dishwasher.scale_m_per_nu,
                           dynamics=False)["joints"][str(rack)]["reasons"]
    assert any(r.startswith("penetrates part") and f"while joint {door} moves" in r for r in reasons), reasons
    truth = check_object(dishwasher.structure, dishwasher.parts, dishwasher.scale_m_per_nu, dynamics=False)
    assert truth["joints"][str(rack)]["ok"] and truth["joints"][str(door)]["ok"], truth
