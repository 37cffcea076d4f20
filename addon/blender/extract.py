"""Reads a Blender depsgraph into a ``Snapshot``: the objects and instances drawn, the camera, the
scene's and the render's settings, what changed since the last read, and the baked fallbacks.
Its readers: ``materials`` (a material), ``geometry`` (a mesh), ``lights`` and ``world``; these
are the only modules that read scene data for rendering.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections import Counter

import bpy
import numpy as np

from ..materials import codegen, surface
from ..plan import auto_terms, programs, shadows
from ..scene import snapshot as S
from ..scene.matrices import invert
from . import bake, nodes
from .geometry import instance_random, mesh_geometry, uniform_attribute, with_attributes, with_orco
from .images import IMAGES
from .lights import LIGHT_KIND, make_light
from .materials import material_params
from .world import world_environment


class ExtractError(RuntimeError):
    """The scene cannot be rendered as it is (no camera, say); the message is for the user."""


def render_size(scene: bpy.types.Scene) -> tuple[int, int]:
    r = scene.render
    scale = r.resolution_percentage / 100.0
    return max(int(r.resolution_x * scale), 1), max(int(r.resolution_y * scale), 1)


# --- objects -----------------------------------------------------------------------------------

def _geometry_key(obj: bpy.types.Object) -> str:
    """The evaluated mesh's identity: instances of one mesh share it, modifiers make a new one."""
    return f"mesh:{obj.data.name_full}:{obj.data.as_pointer():x}"


def _memo_key(obj: bpy.types.Object) -> str:
    """Where ``GEOMETRY_MEMO`` keeps an object's mesh: the original object and mesh, which stay
    from one render's depsgraph to the next (the evaluated mesh, ``_geometry_key``, does not)."""
    data = obj.data.original if obj.data.original is not None else obj.data
    return f"{obj.original.name_full}:{data.name_full}"


def _matrix(m) -> np.ndarray:
    return np.array(m, np.float32)


#: Object types that reach the depsgraph with no mesh of their own, and are not drawn.
UNDRAWN_KINDS = {"CURVES": "hair curves object(s)", "VOLUME": "volume(s)", "POINTCLOUD": "point cloud(s)",
                 "GREASEPENCIL": "Grease Pencil object(s)", "GPENCIL": "Grease Pencil object(s)"}


# --- camera --------------------------------------------------------------------------------------


def make_camera(depsgraph, camera_obj, width: int, height: int) -> S.Camera:
    r = depsgraph.scene.render
    cam_eval = camera_obj.evaluated_get(depsgraph)
    projection = cam_eval.calc_matrix_camera(
        depsgraph, x=width, y=height, scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y
    )
    view = invert(np.array(cam_eval.matrix_world, np.float64))
    return S.Camera.from_matrices(view, np.array(projection), cam_eval.data.type != "ORTHO")


# --- the snapshot ------------------------------------------------------------------------------

def scene_settings(scene) -> S.Settings:
    props = getattr(scene, "shading_lab", None)
    if props is None:
        return S.Settings()
    terms = S.Terms(fresnel=props.fresnel, ndf=props.ndf, visibility=props.visibility, diffuse=props.diffuse,
                    multiscatter=bool(props.multiscatter),
                    normalized_blinn_phong=bool(props.normalized_blinn_phong),
                    principled=props.term_set == "PRINCIPLED")
    auto = None
    if props.exposure_mode == "AUTO":
        auto = S.AutoExposure(method=props.exposure_method, key=float(props.exposure_key),
                              low=float(props.exposure_low) / 100.0, high=float(props.exposure_high) / 100.0,
                              compensation=float(props.exposure), min_stops=float(props.exposure_min),
                              max_stops=float(props.exposure_max), brighter=float(props.adapt_brighter),
                              darker=float(props.adapt_darker))
    return S.Settings(model=props.model, terms=terms, ambient=float(props.ambient), auto_exposure=auto,
                      tone_mapper=props.tone_mapper, exposure=float(props.exposure), transfer=props.transfer,
                      samples=int(props.samples), compare_mode=props.compare_mode,
                      compare_models=(props.compare_a, props.compare_b),
                      compare_split=float(props.compare_split), compare_range=float(props.compare_range),
                      transparency_layers=int(props.transparency_layers),
                      environment_diffuse=props.world_diffuse,
                      ambient_world=props.ambient_source == "WORLD",
                      world_occlusion=bool(props.world_occlusion),
                      occlusion_distance=float(props.occlusion_distance),
                      occlusion_resolution=str(props.occlusion_resolution),
                      shadows=bool(props.shadows), shadow_map_size=int(props.shadow_map_size),
                      soft_shadows=bool(props.soft_shadows),
                      light_threshold=float(props.light_threshold), light_culling=bool(props.light_culling),
                      auto_error_bound=(float(props.auto_error_bound) if props.term_set == "AUTO" else None),
                      auto_quantile=float(props.auto_quantile) / 100.0,
                      environment_samples=(int(props.world_samples) if props.world_specular == "SAMPLED"
                                           else 0))


