"""The built-in demo scene: two rows of spheres (red plastic and gold, roughness 0.1 -> 0.9) on a
grey floor, lit by a point light and a sun, seen through a perspective camera. Materials are
ordinary Principled BSDFs, so the same scene renders in Cycles and EEVEE too."""

from __future__ import annotations

import math

import bpy

from addon.blender.scene_builder import principled_material as _principled

ROUGHNESS = (0.1, 0.3, 0.5, 0.7, 0.9)


def empty_scene(width: int | None = None, height: int | None = None) -> bpy.types.Scene:
    """The add-on registered and Blender's factory settings with an empty scene, rendered by
    Shading Lab (at ``width`` x ``height``, 100 %, when given): where the scripts start."""
    import addon

    addon.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "SHADING_LAB"
    if width and height:
        scene.render.resolution_x, scene.render.resolution_y = width, height
        scene.render.resolution_percentage = 100
    return scene


def _sphere(scene, location, material):
    mesh = bpy.data.meshes.new("Sphere")
    import bmesh

    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=48, v_segments=24, radius=0.42)
    bm.to_mesh(mesh)
    bm.free()
    mesh.shade_smooth()
    mesh.materials.append(material)
    obj = bpy.data.objects.new("Sphere", mesh)
    obj.location = location
    scene.collection.objects.link(obj)
    return obj


def build(scene: bpy.types.Scene) -> None:
    floor = bpy.data.meshes.new("Floor")
    floor.from_pydata([(-6, -4, 0), (6, -4, 0), (6, 5, 0), (-6, 5, 0)], [], [(0, 1, 2, 3)])
    floor.materials.append(_principled("Floor", (0.35, 0.35, 0.35), 0.0, 0.8))
    obj = bpy.data.objects.new("Floor", floor)
    scene.collection.objects.link(obj)
    for i, r in enumerate(ROUGHNESS):
        x = (i - 2) * 1.0
        _sphere(scene, (x, 0.6, 0.42), _principled(f"Plastic r{r}", (0.6, 0.05, 0.03), 0.0, r))
        _sphere(scene, (x, -0.6, 0.42), _principled(f"Gold r{r}", (1.0, 0.71, 0.29), 1.0, r))

    point = bpy.data.lights.new("Key", "POINT")
    point.energy = 400.0
    point.shadow_soft_size = 0.0
    key = bpy.data.objects.new("Key", point)
    key.location = (1.5, -2.5, 3.0)
    scene.collection.objects.link(key)
    sun = bpy.data.lights.new("Sun", "SUN")
    sun.energy = 2.0
    sun_obj = bpy.data.objects.new("Sun", sun)
    sun_obj.rotation_euler = (math.radians(50), 0.0, math.radians(-140))
    scene.collection.objects.link(sun_obj)

    cam = bpy.data.cameras.new("Camera")
    cam.lens = 40
    cam_obj = bpy.data.objects.new("Camera", cam)
    cam_obj.location = (0.0, -6.0, 1.9)
    cam_obj.rotation_euler = (math.radians(77), 0.0, 0.0)
    scene.collection.objects.link(cam_obj)
    scene.camera = cam_obj

    world = bpy.data.worlds.new("Demo")
    world.color = (0.02, 0.02, 0.025)
    if world.node_tree is not None:
        for node in world.node_tree.nodes:
            if node.bl_idname == "ShaderNodeBackground":
                node.inputs["Color"].default_value = (0.02, 0.02, 0.025, 1.0)
                node.inputs["Strength"].default_value = 1.0
    scene.world = world
