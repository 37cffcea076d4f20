"""Panels for the Render and Material tabs, and Blender's own panels opened to this engine."""

from __future__ import annotations

import bpy

from .engine import ENGINE_ID

# Blender's panels that make sense for this engine: light, camera, world, object, output.
_BUILTIN_PREFIXES = ("DATA_PT_", "OBJECT_PT_", "RENDER_PT_format", "RENDER_PT_output",
                     "RENDER_PT_color_management", "WORLD_PT_", "VIEWLAYER_PT_", "MATERIAL_PT_preview",
                     "EEVEE_MATERIAL_PT_context_material", "MATERIAL_PT_viewport")
_EXCLUDED = {"DATA_PT_light", "DATA_PT_EEVEE_light"}


def builtin_panels():
    for panel in bpy.types.Panel.__subclasses__():
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if engines is None or panel.__name__ in _EXCLUDED:
            continue
        if panel.__name__.startswith(_BUILTIN_PREFIXES) and (
                "BLENDER_RENDER" in engines or "BLENDER_EEVEE" in engines or "BLENDER_EEVEE_NEXT" in engines):
            yield panel


def _wrap(text: str, width: int) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width)[:8]


class ShadingLabPanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    COMPAT_ENGINES = {ENGINE_ID}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES


class SHADINGLAB_PT_render(ShadingLabPanel, bpy.types.Panel):
    bl_label = "Shading Lab"
    bl_context = "render"

    def draw(self, context):
        from ..frame.gpu_library import LIBRARY

        layout = self.layout
        layout.use_property_split = True
        props = context.scene.shading_lab
        error = LIBRARY.compile_error
        if error:
            box = layout.box()
            box.label(text="Shader compilation failed (nothing was drawn):", icon="ERROR")
            for line in _wrap(error, 60):
                box.label(text=line)
        layout.prop(props, "model")
        empirical = props.model != "PBR" or (props.compare_mode != "OFF" and
                                             {props.compare_a, props.compare_b} != {"PBR"})
        view = context.scene.view_settings.view_transform
        if empirical and props.tone_mapper == "BLENDER" and view not in ("Standard", "Raw"):
            box = layout.box()
            box.label(text=f"Blinn-Phong and Phong clamp to [0, 1]; {view} shows 1 as light grey:",
                      icon="INFO")
            box.label(text="set Color Management > View Transform to Standard for their white")
        col = layout.column()
        col.active = props.model != "PBR"
        col.prop(props, "ambient_source")
        row = col.row()
        row.active = props.ambient_source == "CONSTANT"
        row.prop(props, "ambient")
        col = layout.column(heading="Physically Based")
        col.active = props.model == "PBR"
        col.prop(props, "term_set")
        if props.term_set == "AUTO":
            sub = col.column(align=True)
            sub.prop(props, "auto_error_bound")
            sub.prop(props, "auto_quantile")
        terms = col.column()
        terms.active = props.term_set == "CUSTOM"
        for name in ("fresnel", "ndf", "visibility", "diffuse", "multiscatter"):
            terms.prop(props, name)
        row = layout.row()
        row.active = props.model == "BLINN_PHONG"
        row.prop(props, "normalized_blinn_phong")
        layout.separator()
        layout.prop(props, "tone_mapper")
        auto = props.exposure_mode == "AUTO"
        layout.prop(props, "exposure_mode")
        if props.tone_mapper != "BLENDER" or auto:
            layout.prop(props, "exposure", text="Compensation" if auto else "Exposure")
        if auto:
            col = layout.column(align=True)
            col.prop(props, "exposure_method")
            col.prop(props, "exposure_key")
            sub = col.column(align=True)
            sub.active = props.exposure_method == "HISTOGRAM"
            sub.prop(props, "exposure_low")
            sub.prop(props, "exposure_high")
            col = layout.column(align=True)
            col.prop(props, "exposure_min")
            col.prop(props, "exposure_max")
            col = layout.column(align=True)
            col.prop(props, "adapt_brighter")
            col.prop(props, "adapt_darker")
        if props.tone_mapper != "BLENDER":
            layout.prop(props, "transfer")
            if context.scene.view_settings.view_transform != "Standard":
                box = layout.box()
                box.label(text="Set Color Management > View Transform to Standard:", icon="ERROR")
                box.label(text="this tone mapper already maps to display values")
        col = layout.column(heading="World")
        col.active = props.model == "PBR"
        col.prop(props, "world_occlusion", text="Occlusion")
        sub = col.column()
        sub.active = props.world_occlusion
        sub.prop(props, "occlusion_distance", text="Distance")
        sub.prop(props, "occlusion_resolution", text="Resolution")
        col.prop(props, "world_diffuse", text="Diffuse")
        col.prop(props, "world_specular", text="Specular")
        if props.world_specular == "SAMPLED":
            col.prop(props, "world_samples", text="Samples")
        col = layout.column(heading="Shadows")
        col.prop(props, "shadows", text="")
        sub = col.column()
        sub.active = props.shadows
        sub.prop(props, "shadow_map_size", text="Map Size")
        sub.prop(props, "soft_shadows")
        col = layout.column(heading="Lights")
        col.prop(props, "light_threshold", text="Threshold")
        col.prop(props, "light_culling", text="Culling")
        layout.prop(props, "samples")
        layout.prop(props, "transparency_layers")
        col = layout.column(heading="Fallback Bakes")
        col.prop(props, "bake_resolution", text="Resolution")
        col.operator("shading_lab.render", icon="RENDER_STILL")
        # Blender's own setting (Cycles shows it under Performance): final renders keep the shadow
        # maps the last one drew where the lights and casters are the same
        layout.prop(context.scene.render, "use_persistent_data", text="Persistent Data")
        layout.separator()
        layout.prop(props, "compare_mode")
        if props.compare_mode != "OFF":
            row = layout.row(align=True)
            row.prop(props, "compare_a")
            row.prop(props, "compare_b")
            if props.compare_mode == "SPLIT":
                layout.prop(props, "compare_split")
            else:
                layout.prop(props, "compare_range")
                layout.label(text=f"Heat map: bottom strip runs 0 (left) to {props.compare_range:g} (right)")


