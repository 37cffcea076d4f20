"""Bake World: a world Shading Lab cannot read (a Sky Texture, procedural textures, math on
colours) rendered once by Cycles through an equirectangular panoramic camera into an image, which
then stands for the world in lighting and background.

Runs on the main thread from an operator, never inside ``render()``. The image is packed into the
file (it travels with the .blend) and remembered on the world with a fingerprint of the world's
node graph: ``extract`` uses it while the fingerprint matches and warns when the world changed
since the bake.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile

import bpy

#: The panoramic camera's rotation that makes Cycles' equirectangular camera image the world
#: exactly as an Environment Texture maps it (+X at the image centre, up along the top row):
#: checked by tests/test_world.py against a known environment image.
CAMERA_ROTATION = (math.pi / 2.0, 0.0, -math.pi / 2.0)


def world_fingerprint(world) -> str:
    """A hash of what the world's radiance depends on: its nodes, their settings, socket values,
    links and images."""
    h = hashlib.sha256()
    tree = world.node_tree
    h.update(repr(tuple(world.color)).encode())
    if tree is None:
        return h.hexdigest()[:16]
    for node in sorted(tree.nodes, key=lambda n: n.name):
        h.update(f"{node.name}|{node.bl_idname}".encode())
        for prop in node.bl_rna.properties:
            if prop.identifier in ("rna_type", "location", "width", "height", "dimensions", "select",
                                   "name", "label", "location_absolute", "warning_propagation"):
                continue
            value = getattr(node, prop.identifier, None)
            if isinstance(value, (int, float, str, bool)):
                h.update(f"{prop.identifier}={value!r}".encode())
            elif isinstance(value, bpy.types.ID):
                h.update(f"{prop.identifier}={value.name_full}#{value.session_uid}".encode())
            elif hasattr(value, "__len__") and not isinstance(value, bpy.types.bpy_prop_collection):
                h.update(f"{prop.identifier}={tuple(value)!r}".encode())
        for socket in node.inputs:
            if hasattr(socket, "default_value"):
                value = socket.default_value
                h.update(repr(tuple(value) if hasattr(value, "__len__") else value).encode())
    for link in tree.links:
        h.update(f"{link.from_node.name}.{link.from_socket.identifier}>{link.to_node.name}."
                 f"{link.to_socket.identifier}".encode())
    return h.hexdigest()[:16]


def bake_world(world, width: int = 1024, samples: int = 16) -> bpy.types.Image:
    """Render ``world`` with Cycles into a ``width`` x ``width / 2`` equirectangular float image,
    packed into the file."""
    scene = bpy.data.scenes.new("Shading Lab World Bake")
    cam_data = bpy.data.cameras.new("Shading Lab World Bake")
    cam = bpy.data.objects.new("Shading Lab World Bake", cam_data)
    folder = tempfile.mkdtemp(prefix="shading_lab_bake_")
    path = os.path.join(folder, "world.exr")
    try:
        scene.world = world
        scene.collection.objects.link(cam)
        scene.camera = cam
        cam.rotation_euler = CAMERA_ROTATION
        cam_data.type = "PANO"
        if hasattr(cam_data, "panorama_type"):
            cam_data.panorama_type = "EQUIRECTANGULAR"
        else:  # Blender before 4.0 kept it with Cycles' settings
            cam_data.cycles.panorama_type = "EQUIRECTANGULAR"
        r = scene.render
        r.engine = "CYCLES"
        r.resolution_x, r.resolution_y, r.resolution_percentage = width, width // 2, 100
        r.film_transparent = False
        scene.cycles.samples = samples
        scene.cycles.use_denoising = False
        scene.cycles.use_adaptive_sampling = False
        scene.cycles.pixel_filter_type = "BOX"
        scene.view_settings.view_transform = "Standard"
        settings = r.image_settings
        if hasattr(settings, "media_type"):
            settings.media_type = "IMAGE"
        settings.file_format = "OPEN_EXR"
        settings.color_depth = "32"
        r.filepath = path
        bpy.ops.render.render(write_still=True, scene=scene.name)
        name = f"{world.name} (baked by Shading Lab)"
        old = bpy.data.images.get(name)
        if old is not None:
            bpy.data.images.remove(old)
        image = bpy.data.images.load(path)
        image.name = name
        image.pack()
        image.filepath_raw = ""
        return image
    finally:
        bpy.data.objects.remove(cam)
        bpy.data.cameras.remove(cam_data)
        bpy.data.scenes.remove(scene)
        for file in os.listdir(folder):
            os.remove(os.path.join(folder, file))
        os.rmdir(folder)
