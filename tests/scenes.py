"""Scene builders and pixel helpers shared by the tests (bpy only, no add-on internals)."""

from __future__ import annotations

import math
from pathlib import Path

import bpy
import numpy as np
import OpenEXR


def reset(engine: str = "SHADING_LAB", size: int = 64) -> bpy.types.Scene:
    """An empty scene with a black world, rendering at ``size`` x ``size``."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = engine
    scene.render.resolution_x = size
    scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    world = bpy.data.worlds.new("Black")
    world.color = (0.0, 0.0, 0.0)
    if world.node_tree is not None:  # Blender 5 worlds are node-based: a 0.05 grey by default
        for node in world.node_tree.nodes:
            if node.bl_idname == "ShaderNodeBackground":
                node.inputs["Strength"].default_value = 0.0
    scene.world = world
    scene.view_settings.view_transform = "Standard"
    return scene


def node_tree(idb) -> bpy.types.NodeTree:
    """A material's or world's node tree; Blender 4.x makes it only when nodes are switched on."""
    if idb.node_tree is None:
        idb.use_nodes = True
    return idb.node_tree


def ortho_camera(scene, location=(0.0, 0.0, 5.0), rotation=(0.0, 0.0, 0.0), scale=2.0):
    data = bpy.data.cameras.new("Camera")
    data.type = "ORTHO"
    data.ortho_scale = scale
    data.clip_start = 0.01
    data.clip_end = 1000.0
    cam = bpy.data.objects.new("Camera", data)
    cam.location = location
    cam.rotation_euler = rotation
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def plane(scene, size=2.0, location=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0), material=None):
    half = size / 2.0
    mesh = bpy.data.meshes.new("Plane")
    mesh.from_pydata([(-half, -half, 0), (half, -half, 0), (half, half, 0), (-half, half, 0)], [],
                     [(0, 1, 2, 3)])
    obj = bpy.data.objects.new("Plane", mesh)
    obj.location = location
    obj.rotation_euler = rotation
    if material is not None:
        mesh.materials.append(material)
    scene.collection.objects.link(obj)
    return obj


def light(scene, kind="POINT", energy=100.0, location=(0.0, 0.0, 1.0), rotation=(0.0, 0.0, 0.0),
          color=(1.0, 1.0, 1.0), **props):
    data = bpy.data.lights.new(kind.title(), kind)
    data.energy = energy
    data.color = color
    data.use_shadow = False
    if kind != "SUN":
        data.shadow_soft_size = 0.0
        if hasattr(data, "use_soft_falloff"):
            data.use_soft_falloff = False
    else:
        data.angle = 0.0
    for key, value in props.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(kind.title(), data)
    obj.location = location
    obj.rotation_euler = rotation
    scene.collection.objects.link(obj)
    return obj


def material(name="Material", **overrides) -> bpy.types.Material:
    """A material whose Shading Lab values are set explicitly: ``base_color=(…)`` ticks
    ``use_base_color`` and sets the value, and so on for every property."""
    mat = bpy.data.materials.new(name)
    for key, value in overrides.items():
        setattr(mat.shading_lab, "use_" + key, True)
        setattr(mat.shading_lab, key, value)
    return mat


def unread_material(name="Haired") -> bpy.types.Material:
    """A material whose surface is a Hair BSDF (a shader Shading Lab does not compile)."""
    mat = bpy.data.materials.new(name)
    tree = node_tree(mat)
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(tree.nodes.new("ShaderNodeBsdfHair").outputs[0], out.inputs["Surface"])
    return mat


def saved_float_image(name: str, pixels: np.ndarray, folder: Path) -> bpy.types.Image:
    """A 32-bit float image of ``pixels`` (h, w, 4; bottom row first), saved as OpenEXR in
    ``folder`` as an artist's file is (an unsaved image is read again for every render)."""
    h, w = pixels.shape[:2]
    image = bpy.data.images.new(name, w, h, float_buffer=True, alpha=False)
    image.use_half_precision = False
    image.pixels.foreach_set(np.asarray(pixels, np.float32).ravel())
    image.filepath_raw = str(Path(folder) / f"{name}.exr")
    image.file_format = "OPEN_EXR"
    image.save()
    return image


def render(scene, path: Path) -> np.ndarray:
    """Render to a 32-bit OpenEXR and read it back: (height, width, 4) float32, top row first."""
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # Blender 5.0: a multilayer save before leaves it so
        settings.media_type = "IMAGE"
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return read_exr(path)