class SHADINGLAB_PT_light(ShadingLabPanel, bpy.types.Panel):
    bl_label = "Light"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.light is not None

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        light = context.light
        layout.prop(light, "type", expand=True)
        layout.prop(light, "color")
        layout.prop(light, "energy")
        layout.prop(light, "exposure")
        if light.type == "SPOT":
            layout.prop(light, "spot_size")
            layout.prop(light, "spot_blend")
        if light.type == "SUN":
            layout.prop(light, "angle")
        elif light.type == "AREA":
            layout.prop(light, "shape")
            layout.prop(light, "size")
            if light.shape in ("RECTANGLE", "ELLIPSE"):
                layout.prop(light, "size_y")
        else:
            layout.prop(light, "shadow_soft_size", text="Radius")
        layout.prop(light, "use_shadow", text="Cast Shadow")
        layout.prop(light, "diffuse_factor", text="Diffuse")
        layout.prop(light, "specular_factor", text="Specular")


class SHADINGLAB_PT_world(ShadingLabPanel, bpy.types.Panel):
    bl_label = "Shading Lab"
    bl_context = "world"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and getattr(context, "world", None) is not None

    def draw(self, context):
        from .world_bake import world_fingerprint

        layout = self.layout
        layout.use_property_split = True
        world = context.world
        props = world.shading_lab
        if hasattr(world, "sun_threshold"):
            col = layout.column(heading="Sun")
            col.prop(world, "sun_threshold", text="Threshold")
            col.prop(world, "sun_angle", text="Angle")
        col = layout.column(heading="Bake")
        col.prop(props, "bake_resolution")
        col.prop(props, "bake_samples")
        col.operator("shading_lab.bake_world", icon="RENDER_STILL")
        if props.baked_image is not None:
            current = props.baked_fingerprint == world_fingerprint(world)
            col.label(text=f"Baked: {props.baked_image.name}" + ("" if current else " (out of date)"),
                      icon="CHECKMARK" if current else "ERROR")
            col.prop(props, "baked_image", text="Image")
        _world_cache_row(layout)


def _world_cache_row(layout) -> None:
    """What the world cache keeps on disk, and a button to clear it."""
    from ..plan import world_cache

    col = layout.column(heading="Cache")
    if world_cache.folder() is None:
        col.label(text="Off (SHADING_LAB_CACHE=off)")
        return
    count, size = world_cache.usage()
    row = col.row(align=True)
    row.label(text=f"{count} world{'s' * (count != 1)}, {size / 2 ** 20:.0f} MB on disk")
    sub = row.row()
    sub.enabled = count > 0
    sub.operator("shading_lab.clear_world_cache", text="", icon="TRASH")


