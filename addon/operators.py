"""Operators: applying a material preset from the shipped library (with undo)."""

from __future__ import annotations

import bpy
from bpy.props import EnumProperty

from . import presets


def _preset_items(self, context):
    try:
        library = presets.load_material_presets()
    except presets.PresetError as exc:  # a broken library must not break the panel
        return [("", f"(material library unreadable: {exc})", "")]
    return [(name, name.replace("_", " ").title(), p.description or name)
            for name, p in sorted(library.items())]


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


classes = (SHADINGLAB_OT_apply_material_preset,)
