"""Builds a ``presets.ScenePreset`` into a Blender scene: camera, lights, meshes and materials.

Materials are ordinary Principled BSDFs carrying the preset's values, so Cycles and EEVEE render
the same surfaces; explicit Blinn-Phong/Phong values (shininess, specular colour) go to the
material's Shading Lab settings (``material.shading_lab``), ticked. Lights use Blender's units:
``energy`` is the power in W for point, spot and area lights and the irradiance in W/m^2 for a sun.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import bmesh
import bpy
from mathutils import Euler, Matrix, Vector

from ..scene import presets as P

_CAMERA_TYPES = {"perspective": "PERSP", "orthographic": "ORTHO"}
#: Principled IOR for F0 close to 1 (IOR -> infinity); beyond it the Shading Lab F0 is ticked.
_MAX_IOR = 100.0
_SHADING_LAB_KEYS = ("base_color", "metalness", "roughness", "f0", "shininess", "specular_color",
                     "ambient_color")


@dataclass
class BuiltScene:
    """What ``build_scene`` created."""

    collection: bpy.types.Collection
    camera: bpy.types.Object
    lights: list = field(default_factory=list)
    objects: list = field(default_factory=list)  # mesh objects (file objects: every imported mesh)
    materials: dict = field(default_factory=dict)  # MaterialPreset -> bpy material


def _radians(degrees) -> Euler:
    return Euler(tuple(math.radians(d) for d in degrees), "XYZ")


def _aim(obj, rotation, direction=None, look_at=None):
    """Orient a camera or light: Euler degrees, a travel direction or a point to face (local -Z
    forward, local Y up)."""
    if look_at is not None:
        direction = Vector(look_at) - Vector(obj.location)
    if direction is not None:
        obj.rotation_euler = Vector(direction).to_track_quat("-Z", "Y").to_euler("XYZ")
    else:
        obj.rotation_euler = _radians(rotation or (0.0, 0.0, 0.0))


def ior_from_f0(f0: float) -> float:
    """The IOR whose normal-incidence reflectance ((n - 1) / (n + 1))^2 is ``f0``."""
    s = math.sqrt(min(max(f0, 0.0), 1.0))
    return _MAX_IOR if s >= 1.0 else min((1.0 + s) / (1.0 - s), _MAX_IOR)


def _principled(material: bpy.types.Material):
    """The Principled BSDF feeding the material's active output, created and linked if needed."""
    if material.node_tree is None:
        material.use_nodes = True
    tree = material.node_tree
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    output = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
    if output is None:
        output = tree.nodes.new("ShaderNodeOutputMaterial")
    surface = output.inputs["Surface"]
    if surface.is_linked and surface.links[0].from_node.bl_idname == "ShaderNodeBsdfPrincipled":
        return surface.links[0].from_node
    node = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"), None)
    if node is None:
        node = tree.nodes.new("ShaderNodeBsdfPrincipled")
        node.location = (output.location.x - 300.0, output.location.y)
    tree.links.new(node.outputs["BSDF"], surface)
    return node


def principled_material(name: str, base, metallic: float = 0.0, roughness: float = 0.5,
                        ior: float = 1.5) -> bpy.types.Material:
    """A new material whose Principled BSDF carries these values (and the viewport's colour)."""
    material = bpy.data.materials.new(name)
    node = _principled(material)
    node.inputs["Base Color"].default_value = (*base, 1.0)
    node.inputs["Metallic"].default_value = metallic
    node.inputs["Roughness"].default_value = roughness
    node.inputs["IOR"].default_value = ior
    material.diffuse_color = (*base, 1.0)
    return material


def apply_material_preset(material: bpy.types.Material, preset: P.MaterialPreset) -> bpy.types.Material:
    """Give ``material`` the preset's values: its Principled BSDF (created and linked to the output
    if the surface is something else) carries base colour, metalness, roughness and the dielectric
    F0 as IOR; Shading Lab's explicit values are cleared, then set for shininess and specular
    colour when the preset has them. Returns ``material``."""
    node = _principled(material)
    rgba = (*preset.base_color, 1.0)
    node.inputs["Base Color"].default_value = rgba
    node.inputs["Metallic"].default_value = preset.metalness
    node.inputs["Roughness"].default_value = preset.roughness
    f0 = preset.dielectric_f0
    ior = preset.ior if preset.ior is not None else ior_from_f0(f0)
    node.inputs["IOR"].default_value = ior
    node.inputs["Specular IOR Level"].default_value = 0.5  # 0.5: F0 exactly from the IOR
    set_principled_inputs(node, {**{k: spec.default for k, spec in P.PRINCIPLED_INPUTS.items()},
                                 **dict(preset.principled)})
    material.diffuse_color = rgba  # the viewport's Solid mode and the extractor's fallback
    material.metallic = preset.metalness
    material.roughness = preset.roughness

    props = getattr(material, "shading_lab", None)  # registered with the add-on
    if props is not None:
        for key in _SHADING_LAB_KEYS:
            setattr(props, "use_" + key, False)
        if ior >= _MAX_IOR:  # the Principled IOR cannot say it: set F0 itself
            props.use_f0, props.f0 = True, f0
        if preset.shininess is not None:
            props.use_shininess, props.shininess = True, preset.shininess
        if preset.specular_color is not None:
            props.use_specular_color, props.specular_color = True, preset.specular_color
    return material


