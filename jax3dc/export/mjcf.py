"""MJCF (MuJoCo) export: the simulation model of ``jax3dc.export.simulation``, which the physics
checks also run on, written as ``<name>.xml`` beside ``meshes/<id>.obj`` (the visual meshes).

The base: roots are fixed to the world by default (the model has exactly the structure's joints,
ready to be placed in a scene); ``free=True`` gives each root a free joint so the object stands on
a floor, falls or can be pushed, except when ``mounted`` (a faucet, a toilet, a door or window
frame: fixed in place in use), whose base stays fixed. ``actuators=True`` adds a position servo per
joint (``servo_<id>``, control = the joint's target in radians or metres).
"""

from __future__ import annotations

from pathlib import Path

import trimesh

from jax3dc.export.files import write_files
from jax3dc.export.simulation import ModelOptions, simulation_mjcf
from jax3dc.structure.schema import Structure


def mjcf_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0, *,
               model_name: str = "object", free: bool = False, mounted: bool = False,
               actuators: bool = False) -> tuple[str, dict[str, bytes]]:
    """MJCF text and its mesh files ({path relative to the MJCF file: bytes})."""
    model = simulation_mjcf(structure, parts, scale, ModelOptions(free_root=free and not mounted, actuators=actuators),
                            model_name=model_name)
    return model.xml, model.files


def export_mjcf(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
                model_name: str = "object", free: bool = False, mounted: bool = False, actuators: bool = False) -> Path:
    """Write ``<out_dir>/<model_name>.xml`` and ``<out_dir>/meshes/<id>.obj``; returns the XML path."""
    text, files = mjcf_model(structure, parts, scale, model_name=model_name, free=free, mounted=mounted,
                             actuators=actuators)
    return write_files(Path(out_dir), f"{model_name}.xml", text, files)
