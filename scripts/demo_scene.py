"""The built-in demo scene: two rows of spheres (gold in front, red plastic behind, roughness
0.1 -> 0.9 from left to right) on a grey floor, lit by Blender's bundled courtyard HDRI and a key
sun whose 6-degree disc softens its shadow, seen from above and in front so that the rows and the
floor's grazing reflection (Fresnel) all show. Blinn-Phong and Phong take the world's light as
their ambient term, so the three models get the same light. Materials are ordinary Principled
BSDFs, so the same scene renders in Cycles and EEVEE too."""

from __future__ import annotations

import math

import bpy
from mathutils import Vector

from addon.blender.scene_builder import bundled_world_path
from addon.blender.scene_builder import principled_material as _principled

ROUGHNESS = (0.1, 0.3, 0.5, 0.7, 0.9)
RADIUS = 0.42
SPACING = 1.0  # between the spheres of a row, m
ROWS = {"Gold": -0.9, "Plastic": 1.1}  # y of each row: gold in front, plastic behind

WORLD = "courtyard"  # one of Blender's bundled worlds (datafiles/studiolights/world/<name>.exr)
WORLD_STRENGTH = 1.0
WORLD_ROTATION = -144.0  # degrees about Z: the courtyard's bright arch behind the camera

KEY_STRENGTH = 3.5  # W/m^2
KEY_ANGLE = 6.0  # degrees: the sun's apparent diameter, which softens its shadow
KEY_ELEVATION = 40.0  # degrees above the horizon
KEY_AZIMUTH = -130.0  # degrees: where the sun stands, counter-clockwise from +X (front left)

CAMERA = (0.0, -5.5, 5.0)
LOOK_AT = (0.0, 0.1, 0.35)
LENS = 40.0

FLOOR_COLOR = (0.25, 0.25, 0.25)
FLOOR_ROUGHNESS = 0.35


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
    bmesh.ops.create_uvsphere(bm, u_segments=48, v_segments=24, radius=RADIUS)
    bm.to_mesh(mesh)
    bm.free()
    mesh.shade_smooth()
    mesh.materials.append(material)
    obj = bpy.data.objects.new("Sphere", mesh)
    obj.location = location
    scene.collection.objects.link(obj)
    return obj


def _aim(obj, target):
    """Point ``obj``'s local -Z at ``target`` (local Y up), as cameras and lights look."""
    direction = Vector(target) - Vector(obj.location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler("XYZ")


def _world(name: str) -> bpy.types.World:
    """A world lit by Blender's bundled HDRI ``name``, turned ``WORLD_ROTATION`` about Z."""
    world = bpy.data.worlds.new("Demo")
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Strength"].default_value = WORLD_STRENGTH
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(bundled_world_path(name), check_existing=True)
    env.location = (background.location.x - 300.0, background.location.y)
    tree.links.new(env.outputs["Color"], background.inputs["Color"])
    if WORLD_ROTATION:
        coords = tree.nodes.new("ShaderNodeTexCoord")
        mapping = tree.nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(WORLD_ROTATION))
        tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    # The courtyard's brightest patch (up to 52 W/m^2/sr, 7 degrees above the horizon) stays in the
    # world's light instead of becoming a sun (EEVEE's World > Sun > Threshold, which Shading Lab
    # follows; 0: none): a 0.5-degree sun from it gave every sphere a second, hard-edged highlight
    # and terminator beside the key's.
    world.sun_threshold = 0.0
    world.color = (0.4, 0.4, 0.42)  # the viewport's Solid mode
    return world


def build(scene: bpy.types.Scene) -> None:
    floor = bpy.data.meshes.new("Floor")
    h = 40.0
    floor.from_pydata([(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], [], [(0, 1, 2, 3)])
    floor.materials.append(_principled("Floor", FLOOR_COLOR, 0.0, FLOOR_ROUGHNESS))
    obj = bpy.data.objects.new("Floor", floor)
    scene.collection.objects.link(obj)
    for i, r in enumerate(ROUGHNESS):
        x = (i - 2) * SPACING
        _sphere(scene, (x, ROWS["Plastic"], RADIUS), _principled(f"Plastic r{r}", (0.6, 0.05, 0.03), 0.0, r))
        _sphere(scene, (x, ROWS["Gold"], RADIUS), _principled(f"Gold r{r}", (1.0, 0.71, 0.29), 1.0, r))

    sun = bpy.data.lights.new("Key", "SUN")
    sun.energy = KEY_STRENGTH
    sun.angle = math.radians(KEY_ANGLE)
    sun.use_shadow = True
    key = bpy.data.objects.new("Key", sun)
    el, az = math.radians(KEY_ELEVATION), math.radians(KEY_AZIMUTH)
    key.location = (4.0 * math.cos(el) * math.cos(az), 4.0 * math.cos(el) * math.sin(az), 4.0 * math.sin(el))
    _aim(key, (0.0, 0.0, 0.0))
    scene.collection.objects.link(key)

    cam = bpy.data.cameras.new("Camera")
    cam.lens = LENS
    cam_obj = bpy.data.objects.new("Camera", cam)
    cam_obj.location = CAMERA
    _aim(cam_obj, LOOK_AT)
    scene.collection.objects.link(cam_obj)
    scene.camera = cam_obj

    scene.world = _world(WORLD)
    props = getattr(scene, "shading_lab", None)  # registered with the add-on
    if props is not None:
        props.ambient_source = "WORLD"  # Blinn-Phong and Phong: the same world light as ambient
        # the world's occlusion traced at every pixel: at half resolution its merge leaves streaks
        # on the floor beside the spheres
        props.occlusion_resolution = "FULL"
