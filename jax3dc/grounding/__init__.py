"""Joints grounded in part geometry at decode time (see ``jax3dc.grounding.ground``)."""

from jax3dc.grounding.ground import Grounding, ground_joint, ground_structure, ground_text
from jax3dc.grounding.prior import CLASSES, JointPrior, shipped_prior

__all__ = ["CLASSES", "Grounding", "JointPrior", "ground_joint", "ground_structure", "ground_text", "shipped_prior"]