def set_principled_inputs(node, values: dict) -> None:
    """Set the Principled BSDF ``node``'s inputs named by ``values``' keys (``PRINCIPLED_INPUTS``'
    preset keys; the lobes the material preset leaves out at Blender's defaults, so a preset
    applied to a coated material leaves no coat behind)."""
    # by identifier: an unavailable input (Subsurface IOR outside the Random Walk (Skin) method) is
    # not found by name, yet keeps its value for when it is
    sockets = {socket.identifier: socket for socket in node.inputs}
    for key, value in values.items():
        socket = sockets[P.PRINCIPLED_INPUTS[key].socket]
        size = len(socket.default_value) if P.PRINCIPLED_INPUTS[key].color else 0
        socket.default_value = (*value, 1.0)[:size] if size else value


# --- geometry ----------------------------------------------------------------------------------

def _torus(bm, major: float, minor: float, segments: int):
    rings = max(segments // 2, 3)
    verts = []
    for i in range(segments):
        u = 2.0 * math.pi * i / segments
        for j in range(rings):
            v = 2.0 * math.pi * j / rings
            r = major + minor * math.cos(v)
            verts.append(bm.verts.new((r * math.cos(u), r * math.sin(u), minor * math.sin(v))))
    for i in range(segments):
        for j in range(rings):
            a = verts[i * rings + j]
            b = verts[((i + 1) % segments) * rings + j]
            c = verts[((i + 1) % segments) * rings + (j + 1) % rings]
            d = verts[i * rings + (j + 1) % rings]
            bm.faces.new((a, b, c, d))


def _sort_faces(bm) -> None:
    """Order ``bm``'s faces by their centres. bmesh's primitives weld their seams through a hash
    of element addresses, so the same primitive's faces (their corners) came out in another order
    in each process: the same triangles, interpolated by the rasteriser from other first corners,
    made renders of a preset differ in the last bits from run to run."""
    bm.faces.index_update()
    centres = [tuple(round(c, 6) for c in face.calc_center_median()) for face in bm.faces]
    rank = [0] * len(centres)
    for position, index in enumerate(sorted(range(len(centres)), key=centres.__getitem__)):
        rank[index] = position
    bm.faces.sort(key=lambda face: rank[face.index])


def primitive_mesh(obj: P.ObjectPreset) -> bpy.types.Mesh:
    """A new mesh for ``obj.primitive``, centred on the origin."""
    mesh = bpy.data.meshes.new(obj.name)
    kind = obj.primitive
    if kind == "plane":
        h = obj.size / 2.0
        mesh.from_pydata([(-h, -h, 0.0), (h, -h, 0.0), (h, h, 0.0), (-h, h, 0.0)], [], [(0, 1, 2, 3)])
    else:
        bm = bmesh.new()
        try:
            if kind == "cube":
                bmesh.ops.create_cube(bm, size=obj.size)
            elif kind == "uv_sphere":
                bmesh.ops.create_uvsphere(bm, u_segments=obj.segments, v_segments=max(obj.segments // 2, 2),
                                          radius=obj.radius)
            elif kind == "ico_sphere":
                bmesh.ops.create_icosphere(bm, subdivisions=obj.subdivisions, radius=obj.radius)
            elif kind == "cylinder":
                bmesh.ops.create_cone(bm, cap_ends=True, segments=obj.segments, radius1=obj.radius,
                                      radius2=obj.radius, depth=obj.depth)
            elif kind == "torus":
                _torus(bm, obj.radius, obj.minor_radius, obj.segments)
            else:
                raise ValueError(f"unknown primitive {kind!r}")
            _sort_faces(bm)
            bm.to_mesh(mesh)
        finally:
            bm.free()
    if obj.smooth:
        mesh.shade_smooth()
        if kind in ("cylinder", "cube"):
            mesh.set_sharp_from_angle(angle=math.radians(30.0))  # keep the caps' edges crisp
    else:
        mesh.shade_flat()
    return mesh


def _matrix(obj: P.ObjectPreset) -> Matrix:
    return Matrix.LocRotScale(Vector(obj.location), _radians(obj.rotation), Vector(obj.scale))


def _move_to(objects, collection):
    for ob in objects:
        for c in list(ob.users_collection):
            c.objects.unlink(ob)
        collection.objects.link(ob)


def _descendants(root, pool) -> list:
    out = [root]
    for ob in pool:
        if ob.parent is not None and ob.parent in out and ob not in out:
            out.append(ob)
    return out


def _load_file_object(scene, obj: P.ObjectPreset, collection, preset: P.ScenePreset, where: str) -> list:
    """The objects of a ``.blend`` (one named object, appended) or ``.glb`` (imported; only
    ``object`` and its children when named; imported cameras and lights are dropped)."""
    shown = P._display(preset.path)
    try:
        return _read_file_object(scene, obj, collection, shown, where)
    except P.PresetError:
        raise
    except Exception as exc:  # a corrupt or unreadable file: name it, never a traceback
        lines = [line.strip() for line in str(exc).strip().splitlines() if line.strip()]
        reason = lines[-1] if lines else type(exc).__name__  # the exception itself, after any traceback
        raise P.PresetError(shown, f"{where}.file", f"a readable {obj.file.suffix} file",
                            got=obj.file.name, note=reason) from None


def _check_glb(path) -> None:
    """Refuse a file that is not a glTF 2.0 binary before the importer sees it (the importer
    prints its own traceback on malformed input): magic, version, length and a JSON chunk."""
    import json
    import struct

    data = path.read_bytes()
    if len(data) < 20:
        raise ValueError("not a glTF binary: shorter than its 20-byte header")
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2:
        raise ValueError("not a glTF 2.0 binary (bad magic or version)")
    if length != len(data):
        raise ValueError(f"truncated glTF binary: header says {length} bytes, file has {len(data)}")
    chunk_length, chunk_type = struct.unpack_from("<I4s", data, 12)
    if chunk_type != b"JSON" or 20 + chunk_length > len(data):
        raise ValueError("glTF binary without a valid JSON chunk")
    json.loads(data[20:20 + chunk_length])


def _read_file_object(scene, obj: P.ObjectPreset, collection, shown: str, where: str) -> list:
    if obj.file.suffix.lower() == ".glb":
        _check_glb(obj.file)
    if obj.file.suffix.lower() == ".blend":
        with bpy.data.libraries.load(str(obj.file), link=False) as (src, dst):
            available = list(src.objects)
            if obj.object_name in available:
                dst.objects = [obj.object_name]
        if obj.object_name not in available:
            raise P.PresetError(shown, f"{where}.object",
                                f"an object of {obj.file.name}: one of " + ", ".join(available[:20]),
                                got=obj.object_name)
        new = [ob for ob in dst.objects if ob is not None]
        for ob in new:
            collection.objects.link(ob)
    else:
        import addon_utils

        if not addon_utils.check("io_scene_gltf2")[1]:
            addon_utils.enable("io_scene_gltf2", default_set=False)
        before = set(bpy.data.objects)
        with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
            bpy.ops.import_scene.gltf(filepath=str(obj.file))
        new = [ob for ob in bpy.data.objects if ob not in before]
        for ob in [ob for ob in new if ob.type in ("CAMERA", "LIGHT")]:
            new.remove(ob)
            bpy.data.objects.remove(ob)
        if obj.object_name is not None:
            root = next((ob for ob in new if ob.name == obj.object_name), None)
            if root is None:
                names = ", ".join(ob.name for ob in new[:20])
                for ob in new:
                    bpy.data.objects.remove(ob)
                raise P.PresetError(shown, f"{where}.object", f"an object of {obj.file.name}: one of {names}",
                                    got=obj.object_name)
            keep = _descendants(root, new)
            for ob in [ob for ob in new if ob not in keep]:
                bpy.data.objects.remove(ob)
            new = keep
            root.parent = None
        _move_to(new, collection)
    transform = _matrix(obj)
    for ob in new:  # the roots: on top of their own transform (matrix_world may not be evaluated)
        if ob.parent is None or ob.parent not in new:
            ob.matrix_basis = transform @ ob.matrix_basis
    return new


# --- the scene ---------------------------------------------------------------------------------

def bundled_world_path(name: str) -> str:
    """The file of one of Blender's bundled worlds (``presets.BUNDLED_WORLDS``)."""
    import os

    return os.path.join(bpy.utils.system_resource("DATAFILES", path="studiolights/world"), f"{name}.exr")


def _world(name: str, preset: P.WorldPreset) -> bpy.types.World:
    world = bpy.data.worlds.new(name)
    world.color = preset.color
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Color"].default_value = (*preset.color, 1.0)
    background.inputs["Strength"].default_value = preset.strength if preset.image else 1.0
    if preset.image:
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.load(bundled_world_path(preset.image), check_existing=True)
        env.location = (background.location.x - 300.0, background.location.y)
        tree.links.new(env.outputs["Color"], background.inputs["Color"])
        if preset.rotation:
            coords = tree.nodes.new("ShaderNodeTexCoord")
            mapping = tree.nodes.new("ShaderNodeMapping")
            mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(preset.rotation))
            tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
            tree.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    return world


def _camera(preset: P.ScenePreset, collection) -> bpy.types.Object:
    c = preset.camera
    data = bpy.data.cameras.new(f"{preset.name} camera")
    data.type = _CAMERA_TYPES[c.type]
    data.lens = c.lens
    data.ortho_scale = c.ortho_scale
    data.clip_start, data.clip_end = c.clip_start, c.clip_end
    ob = bpy.data.objects.new(f"{preset.name} camera", data)
    ob.location = c.location
    _aim(ob, c.rotation, look_at=c.look_at)
    collection.objects.link(ob)
    return ob


def _light(light: P.LightPreset, collection) -> bpy.types.Object:
    data = bpy.data.lights.new(light.name, light.kind.upper())
    data.energy = light.energy
    data.color = light.color
    if light.kind in ("point", "spot"):
        data.shadow_soft_size = 0.0  # a true point: what Shading Lab computes
        if hasattr(data, "use_soft_falloff"):
            data.use_soft_falloff = False
    if light.kind == "spot":
        data.spot_size = math.radians(light.spot_size)
        data.spot_blend = light.spot_blend
    elif light.kind == "sun":
        data.angle = 0.0
    elif light.kind == "area":
        data.shape = "SQUARE"
        data.size = light.size
    ob = bpy.data.objects.new(light.name, data)
    ob.location = light.location
    _aim(ob, light.rotation, light.direction, light.look_at)
    collection.objects.link(ob)
    return ob


def build_scene(preset: P.ScenePreset, scene: bpy.types.Scene, variant: str | None = None) -> BuiltScene:
    """Add ``preset`` to ``scene`` in a new collection named after it: camera (made the scene
    camera), lights (``variant``'s when given), objects and their materials; set the render
    resolution, the world colour and the Shading Lab model and ambient constant. Existing objects
    are left alone: build into an empty scene for the preset as designed."""
    lights, world = preset.lighting(variant)
    collection = bpy.data.collections.new(preset.name)
    scene.collection.children.link(collection)

    scene.render.resolution_x, scene.render.resolution_y = preset.resolution
    scene.render.resolution_percentage = 100
    props = getattr(scene, "shading_lab", None)
    if props is not None:
        props.model = preset.model
        props.ambient = preset.ambient
        props.ambient_source = preset.ambient_source
    scene.world = _world(preset.name, world)

    camera = _camera(preset, collection)
    scene.camera = camera
    built = BuiltScene(collection=collection, camera=camera)
    built.lights = [_light(light, collection) for light in lights]

    for i, obj in enumerate(preset.objects):
        material = None
        if obj.material is not None:
            material = built.materials.get(obj.material)
            if material is None:
                material = apply_material_preset(bpy.data.materials.new(obj.material.name), obj.material)
                built.materials[obj.material] = material
        if obj.primitive is not None:
            mesh = primitive_mesh(obj)
            if material is not None:
                mesh.materials.append(material)
            ob = bpy.data.objects.new(obj.name, mesh)
            ob.matrix_world = _matrix(obj)
            collection.objects.link(ob)
            new = [ob]
        else:
            new = _load_file_object(scene, obj, collection, preset, f"objects[{i}]")
            if material is not None:
                for ob in new:
                    if ob.type == "MESH":
                        ob.data.materials.clear()
                        ob.data.materials.append(material)
        built.objects += [ob for ob in new if ob.type == "MESH"]
    for layer in scene.view_layers:  # world matrices valid for whoever reads them next
        layer.update()
    return built