def _material_row(layout, props, flag, value, fallback_label):
    row = layout.row(align=True)
    row.prop(props, flag, text="")
    sub = row.row()
    sub.active = getattr(props, flag)
    sub.prop(props, value)
    if not getattr(props, flag):
        row.label(text=fallback_label)


class SHADINGLAB_PT_material(ShadingLabPanel, bpy.types.Panel):
    bl_label = "Shading Lab Surface"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return super().poll(context) and context.material is not None

    def draw(self, context):
        props = context.material.shading_lab
        layout = self.layout
        layout.operator_menu_enum("shading_lab.apply_material_preset", "preset", text="Material Preset",
                                  icon="PRESET")
        row = layout.row(align=True)
        row.operator("shading_lab.principled_to_explicit", text="From Shader")
        row.operator("shading_lab.convert_roughness", text="Roughness → Shininess").direction = "TO_SHININESS"
        row.operator("shading_lab.convert_roughness", text="Shininess → Roughness").direction = "TO_ROUGHNESS"
        layout.prop(props, "model")
        terms = layout.column(align=True)
        for name in ("fresnel", "ndf", "visibility", "diffuse"):
            terms.prop(props, name)
        row = layout.row(align=True)
        row.prop(props, "world_specular")
        if props.world_specular == "SAMPLED":
            row.prop(props, "world_samples", text="Samples")
        _auto_choice(layout, context)
        _graph_report(layout, context.material, getattr(context, "object", None))
        layout.label(text="Unticked values come from the surface shader (Principled BSDF)")
        col = layout.column()
        col.label(text="Physically based")
        for flag, value in (("use_base_color", "base_color"), ("use_metalness", "metalness"),
                            ("use_roughness", "roughness"), ("use_f0", "f0")):
            _material_row(col, props, flag, value, "from shader")
        _material_row(col, props, "use_f90", "f90", "saturate(50 F0)")
        col.prop(props, "fresnel_p")
        _material_row(col, props, "use_complex_ior", "ior_n", "Schlick from base colour")
        sub = col.row()
        sub.active = props.use_complex_ior
        sub.prop(props, "ior_k")
        col.separator()
        col.label(text="Blinn-Phong / Phong")
        _material_row(col, props, "use_shininess", "shininess", "from roughness")
        _material_row(col, props, "use_specular_color", "specular_color", "white")
        _material_row(col, props, "use_ambient_color", "ambient_color", "base colour")


def _graph_report(layout, material, obj=None) -> None:
    """What the last render or viewport frame compiled of the material's node graph, per node:
    compiled, baked (on ``obj``: each bake's resolution and measured error) or not read."""
    from .materials import GRAPH_REPORTS

    report = GRAPH_REPORTS.get(material.name_full)
    box = layout.box()
    if report is None:
        box.label(text="Node graph: not read yet (render, or draw the viewport)", icon="NODETREE")
        return
    if not report.compiled:
        box.label(text="Surface: one shader, nothing linked into it: read as values", icon="NODETREE")
    else:
        compiled = report.nodes - len(report.missing)
        share = compiled / report.nodes if report.nodes else 1.0
        baked = set(report.baked)
        box.label(text=f"Node graph: {compiled} of {report.nodes} nodes compiled ({share:.0%})"
                       + (f", {len(baked)} baked" if baked else ""),
                  icon="CHECKMARK" if not report.missing else "INFO" if len(baked) == len(report.missing)
                  else "ERROR")
        for node in report.missing:
            if node.rsplit(" (", 1)[0] in baked:
                box.label(text=f"{node}: baked by Cycles (not compiled)", icon="TEXTURE")
            else:
                box.label(text=f"{node}: not read (not compiled; what it feeds takes its socket's value)",
                          icon="DOT")
        if baked:
            _bake_report(box, material, obj)
        for socket in report.unread:
            box.label(text=f"{socket}: not drawn (the models have no such input)", icon="DOT")
    if report.displacement:
        box.label(text="Displacement: not drawn", icon="INFO")
    if report.aovs:
        box.label(text=f"AOV Outputs: {', '.join(report.aovs)}", icon="RENDERLAYERS")


