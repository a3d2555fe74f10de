"""Mass, centre of mass and inertia of a part from its mesh and a material density.

Part meshes from predictions and importers are often open or badly wound, where the signed
volume integral is meaningless. The solid used is therefore: the mesh itself when it is a
closed, consistently wound volume; else its convex hull; else (a flat or degenerate part, whose
hull has no volume) its axis-aligned box thickened to ``min_thickness`` — so every part gets a
positive mass and a positive definite inertia, which simulators require.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh


@dataclass(frozen=True)
class MassProperties:
    """In the mesh frame, after scaling: kg, metres, kg·m² about the centre of mass."""

    mass: float
    volume: float
    center_of_mass: np.ndarray  # [3]
    inertia: np.ndarray  # [3, 3] about center_of_mass, axes of the mesh frame
    solid: str  # "mesh", "convex hull" or "box": which solid the figures come from


def solid_of(mesh: trimesh.Trimesh, min_thickness: float = 1e-3) -> tuple[trimesh.Trimesh, str]:
    """The closed solid that stands for ``mesh`` in mass computations, and which kind it is."""
    with np.errstate(invalid="ignore", divide="ignore"):  # trimesh divides by zero volumes on the way
        if len(mesh.faces) and mesh.is_volume and mesh.volume > min_thickness ** 3:
            return mesh, "mesh"
        try:
            hull = mesh.convex_hull
            if hull.volume > min_thickness ** 3:
                return hull, "convex hull"
        except Exception:  # qhull fails on flat / collinear point sets
            pass
    lo, hi = np.asarray(mesh.bounds, dtype=np.float64)
    extents = np.maximum(hi - lo, min_thickness)
    box = trimesh.creation.box(extents=extents)
    box.apply_translation((lo + hi) / 2)
    return box, "box"


def mass_properties(mesh: trimesh.Trimesh, density: float, scale: float = 1.0,
                    min_thickness_m: float = 1e-3) -> MassProperties:
    """Mass properties of ``mesh`` scaled by ``scale`` (nu -> metres) at ``density`` (kg/m³)."""
    scaled = trimesh.Trimesh(np.asarray(mesh.vertices, dtype=np.float64) * scale,
                             np.asarray(mesh.faces), process=False)
    solid, kind = solid_of(scaled, min_thickness_m)
    volume = float(abs(solid.volume))
    props = trimesh.triangles.mass_properties(solid.triangles, density=density)
    inertia = np.asarray(props["inertia"], dtype=np.float64)
    com = np.asarray(props["center_mass"], dtype=np.float64)
    inertia = (inertia + inertia.T) / 2
    inertia[np.abs(inertia) < 1e-12 * np.abs(np.trace(inertia))] = 0.0  # round-off of symmetric solids
    return MassProperties(float(density * volume), volume, com, inertia, kind)