def final_render_settings(scene) -> S.Settings:
    """``scene_settings`` for a final render: with Blender's Persistent Data (Render > Performance),
    which only final renders honour (a viewport keeps its renderer anyway; previews keep nothing)."""
    return dataclasses.replace(scene_settings(scene),
                               persistent_data=bool(getattr(scene.render, "use_persistent_data", False)))


#: The artist's scene settings for previews, captured on the main thread (see ``remember_settings``).
_ARTIST_SETTINGS: list[S.Settings | None] = [None]


def remember_settings(scene) -> None:
    """Keep ``scene``'s settings for previews. Called where Blender runs add-on code on the main
    thread (property edits, depsgraph updates, file loads, registration) and by renders: a
    preview renders in a job thread, in Blender's own preview scene, where reading
    ``bpy.context`` is not safe."""
    if scene is not None and getattr(scene, "shading_lab", None) is not None:
        _ARTIST_SETTINGS[0] = scene_settings(scene)


def preview_settings(preview_scene) -> S.Settings:
    """Settings for a material, world or light preview.

    The scene Blender builds for a preview carries default Shading Lab settings, so the model and
    terms come from the artist's scene (the last one remembered): a preview shows what a render
    would. Previews are small and frequent: one sample per pixel, no A|B compare; and manual
    exposure (automatic exposure would meter a dark material up to middle grey).
    """
    artist = _ARTIST_SETTINGS[0]
    settings = artist if artist is not None else scene_settings(preview_scene)
    return dataclasses.replace(settings, samples=1, compare_mode="OFF", auto_exposure=None)


def geometry_updates(depsgraph) -> set[str]:
    """Names of the original objects and meshes whose geometry this depsgraph update changed.

    A transform-only edit sets ``is_updated_transform`` alone and adds nothing here; a material
    edit tags the meshes using it for shading only, which adds nothing either.
    """
    dirty: set[str] = set()
    for update in depsgraph.updates:
        idb = update.id
        if isinstance(idb, (bpy.types.Object, bpy.types.Mesh)) and update.is_updated_geometry:
            dirty.add(idb.original.name_full)
    return dirty


def material_updates(depsgraph) -> set[str] | None:
    """Full names of the materials this depsgraph update changed (their values, their node trees);
    None where something every material may read changed (a node group, an image): read them all."""
    names: set[str] = set()
    for update in depsgraph.updates:
        idb = update.id
        if isinstance(idb, bpy.types.Material):
            names.add(idb.original.name_full)
        elif isinstance(idb, bpy.types.Image) or (isinstance(idb, bpy.types.NodeTree)
                                                   and not idb.is_embedded_data):
            return None  # (a material's own tree comes with the material)
    return names


def _is_dirty(obj, dirty: set[str] | None) -> bool:
    if dirty is None:
        return True
    if obj.original.name_full in dirty:
        return True
    data = obj.data
    return data is not None and data.original is not None and data.original.name_full in dirty