def _bake_report(box, material, obj) -> None:
    """Each bake of ``material`` on ``obj`` as the last render or viewport frame asked for it:
    baked (its resolution, seconds and measured error), waiting, or why it cannot be."""
    from . import bake

    owner = obj.name_full if obj is not None else ""
    why = bake.UNBAKEABLE.get((owner, material.name_full))
    if why:
        box.label(text=f"Not baked on '{obj.name}': {why}; what they feed takes its socket's value",
                  icon="ERROR")
        return
    found = bake.status(owner, material.name_full)
    if not found:
        box.label(text="Bakes are per object: select an object using it (render, or draw the viewport)",
                  icon="DOT")
        return
    for target, baked in found:
        if baked is None:
            box.label(text=f"{target.label}: baked by Cycles, not yet: its socket's value meanwhile",
                      icon="TIME")
            continue
        e = baked.error
        r = baked.resolution
        box.label(text=f"{target.label}: baked {r} x {r} in {baked.seconds:.2f} s", icon="TEXTURE")
        seen = " (as seen along the normal)" if target.view else ""
        box.label(text=f"    error between texels {e.text()}{seen}")
        if baked.note:
            box.label(text=f"    {baked.note}", icon="ERROR")
    box.operator("shading_lab.render", icon="RENDER_STILL")


def _auto_choice(layout, context) -> None:
    """What the Auto term set chose for the material in the last render or viewport frame."""
    scene = getattr(context, "scene", None)
    scene_props = getattr(scene, "shading_lab", None)
    if scene_props is None or scene_props.term_set != "AUTO":
        return
    from ..plan.auto_terms import label
    from .engine import last_term_choices, last_verification

    name = context.material.name_full
    choice = last_term_choices.get(name)
    box = layout.box()
    if choice is None:
        box.label(text="Auto: not chosen yet (render, or draw the viewport)", icon="INFO")
    else:
        box.label(text=f"Auto: {choice.label}", icon="SHADING_RENDERED")
        box.label(text=f"Predicted ΔE_ITP {choice.predicted:.2f} (bound {scene_props.auto_error_bound:.2f}, "
                       f"{scene_props.auto_quantile:.0f}th percentile, {choice.samples} points)")
        if choice.limiting:
            box.label(text=f"Needs {choice.limiting}: {choice.reason}")
        if choice.samples and not choice.errors:
            box.label(text=f"Too small for a program of its own: a cheaper set would save at most "
                           f"{choice.costs_ms:.2f} ms a frame")
        if choice.alone:
            box.label(text=f"Alone it would take {label(choice.alone)}: a program of its own would "
                           f"save {choice.costs_ms:.2f} ms a frame, too little to repay its compile")
    checked = last_verification.get(name)
    if checked is not None:
        box.label(text=f"Measured ΔE_ITP {checked.measured:.2f} on {checked.pixels:,} pixels"
                       + (f": over the bound {checked.bound:.2f}" if checked.over else ""),
                  icon="ERROR" if checked.over else "CHECKMARK")
    box.operator("shading_lab.verify_auto_terms", icon="VIEWZOOM")


def render_menu(self, context) -> None:
    """Atop Blender's Render menu with this engine: what F12 and Ctrl+F12 run here, the fallback
    bakes the current frame needs first (``operators.SHADINGLAB_OT_render``)."""
    if getattr(getattr(context, "scene", None), "render", None) is None or \
            context.scene.render.engine != ENGINE_ID:
        return
    layout = self.layout
    for animation, text, icon in ((False, "Bake Fallbacks and Render Image", "RENDER_STILL"),
                                  (True, "Bake Fallbacks and Render Animation", "RENDER_ANIMATION")):
        props = layout.operator("shading_lab.render", text=text, icon=icon)
        props.animation = animation
        props.use_viewport = True  # as the F12 keys set it: the menu shows them beside
    layout.separator()


classes = (SHADINGLAB_PT_render, SHADINGLAB_PT_light, SHADINGLAB_PT_world, SHADINGLAB_PT_material)


def register():
    for panel in builtin_panels():
        panel.COMPAT_ENGINES.add(ENGINE_ID)
    bpy.types.TOPBAR_MT_render.prepend(render_menu)


def unregister():
    bpy.types.TOPBAR_MT_render.remove(render_menu)
    for panel in builtin_panels():
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
