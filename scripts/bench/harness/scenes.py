"""Scenes the benchmarks render: Blender's empty scene, the demo scene, a preset, each rendering
with Shading Lab at a size; lights with Blender's defaults but for what a benchmark sets; an
orthographic camera; one group of objects shown at a time."""

from __future__ import annotations

import math


def ready(scene, size: tuple[int, int], engine: str = "SHADING_LAB"):
    """``scene`` rendering with ``engine`` at ``size`` (100 %)."""
    scene.render.engine = engine
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    return scene


def empty(size: tuple[int, int]):
    """Blender's empty factory scene (the add-on registered), rendering with Shading Lab."""
    import demo_scene

    return demo_scene.empty_scene(*size)


def demo(size: tuple[int, int]):
    """The demo scene (``scripts/demo_scene.py``) at ``size``."""
    import demo_scene

    scene = empty(size)
    demo_scene.build(scene)
    return scene


def preset(name: str, size: tuple[int, int], variant: str | None = None):
    """A shipped scene preset (or demo, startup, a .toml or .blend: ``render.load_scene``)."""
    import render as cli

    cli.ensure_addon()
    scene, _stem = cli.load_scene(name, variant)
    if scene.camera is None:
        raise cli.CliError(f"{name}: the scene has no active camera")
    return ready(scene, size)


def black_world(scene):
    """A new black world (Blender 5's worlds are node-based: their Background's strength 0)."""
    import bpy

    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    for node in (world.node_tree.nodes if world.node_tree is not None else []):
        if node.bl_idname == "ShaderNodeBackground":
            node.inputs["Strength"].default_value = 0.0
    scene.world = world
    return world


def camera(scene, location, rotation_deg=(0.0, 0.0, 0.0), lens: float | None = None,
           ortho: float | None = None):
    """A camera at ``location`` turned by ``rotation_deg`` (degrees), made the scene's;
    orthographic ``ortho`` metres across when given."""
    import bpy

    data = bpy.data.cameras.new("Camera")
    if lens is not None:
        data.lens = lens
    if ortho is not None:
        data.type, data.ortho_scale = "ORTHO", ortho
    cam = bpy.data.objects.new("Camera", data)
    cam.location = location
    cam.rotation_euler = tuple(math.radians(a) for a in rotation_deg)
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def light(scene, name: str, kind: str, location=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0), **settings):
    """A light with Blender's defaults but for ``settings`` (the light data's properties)."""
    import bpy

    data = bpy.data.lights.new(name, kind)
    for key, value in settings.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(name, data)
    obj.location, obj.rotation_euler = location, rotation
    scene.collection.objects.link(obj)
    return obj


def show_only(groups: dict, key) -> None:
    """Render only the objects of ``groups[key]`` among the groups' objects."""
    for name, objs in groups.items():
        for obj in objs:
            obj.hide_render = name != key


def lights(scene, casting: bool = False) -> list:
    """The scene's lights (their data), only those casting a shadow with ``casting``."""
    return [o.data for o in scene.objects if o.type == "LIGHT" and (o.data.use_shadow or not casting)]


def filled_plane(size: tuple[int, int]):
    """(scene, plane): Blender's empty scene at ``size`` drawn by the physically based model's
    Principled set, a black world, and a 2 m plane filling an orthographic view from above (its
    lights are the benchmark's)."""
    import bpy

    scene = empty(size)
    scene.shading_lab.model = "PBR"
    scene.shading_lab.term_set = "PRINCIPLED"
    width, height = size
    camera(scene, (0.0, 0.0, 5.0), ortho=2.0)
    black_world(scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    plane.scale = (1.0, height / width, 1.0) if width >= height else (width / height, 1.0, 1.0)
    return scene, plane