def snapshot(depsgraph, width: int | None = None, height: int | None = None,
             camera: S.Camera | None = None, settings: S.Settings | None = None,
             previous: S.Snapshot | None = None, dirty: set[str] | None = None,
             auto_camera: S.Camera | None = None, auto_choice: bool = True,
             aovs: bool = False, materials_dirty: set[str] | None = None,
             bakes_only: bool = False) -> S.Snapshot:
    """Everything the renderer draws, read from the evaluated scene.

    ``camera`` may be given (the viewport passes its own); otherwise the scene camera is used
    and its absence raises ``ExtractError``. With ``previous`` and ``dirty`` (from
    ``geometry_updates``), geometry of objects not named in ``dirty`` is reused from
    ``previous`` instead of read again; ``Snapshot.fresh`` lists the geometry keys read anew; with
    ``previous`` and ``materials_dirty`` (from ``material_updates``: not None), the materials it
    does not name are taken from ``previous`` (their node graphs are not read nor compiled again).
    Lights, materials, matrices and the world are cheap and always read. With the Auto term set,
    materials get their terms chosen as seen from ``auto_camera`` (else ``camera``), unless
    ``auto_choice`` is off (a viewport that has drawn no view yet chooses at its first draw).
    With ``bakes_only``, only the objects a material of which has fallback bakes are read, for
    their ``bake_requests`` (F12's bake steps: the others' evaluated meshes are not even asked for,
    which would subdivide them).
    """
    scene = depsgraph.scene
    if width is None or height is None:
        width, height = render_size(scene)
    if camera is None:
        if scene.camera is None:
            raise ExtractError("The scene has no active camera: add one or set Scene > Camera")
        camera = make_camera(depsgraph, scene.camera, width, height)
    snap = S.Snapshot(
        camera=camera,
        width=width,
        height=height,
        settings=settings or scene_settings(scene),
    )
    # the evaluated world: its animated values as this frame has them (an animation render job
    # evaluates frames without writing them back to the original data)
    snap.world = world_environment(depsgraph.scene_eval.world, snap)
    snap.world_color = S.World.constant(snap.world.camera)
    snap.lights.extend(snap.world.suns)
    snap.materials[""] = S.DEFAULT_MATERIAL
    if aovs:  # a final render writes the view layer's AOVs (each name once, as Blender keeps them)
        snap.aovs = list({aov.name: (aov.name, aov.type) for aov in depsgraph.view_layer.aovs
                          if aov.name and getattr(aov, "is_valid", True)}.values())
    aov_names = {name for name, _ in snap.aovs}
    reusable = previous.geometries if previous is not None else {}
    skipped_empty: set[str] = set()
    skipped_kinds: Counter = Counter()
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.type == "LIGHT":
            if obj.data.type in LIGHT_KIND:
                snap.lights.append(make_light(obj.data, inst.matrix_world))
            continue
        # Curves, surfaces, text, metaballs and geometry-node output reach the depsgraph as mesh
        # instances of their own, beside the source object: take geometry from meshes only, or
        # they are drawn twice (Cycles' BlenderSync::object_is_geometry does the same).
        if obj.type != "MESH":
            if obj.type in UNDRAWN_KINDS:
                skipped_kinds[obj.type] += 1
            continue
        if not inst.show_self:  # an instancer its instances hide (Show Instancer off), as Cycles skips it
            continue
        if bakes_only and not _bakes_in(obj):
            continue
        key = _geometry_key(obj)
        if key in skipped_empty:
            continue
        slots = []
        for slot in obj.material_slots:
            mat = slot.material
            mkey = mat.name_full if mat is not None else ""
            if mkey not in snap.materials:
                kept = previous.materials.get(mkey) if previous is not None and materials_dirty is not None \
                    and mkey not in materials_dirty else None
                if kept is not None:  # unchanged since the last snapshot: not read (nor compiled) again
                    snap.materials[mkey] = kept
                    snap.warnings.extend(previous.material_warnings.get(mkey, ()))
                    snap.material_warnings[mkey] = previous.material_warnings.get(mkey, [])
                    graphs = ([kept.graph] if kept.graph is not None else []) + [g for _, g in kept.aovs]
                    snap.images.update((key, previous.images[key]) for g in graphs for key in g.images
                                       if key in previous.images)
                else:
                    said = len(snap.warnings)
                    snap.materials[mkey] = _material_with_images(snap, mat)
                    snap.material_warnings[mkey] = snap.warnings[said:]
            slots.append(mkey)
        if key not in snap.geometries:
            geometry = reusable.get(key)
            graphs = [snap.materials[m].graph for m in slots if snap.materials[m].graph is not None]
            if aov_names:  # the AOV Outputs' graphs the frame draws
                graphs += [g for m in slots for name, g in snap.materials[m].aovs if name in aov_names]
            tangents = any("tangent" in g.program.uses for g in graphs)
            wanted = {a for g in graphs for a in g.attributes}
            generated = any("generated" in g.program.uses for g in graphs)
            if geometry is None or _is_dirty(obj, dirty) or (tangents and geometry.tangents is None) or \
                    not wanted <= geometry.attributes.keys() or (generated and not geometry.orco_read):
                mesh = obj.to_mesh()
                try:
                    geometry = (mesh_geometry(key, mesh, tangents, _memo_key(obj))
                                if mesh is not None else None)
                    if geometry is not None and wanted:
                        geometry = with_attributes(geometry, mesh, wanted, snap.warnings)
                    if geometry is not None and generated:
                        geometry = with_orco(geometry, obj, mesh, depsgraph, snap.warnings)
                finally:
                    obj.to_mesh_clear()
                if geometry is None:
                    skipped_empty.add(key)
                    continue
                snap.fresh.add(key)
                if tangents and geometry.tangents is None:
                    snap.warnings.append(f"Mesh '{obj.data.name}': its normal map is not drawn (Blender "
                                         f"gives tangents to triangles and quads with a UV map only: "
                                         f"triangulate its n-gons or add a UV map)")
            snap.geometries[key] = geometry
        data = obj.data
        slots = _fallback_slots(snap, inst, slots, key, depsgraph)
        if surface.ORCO in snap.geometries[key].attributes:  # deformed: Generated from its orco
            slots = [_with_orco(snap, m) for m in slots]
        graphs = [g for m in slots for g in (snap.materials[m].graph, *(g for _, g in snap.materials[m].aovs))
                  if g is not None]
        wanted = {a for g in graphs for a in g.uniform_attributes}
        attributes = {a: uniform_attribute(*a, inst, depsgraph.view_layer, depsgraph.scene) for a in wanted}
        snap.items.append(S.DrawItem(key, _matrix(inst.matrix_world), slots or [""],
                                     casts_shadow=bool(getattr(obj, "visible_shadow", True)),
                                     texspace=(tuple(data.texspace_location), tuple(data.texspace_size)),
                                     color=tuple(float(c) for c in obj.color), pass_index=int(obj.pass_index),
                                     random=instance_random(inst), attributes=attributes))
    # before the shadow maps: they fit to the reaches; the scene's box only where a reach needs it
    def box():
        return shadows.scene_bounds(snap, {key: geometry.bounds for key, geometry in snap.geometries.items()})

    snap.lights[:] = programs.light_reaches(snap.lights, snap.settings.light_threshold, box)
    _first, _layers, dropped = shadows.assign(snap)
    if dropped:
        snap.warnings.append(f"{dropped} shadowed light(s) cast no shadow: a frame holds "
                             f"{shadows.MAX_SHADOW_LAYERS} shadow maps (point and area lights take six)")
    skipped = {kind: count for kind, count in skipped_kinds.items() if count}
    if skipped:
        snap.warnings.append("Not drawn (Shading Lab draws meshes): " + ", ".join(
            f"{count} {UNDRAWN_KINDS[kind]}" for kind, count in sorted(skipped.items())))
    if len(snap.lights) > S.MAX_LIGHTS:
        snap.warnings.append(f"{len(snap.lights):,} lights: the first {S.MAX_LIGHTS:,} are drawn, the rest "
                             f"left out")
        del snap.lights[S.MAX_LIGHTS:]
    snap.warnings[:] = dict.fromkeys(snap.warnings)  # each once, however many objects share it
    if snap.settings.auto_error_bound is not None and auto_choice:
        choose_terms(snap, previous.term_choices if previous is not None else None, auto_camera)
    return snap