def save_result(scene, path: Path, kind: str) -> Path:
    """Save the last render result as ``kind``: EXR (32-bit), MULTILAYER (32-bit EXR with every
    pass) or PNG (8-bit through the view transform, no dither)."""
    settings = scene.render.image_settings
    multilayer = kind == "MULTILAYER"
    if hasattr(settings, "media_type"):  # Blender 5.0 groups formats by media type
        settings.media_type = "MULTI_LAYER_IMAGE" if multilayer else "IMAGE"
    if kind == "PNG":
        settings.file_format = "PNG"
        settings.color_mode = "RGBA"
        settings.color_depth = "8"
        scene.render.dither_intensity = 0.0
    else:
        settings.file_format = "OPEN_EXR_MULTILAYER" if multilayer else "OPEN_EXR"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
    bpy.data.images["Render Result"].save_render(filepath=str(path), scene=scene)
    return path


def read_png(path: Path) -> np.ndarray:
    """8-bit PNG as stored: (height, width, 4) integers 0..255, top row first."""
    img = bpy.data.images.load(str(path))
    try:
        img.colorspace_settings.name = "Non-Color"  # no conversion: the stored code values
        w, h = img.size
        px = np.empty(w * h * 4, np.float32)
        img.pixels.foreach_get(px)
    finally:
        bpy.data.images.remove(img)
    return np.rint(px.reshape(h, w, 4)[::-1] * 255.0).astype(np.int32)


def read_exr_layers(path: Path) -> dict[str, np.ndarray]:
    """Every RGBA pass of a multilayer EXR by pass name, (height, width, 4), top row first."""
    out = {}
    with OpenEXR.File(str(path)) as f:
        for part in f.parts:
            for name, channel in part.channels.items():
                out[name.split(".")[-1]] = np.asarray(channel.pixels, np.float32)
    return out


def read_exr(path: Path) -> np.ndarray:
    with OpenEXR.File(str(path)) as f:
        channels = f.channels()
        if "RGBA" in channels:
            return np.asarray(channels["RGBA"].pixels, np.float32)
        if "RGB" in channels:
            rgb = np.asarray(channels["RGB"].pixels, np.float32)
            return np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,), np.float32)], axis=-1)
        return np.stack([np.asarray(channels[c].pixels, np.float32) for c in "RGBA"], axis=-1)


def ortho_pixel_rays(size: int, scale: float, cam_matrix: np.ndarray):
    """World-space origins (size, size, 3) of an orthographic camera's pixel-centre rays, top row
    first, and the common ray direction."""
    centres = (np.arange(size) + 0.5) / size - 0.5
    x = centres[None, :] * scale
    y = -centres[:, None] * scale  # top row first
    local = np.stack([np.broadcast_to(x, (size, size)), np.broadcast_to(y, (size, size)),
                      np.zeros((size, size)), np.ones((size, size))], axis=-1)
    origins = local @ np.asarray(cam_matrix, np.float64).T
    direction = -np.asarray(cam_matrix, np.float64)[:3, 2]
    return origins[..., :3], direction / np.linalg.norm(direction)


def intersect_plane(origins, direction, point, normal):
    """Points where parallel rays meet the plane through ``point`` with ``normal``."""
    t = np.sum((np.asarray(point) - origins) * normal, axis=-1) / float(np.dot(direction, normal))
    return origins + t[..., None] * direction


def euler_matrix(rotation) -> np.ndarray:
    rx, ry, rz = rotation
    cx, sx, cy, sy, cz, sz = (math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry),
                              math.cos(rz), math.sin(rz))
    X = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Z @ Y @ X  # Blender's XYZ Euler order


#: Radiance of ``lambert_scene``'s plane: rho / pi * E * cos 45 degrees.
LAMBERT = 0.5 / math.pi * 2.0 * math.cos(math.radians(45.0))


def lambert_scene(size: int = 8):
    """An orthographic camera over a Lambert plane (rho 0.5, no specular) under a 2 W/m^2 sun at
    45 degrees: every model renders ``LAMBERT`` everywhere."""
    scene = reset(size=size)
    scene.shading_lab.ambient = 0.0
    ortho_camera(scene)
    mat = material(base_color=(0.5, 0.5, 0.5), f0=0.0, metalness=0.0, shininess=10.0,
                   specular_color=(0.0, 0.0, 0.0))
    plane(scene, size=4.0, material=mat)
    light(scene, "SUN", energy=2.0, rotation=(math.radians(45.0), 0.0, 0.0))
    return scene
