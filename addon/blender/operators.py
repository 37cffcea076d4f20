"""Operators (all undoable): applying a material preset from the shipped library, copying the
surface shader's values into Shading Lab's explicit settings, and converting between roughness
and shininess."""

from __future__ import annotations

import bpy
from bpy.props import EnumProperty

from ..scene import presets

#: The menu's items, kept alive between draws (Blender does not copy the strings a dynamic enum
#: returns: items built anew on every call may be freed while the menu shows them) and read again
#: only when the library file changes.
_PRESET_ITEMS: dict = {"stamp": None, "items": []}
#: The identifier of the one item shown when the library cannot be read.
UNREADABLE = "UNREADABLE"


def _preset_items(self, context):
    path = presets.PRESETS_DIR / "materials.toml"
    try:
        stat = path.stat()
        stamp = (stat.st_mtime_ns, stat.st_size)
    except OSError:
        stamp = None
    if stamp is not None and stamp == _PRESET_ITEMS["stamp"]:
        return _PRESET_ITEMS["items"]
    try:
        library = presets.load_material_presets()
        items = [(name, name.replace("_", " ").title(), p.description or name)
                 for name, p in sorted(library.items())]
    except presets.PresetError as exc:  # a broken library must not break the panel
        items = [(UNREADABLE, "(material library unreadable)", str(exc))]
    _PRESET_ITEMS.update(stamp=stamp, items=items)
    return items


class SHADINGLAB_OT_apply_material_preset(bpy.types.Operator):
    """Give the active material a measured preset's base colour, metalness, roughness and F0"""

    bl_idname = "shading_lab.apply_material_preset"
    bl_label = "Apply Material Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: EnumProperty(name="Preset", items=_preset_items)

    @classmethod
    def poll(cls, context):
        return getattr(context, "material", None) is not None

    def execute(self, context):
        from .scene_builder import apply_material_preset

        try:
            library = presets.load_material_presets()
        except presets.PresetError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        preset = library.get(self.preset)
        if preset is None:
            self.report({"ERROR"}, f"No material preset named {self.preset!r}")
            return {"CANCELLED"}
        material = context.material
        apply_material_preset(material, preset)
        material.update_tag()  # node values alone do not always reach the viewport session
        self.report({"INFO"}, f"{material.name}: {self.preset} applied")
        return {"FINISHED"}


def _target_materials(context, scope: str):
    if scope == "ACTIVE":
        return [context.material] if getattr(context, "material", None) is not None else []
    seen = []
    for obj in getattr(context, "selected_objects", None) or []:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None and slot.material not in seen:
                seen.append(slot.material)
    return seen


_SCOPE = EnumProperty(name="Materials", default="ACTIVE", items=(
    ("ACTIVE", "Active Material", "Only the active material"),
    ("SELECTED", "All Selected", "Every material of the selected objects"),
))


class _MaterialConversion:
    """Runs ``convert(material, resolved values)`` on the chosen materials, then tags them."""

    scope: _SCOPE

    def execute(self, context):
        from .extract import material_params

        materials = _target_materials(context, self.scope)
        if not materials:
            self.report({"WARNING"}, "No material to convert")
            return {"CANCELLED"}
        for mat in materials:
            self.convert(mat.shading_lab, material_params(mat))
            mat.update_tag()
        self.report({"INFO"}, f"Converted {len(materials)} material(s)")
        return {"FINISHED"}


class SHADINGLAB_OT_principled_to_explicit(_MaterialConversion, bpy.types.Operator):
    """Copy the values read from the surface shader into Shading Lab's explicit settings (ticked),
    so they stay when the shader changes"""

    bl_idname = "shading_lab.principled_to_explicit"
    bl_label = "Principled to Shading Lab"
    bl_options = {"REGISTER", "UNDO"}

    def convert(self, props, p):
        for name in ("base_color", "metalness", "roughness", "f0", "shininess", "specular_color",
                     "ambient_color"):
            setattr(props, name, getattr(p, name))
            setattr(props, "use_" + name, True)


class SHADINGLAB_OT_convert_roughness(_MaterialConversion, bpy.types.Operator):
    """Set shininess from roughness, or roughness from shininess, with the documented mapping
    s = 2 / r^4 - 2 (Walter et al. 2007, alpha = r^2)"""

    bl_idname = "shading_lab.convert_roughness"
    bl_label = "Convert Roughness / Shininess"
    bl_options = {"REGISTER", "UNDO"}

    direction: EnumProperty(name="Direction", default="TO_SHININESS", items=(
        ("TO_SHININESS", "Roughness to Shininess", "Blinn-Phong shininess matching the roughness"),
        ("TO_ROUGHNESS", "Shininess to Roughness", "Roughness matching the Blinn-Phong shininess"),
    ))

    def convert(self, props, p):
        from ..scene.snapshot import roughness_from_shininess, shininess_from_roughness

        if self.direction == "TO_SHININESS":
            props.shininess, props.use_shininess = shininess_from_roughness(p.roughness), True
        else:
            props.roughness, props.use_roughness = roughness_from_shininess(p.shininess), True