# --- the baked fallback (addon/blender/bake.py) -------------------------------------------------

def _graphs(params: S.MaterialParams) -> list:
    return ([params.graph] if params.graph is not None else []) + [g for _, g in params.aovs]


def bake_resolution(scene) -> int:
    """The resolution of the scene's fallback bakes (Render properties > Shading Lab > Bake)."""
    props = getattr(scene, "shading_lab", None)
    return int(getattr(props, "bake_resolution", bake.RESOLUTION))


def _fallback_slots(snap: S.Snapshot, inst, slots: list[str], key: str, depsgraph) -> list[str]:
    """The object's material slots, each with the fallback bakes the cache holds (a material of
    its own: ``_with_bakes``; the outputs not baked yet keep their socket values); a slot still
    waiting for bakes has its request in ``snap.bake_requests``. An object whose mesh cannot hold
    a bake (no UV map) keeps the socket values, and the warnings say why."""
    geometry = snap.geometries[key]
    obj = inst.object
    owner = obj.original.name_full if obj.original is not None else obj.name_full
    out = []
    for k, mkey in enumerate(slots):
        params = snap.materials[mkey]
        targets = list({(t.node, t.socket): t for g in _graphs(params) for t in g.bakes}.values())
        if not targets:
            out.append(mkey)
            continue
        labels = ", ".join(t.label for t in targets)
        problem = bake.uv_problem(geometry)
        if problem:
            bake.UNBAKEABLE[(owner, mkey)] = problem
            bake.REQUESTS.pop((owner, mkey), None)
            snap.warnings.append(f"Object '{obj.name}', material '{params.name}': {labels} not compiled and "
                                 f"not baked ({problem}): what they feed takes its socket's value")
            out.append(mkey)
            continue
        bake.UNBAKEABLE.pop((owner, mkey), None)
        for note in bake.uv_notes(geometry):
            snap.warnings.append(f"Object '{obj.name}', material '{params.name}': {labels} baked, but {note}")
        texspace = (tuple(obj.data.texspace_location), tuple(obj.data.texspace_size)) \
            if hasattr(obj.data, "texspace_location") else ()
        resolution = bake_resolution(depsgraph.scene)
        matrix = tuple(tuple(float(v) for v in row) for row in inst.matrix_world)
        placement = repr((matrix, owner, tuple(obj.color), obj.pass_index))
        mesh = bake.mesh_digest(geometry, texspace)
        uv = obj.data.uv_layers.active.name
        scene = depsgraph.scene
        keys = tuple(bake.key(t, mesh, resolution, placement, bake.inputs_digest(t, geometry, snap.images))
                     for t in targets)
        request = bake.Request(owner, mkey, tuple(targets), keys, uv, resolution, matrix,
                               scene.frame_current + scene.frame_subframe, len(snap.items), k)
        bake.REQUESTS[(owner, mkey)] = request
        variant, waiting = _with_bakes(snap, request)
        if waiting:
            snap.bake_requests.append(request)
        out.append(variant or mkey)
    return out


