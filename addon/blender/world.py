"""Reads a Blender world into ``World``: its shader graph as radiance terms, as Cycles evaluates it
(``_WorldReader``), the sun split out of a bright environment, and the baked stand-in for what it
cannot read.
"""

from __future__ import annotations

import threading

import bpy
import numpy as np

from ..scene import snapshot as S
from .images import IMAGES, image_key
from .materials import rgb


def _world_tree(world):
    # Blender 5 worlds always use nodes (use_nodes is deprecated); 4.x honours the toggle
    return world.node_tree if bpy.app.version >= (5, 0, 0) or world.use_nodes else None


def _world_output(tree):
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
    active = [n for n in outputs if n.is_active_output] or outputs
    return active[0] if active else None


class _WorldReader:
    """Reads a world's shader graph into radiance terms as Cycles evaluates it: Background
    (colour x strength), its colour from an Environment Texture (equirectangular or mirror ball,
    through Texture Coordinate "Generated" and a Mapping node), Add Shader, Mix Shader by a
    constant factor or by Light Path "Is Camera Ray" (camera rays see one input, lighting uses
    the other). What it cannot read becomes the world's viewport colour, with a warning."""

    def __init__(self, world, snap: S.Snapshot):
        self.world, self.snap = world, snap
        self.unreadable: list[str] = []  # what could not be read (a baked world stands in for it)

    def warn(self, what: str) -> None:
        self.unreadable.append(what)

    def shader(self, socket, weight: np.ndarray, camera: bool | None) -> tuple[list, list]:
        """(camera terms, lighting terms) of what is linked into ``socket``; ``camera`` None
        means both kinds of rays."""
        if not socket.is_linked:
            return [], []
        node = socket.links[0].from_node
        kind = node.bl_idname
        if kind == "ShaderNodeBackground":
            strength_socket = node.inputs["Strength"]
            if strength_socket.is_linked:
                self.warn(f"a link into {node.name}'s Strength")
            term = self.background(node, weight * float(strength_socket.default_value))
            return ([term] if camera in (None, True) else []), ([term] if camera in (None, False) else [])
        if kind == "ShaderNodeAddShader":
            a = self.shader(node.inputs[0], weight, camera)
            b = self.shader(node.inputs[1], weight, camera)
            return a[0] + b[0], a[1] + b[1]
        if kind == "ShaderNodeMixShader":
            fac = node.inputs["Fac"]
            if fac.is_linked and fac.links[0].from_node.bl_idname == "ShaderNodeLightPath" \
                    and fac.links[0].from_socket.name == "Is Camera Ray":
                lighting = self.shader(node.inputs[1], weight, False if camera is None else camera)
                seen = self.shader(node.inputs[2], weight, True if camera is None else camera)
                return lighting[0] + seen[0], lighting[1] + seen[1]
            if fac.is_linked:
                self.warn(f"a link into {node.name}'s Fac")
            f = min(max(float(fac.default_value), 0.0), 1.0)
            a = self.shader(node.inputs[1], weight * (1.0 - f), camera) if f < 1.0 else ([], [])
            b = self.shader(node.inputs[2], weight * f, camera) if f > 0.0 else ([], [])
            return a[0] + b[0], a[1] + b[1]
        self.warn(f"the {node.bl_label} node")
        term = S.EnvironmentTerm(tuple(float(c) for c in weight * np.array(rgb(self.world.color))))
        return ([term] if camera in (None, True) else []), ([term] if camera in (None, False) else [])

    def background(self, node, weight: np.ndarray) -> S.EnvironmentTerm:
        color = node.inputs["Color"]
        if not color.is_linked:
            return S.EnvironmentTerm(tuple(float(c) for c in weight * np.array(rgb(color.default_value))))
        source = color.links[0].from_node
        if source.bl_idname != "ShaderNodeTexEnvironment" or source.image is None:
            self.warn(f"the {source.bl_label} node")
            return S.EnvironmentTerm(tuple(float(c) for c in weight * np.array(rgb(self.world.color))))
        key = image_key(source.image)
        data = self.snap.images.get(key) or IMAGES.get(key, source.image, self.snap.warnings)
        if data is None:  # no pixels (missing file): said in the warnings
            return S.EnvironmentTerm((0.0, 0.0, 0.0))
        self.snap.images[key] = data
        if source.interpolation not in ("Linear", "Closest"):
            self.snap.warnings.append(f"World '{self.world.name}': {source.interpolation} "
                                      f"interpolation of '{source.image.name}' is drawn as Linear")
        return S.EnvironmentTerm(tuple(float(c) for c in weight), data, source.projection,
                                 source.interpolation == "Closest", self.lookup(source.inputs["Vector"]))

    def lookup(self, vector) -> np.ndarray:
        """The texture-space vector as a 4x4 of the world direction (identity: Generated)."""
        if not vector.is_linked:
            return np.eye(4, dtype=np.float32)
        node = vector.links[0].from_node
        if node.bl_idname == "ShaderNodeTexCoord":
            if vector.links[0].from_socket.name != "Generated":
                self.warn(f"Texture Coordinate {vector.links[0].from_socket.name}")
            return np.eye(4, dtype=np.float32)
        if node.bl_idname != "ShaderNodeMapping":
            self.warn(f"the {node.bl_label} node")
            return np.eye(4, dtype=np.float32)
        from mathutils import Euler, Matrix

        values = {}
        for name in ("Location", "Rotation", "Scale"):
            socket = node.inputs.get(name)
            if socket is not None and socket.is_linked:
                self.warn(f"a link into {node.name}'s {name}")
            values[name] = tuple(socket.default_value) if socket is not None else (0.0, 0.0, 0.0)
        rotation = Euler(values["Rotation"], "XYZ").to_matrix().to_4x4()
        scale = Matrix.Diagonal((*values["Scale"], 1.0))
        location = Matrix.Translation(values["Location"])
        kind = node.vector_type
        if kind == "POINT":
            m = location @ rotation @ scale
        elif kind == "TEXTURE":
            m = (location @ rotation @ scale).inverted_safe()
        elif kind == "VECTOR":
            m = rotation @ scale
        else:  # NORMAL: the inverse transpose of rotation x scale (a direction, normalised later)
            m = (rotation @ scale).inverted_safe().transposed()
        inner = self.lookup(node.inputs["Vector"])
        return (np.array(m, np.float64) @ inner).astype(np.float32)


