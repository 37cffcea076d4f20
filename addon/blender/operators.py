"""Operators: applying a material preset from the shipped library, copying the surface shader's
values into Shading Lab's explicit settings and converting between roughness and shininess (all
undoable); baking a world; F12 and Ctrl+F12 with this engine (``SHADINGLAB_OT_render``: the
fallback bakes the frame needs first, then Blender's render), on keys of the add-on keymap."""

from __future__ import annotations

import time

import bpy
from bpy.props import BoolProperty, EnumProperty

from ..scene import presets
from . import bake, engine, extract

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
        from .materials import material_params

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


#: Seconds of baking per render that only bakes, at least (``FallbackBaking``): how often F12's
#: progress moves and Esc is read.
TICK_S = 0.5
#: Seconds between those renders, in which the interface draws the progress and takes events.
STEP_INTERVAL_S = 0.05


class FallbackBaking:
    """What F12 bakes before it renders, a step per call (``step``): each step a render on the main
    thread that only bakes (``engine.Preparation``: the scene read as the render after it reads
    it, so the bakes have the keys that render looks for), drawing nothing, baking for at least
    ``TICK_S`` seconds or for as long as its reading took (reading the scene again each step then
    costs at most about as much as the baking). Between steps the interface shows the progress and
    takes Esc."""

    def __init__(self, use_viewport: bool = False):
        self.use_viewport = use_viewport
        self.total: int | None = None  # bakes the frame lacked at the first step
        self.made = 0  # of them, baked
        self.left = 0  # still missing after the last step
        self.last = ""  # what the last bake started stands for
        self.problems: list[str] = []
        self.seconds = 0.0  # spent baking
        self.steps = 0
        self.budget = TICK_S

    def step(self) -> bool:
        """One render that bakes; whether another step would bake more (some are missing and this
        step baked one: a bake that fails is not tried again)."""
        job = engine.Preparation(budget=self.budget)
        start = time.perf_counter()
        try:
            with engine.preparing(job):
                bpy.ops.render.render(use_viewport=self.use_viewport)
        except RuntimeError as exc:  # Blender refused to render: the render that follows says why
            self.problems.append(f"Fallbacks not baked: {str(exc).strip()}")
            return False
        self.steps += 1
        self.seconds += job.seconds
        self.budget = max(TICK_S, time.perf_counter() - start - job.seconds)
        left = job.left()
        made = len(job.wanted) - len(left)
        if self.total is None:
            self.total = len(job.wanted)
        self.made += made
        self.left = len(left)
        self.last = job.started[-1] if job.started else self.last
        self.problems += [p for p in job.problems if p not in self.problems]
        return bool(left) and made > 0

    def status(self) -> str:
        """The progress as the status bar says it."""
        if self.total is None:
            return "Shading Lab: finding the fallback bakes this frame needs (Esc: render without them)"
        return (f"Shading Lab: baked {self.made} of {self.total} fallback(s)" +
                (f", the last {self.last}" if self.last else "") + " (Esc: stop and render)")


