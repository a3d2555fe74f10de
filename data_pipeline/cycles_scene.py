"""Blender side of the Cycles restyle: run by the Python that has ``bpy`` (never imported by jax3dc).

bpy needs numpy < 2, so it lives in its own environment; ``data_pipeline.cycles`` decides every
random choice and writes a job (JSON + one .npz of posed part meshes per view), and this script
only builds each scene in Blender and renders it. Usage: ``PYTHON cycles_scene.py JOB.json``.

Each view is rendered to an RGBA PNG with a transparent film: the alpha is the object's coverage,
so the caller can check it against S and put its own background behind the object. The world
colour still lights the scene (film transparency only hides it from the camera).
"""

from __future__ import annotations

import json
import sys
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector


def clear_scene() -> None:
    """Remove every object, mesh, material and light of the previous view."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights,
                       bpy.data.cameras, bpy.data.worlds):
        for block in list(collection):
            collection.remove(block)


def make_mesh(name: str, vertices: np.ndarray, faces: np.ndarray) -> bpy.types.Object:
    """A triangle mesh object, filled through foreach_set (from_pydata is slow on large parts)."""
    mesh = bpy.data.meshes.new(name)
    n_v, n_f = len(vertices), len(faces)
    mesh.vertices.add(n_v)
    mesh.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
    mesh.loops.add(3 * n_f)
    mesh.loops.foreach_set("vertex_index", faces.astype(np.int32).ravel())
    mesh.polygons.add(n_f)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * n_f, 3, dtype=np.int32))
    mesh.update()
    mesh.validate()
    mesh.shade_smooth()
    mesh.set_sharp_from_angle(angle=0.6)  # cylinders look round, boxes keep their edges
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def make_material(name: str, spec: dict) -> bpy.types.Material:
    """Principled BSDF with the spec's colour, roughness, metallic, transmission and coat; a
    ``texture`` ("grain": wave bands, "speckle": noise) mixes the colour towards ``colour2``."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*spec["colour"], 1.0)
    bsdf.inputs["Roughness"].default_value = spec["roughness"]
    bsdf.inputs["Metallic"].default_value = spec["metallic"]
    bsdf.inputs["Transmission Weight"].default_value = spec["transmission"]
    bsdf.inputs["Coat Weight"].default_value = spec["coat"]
    texture = spec.get("texture")
    if texture:
        coords = nodes.new("ShaderNodeTexCoord")
        if texture == "grain":
            tex = nodes.new("ShaderNodeTexWave")
            tex.inputs["Scale"].default_value = spec["scale"]
            tex.inputs["Distortion"].default_value = 6.0
            tex.inputs["Detail"].default_value = 2.0
        else:
            tex = nodes.new("ShaderNodeTexNoise")
            tex.inputs["Scale"].default_value = spec["scale"]
            tex.inputs["Detail"].default_value = 6.0
        links.new(coords.outputs["Object"], tex.inputs["Vector"])
        mix = nodes.new("ShaderNodeMix")
        mix.data_type = "RGBA"
        mix.inputs["A"].default_value = (*spec["colour"], 1.0)
        mix.inputs["B"].default_value = (*spec["colour2"], 1.0)
        links.new(tex.outputs["Fac"], mix.inputs["Factor"])
        links.new(mix.outputs["Result"], bsdf.inputs["Base Color"])
    return mat


def make_camera(spec: dict) -> bpy.types.Object:
    """A camera at ``location`` whose 3x3 ``rotation`` has columns right, up, backward (Blender
    cameras look along their local -Z) and whose vertical field of view is ``fovy`` degrees."""
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = np.deg2rad(spec["fovy"])
    data.clip_start, data.clip_end = 0.01, 100.0
    cam = bpy.data.objects.new("camera", data)
    world = Matrix(spec["rotation"]).to_4x4()
    world.translation = spec["location"]
    cam.matrix_world = world
    bpy.context.scene.collection.objects.link(cam)
    return cam


def add_light(i: int, spec: dict) -> None:
    """A sun (``direction`` from the light towards the scene) or an area light at ``location``
    aimed at the origin."""
    data = bpy.data.lights.new(f"light{i}", type=spec["type"].upper())
    data.color = spec["colour"]
    data.energy = spec["energy"]
    obj = bpy.data.objects.new(f"light{i}", data)
    if spec["type"] == "sun":
        data.angle = np.deg2rad(spec.get("angle", 2.0))
        aim = -np.asarray(spec["direction"], dtype=np.float64)  # local +Z of a sun points at it
    else:
        data.size = spec["size"]
        obj.location = spec["location"]
        aim = np.asarray(spec["location"], dtype=np.float64)
    obj.rotation_euler = Vector(tuple(float(x) for x in aim)).to_track_quat("Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(obj)


def set_world(spec: dict) -> None:
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*spec["colour"], 1.0)
    background.inputs["Strength"].default_value = spec["strength"]
    bpy.context.scene.world = world


def configure(job: dict) -> None:
    bpy.ops.preferences.addon_enable(module="cycles")  # bpy as a module starts without its engines
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = job["samples"]
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.max_bounces = 4
    scene.cycles.use_denoising = job["denoise"]
    if job["denoise"]:
        scene.cycles.denoiser = "OPENIMAGEDENOISE"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = job["threads"]
    scene.render.resolution_x = scene.render.resolution_y = job["size"]
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    scene.render.image_settings.color_depth = "8"


def render_view(view: dict, job: dict) -> float:
    """Build and render one view; returns the seconds the render itself took."""
    clear_scene()
    scene = bpy.context.scene
    meshes = np.load(view["meshes"])
    for part in view["parts"]:
        obj = make_mesh(f"part{part['id']}", meshes[f"v{part['id']}"], meshes[f"f{part['id']}"])
        obj.data.materials.append(make_material(f"mat{part['id']}", part["material"]))
    scene.camera = make_camera(view["camera"])
    for i, light in enumerate(view["lights"]):
        add_light(i, light)
    set_world(view["world"])
    scene.view_settings.view_transform = view["view_transform"]
    scene.view_settings.exposure = view["exposure"]
    scene.render.filepath = view["png"]
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start


def main(path: str) -> None:
    with open(path) as f:
        job = json.load(f)
    configure(job)
    seconds = [render_view(view, job) for view in job["views"]]
    with open(job["timings"], "w") as f:
        json.dump(seconds, f)


if __name__ == "__main__":
    main(sys.argv[1])
