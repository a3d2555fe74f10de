"""MJCF (MuJoCo) export: the simulation model of ``jax3dc.export.simulation``, which the physics
checks also run on, written as ``<name>.xml`` beside ``meshes/<id>.obj`` (the visual meshes).

The base: roots are fixed to the world by default (the model has exactly the structure's joints,
ready to be placed in a scene); ``free=True`` gives each root a free joint so the object stands on
a floor, falls or can be pushed, except when ``mounted`` (a faucet, a toilet, a door or window
frame: fixed in place in use), whose base stays fixed. ``actuators=True`` adds a position servo per
joint (``servo_<id>``, control = the joint's target in radians or metres).

What a simulator does not need but a check of the file does rides along as MuJoCo custom text
(``<custom><text name=... data=...>``, ignored by simulation): the structure document
(``jax3dc_structure``: part ids, materials, relations; not the semantic names, which are data and
reach the file only as the labels' slugs), metres per nu (``jax3dc_scale``) and
whether the object is mounted (``jax3dc_mounted``). With them and ``meshes/<id>.obj`` (every
part's surface, a flat part's too though MuJoCo draws that one as a thin box) ``jax3dc physics
check object.xml`` checks the file itself: its bodies, joints and collision pieces
(``jax3dc.physics.exported``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import trimesh

from jax3dc.export.files import write_files
from jax3dc.export.simulation import ModelOptions, simulation_mjcf
from jax3dc.structure.schema import Structure
from jax3dc.structure.serialize import to_json

STRUCTURE_TEXT = "jax3dc_structure"  # custom text: the structure document
SCALE_TEXT = "jax3dc_scale"  # custom text: metres per nu, as Python writes the float (exact)
MOUNTED_TEXT = "jax3dc_mounted"  # custom text: "true" or "false"


def mjcf_model(structure: Structure, parts: dict[int, trimesh.Trimesh], scale: float = 1.0, *,
               model_name: str = "object", free: bool = False, mounted: bool = False,
               actuators: bool = False) -> tuple[str, dict[str, bytes]]:
    """MJCF text and its mesh files ({path relative to the MJCF file: bytes})."""
    model = simulation_mjcf(structure, parts, scale, ModelOptions(free_root=free and not mounted, actuators=actuators),
                            model_name=model_name)
    return _with_source(model.xml, structure, scale, mounted), model.files


def _with_source(xml: str, structure: Structure, scale: float, mounted: bool) -> str:
    """The model with its custom texts (see the module docstring) before its closing tag."""
    custom = ET.Element("custom")
    for name, data in ((STRUCTURE_TEXT, to_json(structure)), (SCALE_TEXT, repr(float(scale))),
                       (MOUNTED_TEXT, "true" if mounted else "false")):
        ET.SubElement(custom, "text", name=name, data=data)
    ET.indent(custom, space="  ", level=1)
    block = "  " + ET.tostring(custom, encoding="unicode") + "\n"
    end = xml.rindex("</mujoco>")
    return xml[:end] + block + xml[end:]


def export_mjcf(structure: Structure, parts: dict[int, trimesh.Trimesh], out_dir: str | Path, scale: float = 1.0, *,
                model_name: str = "object", free: bool = False, mounted: bool = False, actuators: bool = False) -> Path:
    """Write ``<out_dir>/<model_name>.xml`` and ``<out_dir>/meshes/<id>.obj``; returns the XML path."""
    text, files = mjcf_model(structure, parts, scale, model_name=model_name, free=free, mounted=mounted,
                             actuators=actuators)
    return write_files(Path(out_dir), f"{model_name}.xml", text, files)