class SHADINGLAB_OT_bake_world(bpy.types.Operator):
    """Render the world once with Cycles into an equirectangular image, which Shading Lab then
    lights and shows with (for skies and procedural worlds it cannot read)"""

    bl_idname = "shading_lab.bake_world"
    bl_label = "Bake World"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return getattr(context.scene, "world", None) is not None

    def execute(self, context):
        from .world_bake import bake_world, world_fingerprint

        world = context.scene.world
        props = world.shading_lab
        self.report({"INFO"}, f"Baking world '{world.name}' with Cycles ({props.bake_resolution} x "
                              f"{props.bake_resolution // 2}, {props.bake_samples} samples)...")
        try:
            image = bake_world(world, props.bake_resolution, props.bake_samples)
        except (RuntimeError, OSError) as exc:
            self.report({"ERROR"}, f"Could not bake world '{world.name}': {exc}")
            return {"CANCELLED"}
        props.baked_image = image
        props.baked_fingerprint = world_fingerprint(world)
        world.update_tag()
        self.report({"INFO"}, f"World '{world.name}' baked into image '{image.name}'")
        return {"FINISHED"}


class SHADINGLAB_OT_bake_fallbacks(bpy.types.Operator):
    """Bake with Cycles what Shading Lab does not compile in the scene's materials, then render the
    frame here. A render started with F12 runs beside the interface and cannot bake: it draws with
    these bakes. The bakes are kept in memory: nothing is added to the file"""

    bl_idname = "shading_lab.bake_fallbacks"
    bl_label = "Bake Fallbacks and Render"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        from .engine import ENGINE_ID

        return getattr(context.scene.render, "engine", "") == ENGINE_ID

    def execute(self, context):
        from . import bake

        before = bake.CACHE.bakes
        # not invoked: the render runs on this thread, where render() bakes before it draws
        bpy.ops.render.render()
        made = bake.CACHE.bakes - before
        self.report({"INFO"}, f"Baked {made} fallback(s) ({len(bake.CACHE)} kept in memory) and rendered")
        return {"FINISHED"}


class SHADINGLAB_OT_clear_world_cache(bpy.types.Operator):
    """Delete the world lighting Shading Lab keeps on disk between sessions (each world's maps are
    computed again the next time it is rendered)"""

    bl_idname = "shading_lab.clear_world_cache"
    bl_label = "Clear World Cache"
    bl_options = {"REGISTER"}

    def execute(self, context):
        from ..plan import world_cache

        where = world_cache.folder()
        if where is None:
            self.report({"INFO"}, "The world cache is off (SHADING_LAB_CACHE=off): nothing to clear")
            return {"CANCELLED"}
        count, size = world_cache.clear()
        self.report({"INFO"}, f"Deleted {count} cached world{'s' * (count != 1)} "
                              f"({size / 2 ** 20:.0f} MB) from {where}")
        return {"FINISHED"}


class SHADINGLAB_OT_verify_auto_terms(bpy.types.Operator):
    """Render the scene with the Auto term set and with the Principled set, measure each material's
    real error on its own pixels and mark those over the Error Bound"""

    bl_idname = "shading_lab.verify_auto_terms"
    bl_label = "Verify Auto Terms"

    @classmethod
    def poll(cls, context):
        props = getattr(getattr(context, "scene", None), "shading_lab", None)
        return props is not None and props.term_set == "AUTO" and context.scene.camera is not None

    def execute(self, context):
        from . import engine

        engine.request_verification()
        try:
            bpy.ops.render.render()
        except RuntimeError as exc:
            self.report({"ERROR"}, f"Verify: the render failed: {str(exc).strip()}")
            return {"CANCELLED"}
        finally:
            engine._VERIFY_NEXT.clear()  # a render that never ran must not verify a later one
        measured = dict(engine.last_verification)
        if not measured:
            self.report({"WARNING"}, "Verify: no material chosen by Auto covers a pixel")
            return {"CANCELLED"}
        over = sorted(name for name, v in measured.items() if v.over)
        bound = context.scene.shading_lab.auto_error_bound
        if over:
            self.report({"WARNING"}, f"{len(over)} of {len(measured)} material(s) over the error bound "
                                     f"{bound:g}: " + ", ".join(f"{name} ({measured[name].measured:.2f})"
                                                                for name in over))
        else:
            worst = max(v.measured for v in measured.values())
            self.report({"INFO"}, f"All {len(measured)} material(s) within the error bound {bound:g} "
                                  f"(largest measured ΔE_ITP {worst:.2f})")
        return {"FINISHED"}


classes = (SHADINGLAB_OT_apply_material_preset, SHADINGLAB_OT_principled_to_explicit,
           SHADINGLAB_OT_bake_fallbacks, SHADINGLAB_OT_convert_roughness, SHADINGLAB_OT_bake_world,
           SHADINGLAB_OT_clear_world_cache, SHADINGLAB_OT_verify_auto_terms)
