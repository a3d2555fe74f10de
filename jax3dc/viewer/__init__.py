"""The interactive viewer: one HTML page per object with the object in 3D, a slider per joint,
the physics verdict, the images I and S, and the relations (issue 33).

``write_viewer`` writes it from a GLB made by ``jax3dc.export.gltf`` (whose node extras carry the
structure), so what the page shows is the exported object itself. ``jax3dc view`` opens one.
"""

from jax3dc.viewer.page import ViewerInputs, write_viewer

__all__ = ["ViewerInputs", "write_viewer"]