_SUNS: dict = {}  # split_suns results by the term's content (a few ms to a few tens of ms each)
_SUNS_LOCK = threading.Lock()


def _world_suns(terms, threshold: float, angle: float) -> tuple[S.Light, ...]:
    """The lighting field's brightest texels as suns (``environment.split_suns``), cached."""
    from ..reference import environment

    lights = []
    for term in S.World.images(terms)[:S.MAX_ENVIRONMENT_IMAGES]:
        key = (term.image.key, term.image.revision, tuple(term.weight), term.projection,
               np.asarray(term.lookup, np.float32).tobytes(), threshold)
        with _SUNS_LOCK:
            suns = _SUNS.get(key)
        if suns is None:
            suns = environment.split_suns(term, threshold)
            with _SUNS_LOCK:
                if len(_SUNS) > 16:
                    _SUNS.clear()
                _SUNS[key] = suns
        for direction, irradiance, _omega in suns:
            lights.append(S.Light("SUN", (0.0, 0.0, 0.0), tuple(-c for c in direction), irradiance,
                                  angle=angle, world=True, shadow=True))
    return tuple(lights)


def _baked_or_warned(world, snap: S.Snapshot, unreadable: list[str], camera, lighting):
    """A world with parts Shading Lab cannot read: its baked image (World > Shading Lab > Bake
    World) if it has one, with a warning when the world changed since; else what was read, the
    rest as the viewport colour, with a warning saying so."""
    from .world_bake import world_fingerprint

    props = getattr(world, "shading_lab", None)
    baked = props.baked_image if props is not None else None
    what = ", ".join(dict.fromkeys(unreadable))
    if baked is not None:
        data = IMAGES.get(image_key(baked), baked, snap.warnings)
        if data is not None:
            snap.images[image_key(baked)] = data
            if props.baked_fingerprint != world_fingerprint(world):
                snap.warnings.append(f"World '{world.name}' changed since it was baked: bake it again "
                                     f"(World > Shading Lab > Bake World)")
            term = (S.EnvironmentTerm((1.0, 1.0, 1.0), data, "EQUIRECTANGULAR"),)
            return term, term
    snap.warnings.append(f"World '{world.name}': {what} is not read by Shading Lab; it lights and shows "
                         f"as the world's viewport colour (World > Shading Lab > Bake World renders it "
                         f"into an image Shading Lab reads)")
    return camera, lighting


def world_environment(world, snap: S.Snapshot) -> S.World:
    """The world's radiance terms (see ``_WorldReader``) and, for the lighting field, the suns
    split off above Blender's World > Sun > Threshold; a missing world is black."""
    if world is None:
        return S.World()
    tree = _world_tree(world)
    if tree is None:
        term = (S.EnvironmentTerm(rgb(world.color)),)
        return S.World(term, term)
    output = _world_output(tree)
    if output is None:
        return S.World()
    reader = _WorldReader(world, snap)
    camera, lighting = reader.shader(output.inputs["Surface"], np.ones(3), None)
    if reader.unreadable:
        camera, lighting = _baked_or_warned(world, snap, reader.unreadable, camera, lighting)
    for terms, label in ((camera, "seen by the camera"), (lighting, "lighting the scene")):
        if len(S.World.images(terms)) > S.MAX_ENVIRONMENT_IMAGES:
            snap.warnings.append(f"World '{world.name}': more than {S.MAX_ENVIRONMENT_IMAGES} "
                                 f"environment images {label}; the first {S.MAX_ENVIRONMENT_IMAGES} "
                                 f"are used")
    threshold = float(getattr(world, "sun_threshold", 10.0))  # EEVEE's setting, 10 by default
    suns = _world_suns(lighting, threshold, float(getattr(world, "sun_angle", 0.0))) if threshold > 0 else ()
    return S.World(tuple(camera), tuple(lighting), threshold, suns)