class SHADINGLAB_OT_render(bpy.types.Operator):
    """Bake with Cycles what Shading Lab does not compile that the frame needs, then render (F12 and
    Ctrl+F12 with Shading Lab as the render engine). The bakes are kept in memory: nothing is
    added to the file"""

    bl_idname = "shading_lab.render"
    bl_label = "Bake Fallbacks and Render"
    bl_options = {"REGISTER"}

    animation: BoolProperty(name="Animation", description="Render the animation (the current frame's "
                            "bakes first)")
    use_viewport: BoolProperty(name="Use 3D Viewport", description="When inside a 3D viewport, use its "
                               "camera and local view, as Blender's Render does")

    #: Whether one is baking (another waits: F12 again meanwhile is taken, the menu greyed out).
    _running = False

    @classmethod
    def poll(cls, context):
        # with another engine, or while a render runs, F12 goes on to Blender's own Render
        scene = getattr(context, "scene", None)
        return (scene is not None and scene.render.engine == engine.ENGINE_ID and not cls._running
                and not bpy.app.is_job_running("RENDER"))

    @classmethod
    def description(cls, context, properties):
        what = "the animation" if properties.animation else "the frame"
        return (f"Bake with Cycles what Shading Lab does not compile that the current frame needs, then "
                f"render {what}. The bakes are kept in memory: nothing is added to the file")

    def execute(self, context):
        # a script, or no interface: the render runs on this thread, where it bakes what each frame
        # needs before it draws it
        before = bake.CACHE.bakes
        try:
            bpy.ops.render.render(animation=self.animation, use_viewport=self.use_viewport)
        except RuntimeError as exc:
            self.report({"ERROR"}, f"The render failed: {str(exc).strip()}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Baked {bake.CACHE.bakes - before} fallback(s) ({len(bake.CACHE)} kept in "
                              f"memory) and rendered")
        return {"FINISHED"}

    def invoke(self, context, event):
        if context.window is None or bpy.app.background:  # no interface to show the steps in
            return self.execute(context)
        try:
            wanted = bool(extract.fallback_materials(context.evaluated_depsgraph_get()))
        except Exception:  # a material the check cannot read: the steps find out (and say why)
            wanted = True
        if not wanted:
            return self._render()  # nothing to bake: Blender's render at once
        self._baking = FallbackBaking(self.use_viewport)
        wm = context.window_manager
        self._timer = wm.event_timer_add(STEP_INTERVAL_S, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0.0, 1.0)
        context.workspace.status_text_set(self._baking.status())
        type(self)._running = True
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            return self._finish(context, stopped=True)
        if event.type == "F12":  # pressed again while baking: this render follows
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if bpy.app.is_job_running("RENDER"):  # a render started meanwhile (from a menu, say)
            self._close(context)
            self.report({"WARNING"}, "A render started meanwhile: baking stopped")
            return {"CANCELLED"}
        baking = self._baking
        try:
            more = baking.step()
        except Exception as exc:  # never leave F12 waiting on a step that failed: render
            baking.problems.append(f"Fallbacks not baked ({type(exc).__name__}: {exc})")
            more = False
        if not more:
            return self._finish(context, stopped=False)
        context.window_manager.progress_update(baking.made / max(baking.total or 1, 1))
        context.workspace.status_text_set(baking.status())
        return {"RUNNING_MODAL"}

    def _close(self, context) -> None:
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        type(self)._running = False

    def cancel(self, context):
        self._close(context)

    def _finish(self, context, stopped: bool):
        """Say what was baked, then start Blender's render (its window, its job)."""
        self._close(context)
        for line in finished_report(self._baking, stopped):
            self.report(*line)
        return self._render()

    def _render(self):
        try:
            result = bpy.ops.render.render("INVOKE_DEFAULT", animation=self.animation,
                                           use_viewport=self.use_viewport)
        except RuntimeError as exc:
            self.report({"ERROR"}, f"The render did not start: {str(exc).strip()}")
            return {"CANCELLED"}
        return {"FINISHED"} if result & {"RUNNING_MODAL", "FINISHED"} else {"CANCELLED"}


def finished_report(baking: FallbackBaking, stopped: bool) -> list[tuple[set, str]]:
    """What F12's bakes say when done (``self.report``'s arguments): each bake that failed, and
    what was baked or, stopped with Esc, what the render draws without its bake."""
    lines = [({"WARNING"}, problem) for problem in baking.problems]
    if stopped and baking.total is None:
        lines.append(({"WARNING"}, "Fallbacks not baked (stopped): what they stand for takes its socket's "
                                   "value in this render"))
    elif stopped and baking.left:
        lines.append(({"WARNING"}, f"Baking stopped: {baking.made} of {baking.total} fallback(s) baked; "
                                   f"what the other {baking.left} stand for takes its socket's value in "
                                   f"this render"))
    elif baking.made:
        lines.append(({"INFO"}, f"Baked {baking.made} fallback(s) in {baking.seconds:.1f} s"))
    return lines


#: The add-on keymap's items this module made (``register``), removed at ``unregister``.
_KEYMAP_ITEMS: list = []


def add_keys(keyconfig) -> list:
    """F12 and Ctrl+F12 in ``keyconfig``'s Screen keymap run ``shading_lab.render`` (the image, the
    animation), with the properties of Blender's own F12 items; with another engine its poll lets
    them through to Blender's Render. The (keymap, item) pairs made."""
    keymap = keyconfig.keymaps.new(name="Screen", space_type="EMPTY")
    made = []
    for animation in (False, True):
        item = keymap.keymap_items.new(SHADINGLAB_OT_render.bl_idname, "F12", "PRESS", ctrl=animation)
        item.properties.animation = animation
        item.properties.use_viewport = True
        made.append((keymap, item))
    return made


def remove_keys(made: list) -> None:
    """Remove the (keymap, item) pairs ``add_keys`` made (those still there)."""
    for keymap, item in made:
        try:
            keymap.keymap_items.remove(item)
        except (ReferenceError, RuntimeError):  # the keymap went first (its key configuration removed)
            pass
    made.clear()


def register() -> None:
    keyconfig = getattr(bpy.context.window_manager, "keyconfigs", None)
    addon = getattr(keyconfig, "addon", None)  # None in background mode
    if addon is not None:
        _KEYMAP_ITEMS.extend(add_keys(addon))


def unregister() -> None:
    remove_keys(_KEYMAP_ITEMS)


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
           SHADINGLAB_OT_render, SHADINGLAB_OT_convert_roughness, SHADINGLAB_OT_bake_world,
           SHADINGLAB_OT_clear_world_cache, SHADINGLAB_OT_verify_auto_terms)