def _with_bakes(snap: S.Snapshot, request) -> tuple[str | None, bool]:
    """The key of ``request``'s material with the bakes the cache holds sampled (added to
    ``snap.materials``, the baked pixels to ``snap.images``; None where it holds none of them:
    the material as it is), and whether a bake is still missing (the outputs not baked keep their
    socket values: a bake that failed, or F12's bakes stopped, leaves the others drawn)."""
    found = [bake.CACHE.get(k) for k in request.keys]
    waiting = any(b is None for b in found)
    baked = {(t.node, t.socket): k for t, k, b in zip(request.targets, request.keys, found) if b is not None}
    if not baked:
        return None, waiting
    variant = f"{request.material}\x1f{hashlib.sha1(repr(sorted(baked.items())).encode()).hexdigest()[:16]}"
    if variant not in snap.materials:
        params = snap.materials[request.material]
        graph = surface.with_bakes(params.graph, baked) if params.graph is not None else None
        aovs = tuple((name, surface.with_bakes(g, baked)) for name, g in params.aovs)
        snap.materials[variant] = dataclasses.replace(params, graph=graph, aovs=aovs)
        snap.material_warnings[variant] = snap.material_warnings.get(request.material, [])
        if request.material in snap.term_choices:
            snap.term_choices[variant] = snap.term_choices[request.material]
    for b in found:
        if b is not None:
            snap.images[b.image.key] = b.image
    return variant, waiting


def _with_orco(snap: S.Snapshot, mkey: str) -> str:
    """The key of material ``mkey`` as drawn on a deformed mesh (``surface.with_orco``: Generated
    from its undeformed positions; added to ``snap.materials``); ``mkey`` where none of its graphs
    reads Generated."""
    params = snap.materials[mkey]
    if not any("generated" in g.program.uses for g in _graphs(params)):
        return mkey
    variant = f"{mkey}\x1forco"
    if variant not in snap.materials:
        graph = surface.with_orco(params.graph) if params.graph is not None else None
        aovs = tuple((name, surface.with_orco(g)) for name, g in params.aovs)
        snap.materials[variant] = dataclasses.replace(params, graph=graph, aovs=aovs)
        snap.material_warnings[variant] = snap.material_warnings.get(mkey, [])
        if mkey in snap.term_choices:
            snap.term_choices[variant] = snap.term_choices[mkey]
    return variant


def apply_bakes(snap: S.Snapshot) -> int:
    """Give the draw items whose bakes have since been made their materials with the bakes
    (``snap.bake_requests`` keeps those still missing one); how many slots changed."""
    changed, waiting = 0, []
    for request in snap.bake_requests:
        variant, missing = _with_bakes(snap, request)
        if missing:
            waiting.append(request)
        if variant is None:
            continue
        item = snap.items[request.item]
        if surface.ORCO in snap.geometries[item.geometry].attributes:  # deformed (snapshot's slots)
            variant = _with_orco(snap, variant)
        item.materials[request.slot] = variant
        changed += 1
    snap.bake_requests[:] = waiting
    return changed


#: What ``fallback_materials`` last found of each material: full name -> (its read,
#: ``nodes.read_material``, and ``codegen.FORCE_BAKE`` then; its bakes' labels).
FALLBACK_READS: dict[str, tuple] = {}


def fallback_materials(depsgraph) -> dict[str, tuple[str, ...]]:
    """The materials that the view layer's objects use and whose graphs have node outputs Cycles
    bakes (``MaterialGraph.bakes``), each with the bakes' labels: what F12 asks before it renders,
    reading no object's geometry. The objects: the view layer's (those the viewport hides too) and
    ``depsgraph``'s evaluated ones (instanced collections', materials geometry nodes set). A
    material is compiled again only where its nodes read differently from the last time."""
    materials = {}
    for obj in [*depsgraph.view_layer.objects, *depsgraph.objects]:
        for slot in getattr(obj, "material_slots", ()):
            material = slot.material
            if material is not None and material.original is not None:
                materials.setdefault(material.original.name_full, material.original)
    found = {name: _fallback_labels(material) for name, material in materials.items()}
    return {name: labels for name, labels in found.items() if labels}


def _fallback_labels(material) -> tuple[str, ...]:
    """The labels of the bakes the graphs of ``material`` (an original) have ("Node > Output"),
    compiled again only where its nodes read differently from the last time (``FALLBACK_READS``)."""
    read = nodes.read_material(material)
    if read is None:
        return ()
    known = FALLBACK_READS.get(material.name_full)
    if known is not None and known[0] == (read, codegen.FORCE_BAKE):
        return known[1]
    graphs = [surface.compile_material(*read), *surface.compile_aovs(*read).values()]
    labels = tuple(dict.fromkeys(t.label for g in graphs if g is not None for t in g.bakes))
    FALLBACK_READS[material.name_full] = ((read, codegen.FORCE_BAKE), labels)
    return labels


def _bakes_in(obj) -> bool:
    """Whether a material of ``obj`` (evaluated) has bakes (``_fallback_labels``)."""
    return any(slot.material is not None and slot.material.original is not None
               and _fallback_labels(slot.material.original) for slot in obj.material_slots)


def choose_terms(snap: S.Snapshot, previous: dict | None = None, camera: S.Camera | None = None) -> None:
    """The Auto term set's choice per material (``auto_terms.choose``), fixed into ``snap``."""
    settings = snap.settings
    auto_terms.apply(snap, auto_terms.choose(snap, settings.auto_error_bound, settings.auto_quantile,
                                             previous, camera))


def _material_with_images(snap: S.Snapshot, material) -> S.MaterialParams:
    """``materials.material_params``, with the pixels of the images its graph samples added to
    ``snap.images`` (an image without pixels is said in ``snap.warnings`` and drawn as Blender
    draws a missing image)."""
    found: dict = {}
    params = material_params(material, found, snap.warnings)
    graphs = ([params.graph] if params.graph is not None else []) + [g for _, g in params.aovs]
    keys = {key for g in graphs for entry in g.images for key in codegen.sampler_keys(entry)}
    for key in sorted(keys):
        if key not in snap.images:
            data = IMAGES.get(key, found[key], snap.warnings)
            if data is not None:
                snap.images[key] = data

    def kind(tile: S.ImageData) -> tuple:  # what one 2D array holds alike (half floats with floats)
        return tile.size, "FLOAT" if tile.storage == "HALF" else tile.storage

    for entry in {entry for g in graphs for entry in g.images if isinstance(entry, tuple)}:
        tiles = {key: snap.images[key] for key in entry if key in snap.images}  # a UDIM image's 2D array
        first = next(iter(tiles.values()), None)
        odd = [key.rsplit("#", 1)[1] for key, tile in tiles.items() if kind(tile) != kind(first)]
        if odd:  # gpu_scene.array_texture draws them as missing
            snap.warnings.append(f"Image '{found[entry[0]].name_full}': UDIM tiles {', '.join(odd)} are not "
                                 f"of the first tile's size ({first.size[0]} x {first.size[1]}) and kind of "
                                 f"pixels: they are drawn as missing images")
    return params
