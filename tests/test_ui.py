"""Panels, drawn into a recording layout (no window is available headless): what a user would
read in the Render and Material tabs, and which of Blender's panels open to the engine."""

from __future__ import annotations

from types import SimpleNamespace

import bpy
import pytest
import scenes

from addon.blender import materials, ui
from addon.frame import gpu_library


class Layout:
    """Records prop() and label() calls of a panel's draw(); every sub-layout records into it."""

    def __init__(self, log=None):
        self.log = [] if log is None else log
        self.use_property_split = False
        self.active = True

    def prop(self, data, name, **kwargs):
        self.log.append(("prop", name, self.active))

    def label(self, text="", **kwargs):
        self.log.append(("label", text, self.active))

    def _sub(self, *args, **kwargs):
        sub = Layout(self.log)
        sub.active = self.active
        return sub

    row = column = box = _sub

    def separator(self, **kwargs):
        pass

    def operator_menu_enum(self, operator, prop, **kwargs):
        self.log.append(("operator_menu_enum", prop, self.active))

    def operator(self, operator, **kwargs):
        self.log.append(("operator", operator, self.active))
        return SimpleNamespace()

    def labels(self):
        return [text for kind, text, _ in self.log if kind == "label"]

    def props(self):
        return [name for kind, name, _ in self.log if kind == "prop"]


def _draw(panel_cls, context):
    layout = Layout()
    panel_cls.draw(SimpleNamespace(layout=layout), context)
    return layout


def test_render_panel_warns_about_the_view_transform_and_shows_compile_errors(monkeypatch):
    scene = scenes.reset(size=8)
    context = SimpleNamespace(scene=scene)
    plain = _draw(ui.SHADINGLAB_PT_render, context)
    assert {"model", "ambient", "tone_mapper", "samples"} <= set(plain.props())
    assert "exposure" not in plain.props()  # only for the engine's own tone mappers
    scene.shading_lab.tone_mapper = "ACES"
    scene.view_settings.view_transform = "AgX"
    warned = _draw(ui.SHADINGLAB_PT_render, context)
    assert {"exposure", "transfer"} <= set(warned.props())
    assert any("View Transform to Standard" in t for t in warned.labels())
    scene.view_settings.view_transform = "Standard"
    assert not any("Standard" in t for t in _draw(ui.SHADINGLAB_PT_render, context).labels())
    monkeypatch.setattr(gpu_library.LIBRARY, "_compile_error", "could not compile its PBR program: 0:1 boom")
    failed = _draw(ui.SHADINGLAB_PT_render, context)
    assert any("compilation failed" in t for t in failed.labels())
    assert any("boom" in t for t in failed.labels())


def test_material_panel_says_where_each_value_comes_from():
    scenes.reset(size=8)
    mat = scenes.material("M", roughness=0.3)  # roughness set here, the rest from the shader
    layout = _draw(ui.SHADINGLAB_PT_material, SimpleNamespace(material=mat))
    log = layout.log
    i = log.index(("prop", "roughness", True))
    assert ("label", "from shader", True) not in log[i:i + 2]
    j = next(k for k, e in enumerate(log) if e[:2] == ("prop", "metalness"))
    assert log[j][2] is False and log[j + 1][:2] == ("label", "from shader")
    assert "model" in layout.props()


def test_material_panel_reports_the_node_graph_per_node():
    """After a render reads it: the share of the graph's nodes compiled, each node not compiled
    (baked, or why not on the active object), the Principled inputs not drawn, a linked
    Displacement, the AOV Outputs; before: says so."""
    from addon.blender import extract

    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    mat = bpy.data.materials.new("Reported")
    tree = scenes.node_tree(mat)
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(tree.nodes.new("ShaderNodeParticleInfo").outputs["Random"], bsdf.inputs["Roughness"])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    tree.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    # a Specular BSDF (EEVEE's) mixed in: its Clear Coat is not drawn
    specular = tree.nodes.new("ShaderNodeEeveeSpecular")
    tree.links.new(tree.nodes.new("ShaderNodeValue").outputs[0], specular.inputs["Clear Coat"])
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(bsdf.outputs["BSDF"], mix.inputs[1])
    tree.links.new(specular.outputs["BSDF"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    tree.links.new(tree.nodes.new("ShaderNodeDisplacement").outputs[0], out.inputs["Displacement"])
    aov = tree.nodes.new("ShaderNodeOutputAOV")
    aov.aov_name = "mask"
    scenes.plane(scene, material=mat)
    materials.GRAPH_REPORTS.pop(mat.name_full, None)
    before = _draw(ui.SHADINGLAB_PT_material, SimpleNamespace(material=mat)).labels()
    assert "Node graph: not read yet (render, or draw the viewport)" in before
    extract.snapshot(bpy.context.evaluated_depsgraph_get())
    labels = _draw(ui.SHADINGLAB_PT_material, SimpleNamespace(material=mat)).labels()
    # Principled, Ramp, Value, Specular, Mix
    assert "Node graph: 5 of 6 nodes compiled (83%), 1 baked" in labels, labels
    assert "Particle Info (ShaderNodeParticleInfo): baked by Cycles (not compiled)" in labels
    plane = next(o for o in scene.objects if o.type == "MESH")  # no UV map: its bake cannot be made
    labels = _draw(ui.SHADINGLAB_PT_material, SimpleNamespace(material=mat, object=plane)).labels()
    assert ("Not baked on 'Plane': it has no UV map; what they feed takes its socket's value") in labels
    assert "Clear Coat (Specular BSDF): not drawn (the models have no such input)" in labels
    assert "Displacement: not drawn" in labels and "AOV Outputs: mask" in labels


def test_blenders_panels_open_to_the_engine():
    for name in ("DATA_PT_context_light", "DATA_PT_lens", "DATA_PT_camera", "WORLD_PT_context_world",
                 "RENDER_PT_format", "RENDER_PT_color_management"):
        panel = getattr(bpy.types, name)
        assert "SHADING_LAB" in panel.COMPAT_ENGINES, name
    assert ui.SHADINGLAB_PT_render.poll(SimpleNamespace(engine="SHADING_LAB"))
    assert not ui.SHADINGLAB_PT_render.poll(SimpleNamespace(engine="CYCLES"))


def test_material_preset_operator_applies_measured_values():
    from addon.scene import presets

    scene = scenes.reset(size=8)
    mat = scenes.material("Target", roughness=0.9, shininess=5.0)  # explicit values to be replaced
    obj = scenes.plane(scene, material=mat)
    gold = presets.load_material_presets()["gold"]
    from addon.blender.operators import SHADINGLAB_OT_apply_material_preset as op
    assert "UNDO" in op.bl_options
    with bpy.context.temp_override(material=mat, object=obj):
        assert bpy.ops.shading_lab.apply_material_preset(preset="gold") == {"FINISHED"}

    params = materials.material_params(mat)
    assert params.base_color == pytest.approx(gold.base_color, abs=1e-6)
    assert params.metalness == pytest.approx(gold.metalness)
    assert params.roughness == pytest.approx(gold.roughness)
    assert not mat.shading_lab.use_roughness  # the preset's value now comes from the shader
    layout = _draw(ui.SHADINGLAB_PT_material, SimpleNamespace(material=mat))
    assert layout.log[0][:2] == ("operator_menu_enum", "preset")


def test_conversion_operators_with_undo():
    from addon.blender.operators import SHADINGLAB_OT_convert_roughness, SHADINGLAB_OT_principled_to_explicit

    assert "UNDO" in SHADINGLAB_OT_convert_roughness.bl_options
    assert "UNDO" in SHADINGLAB_OT_principled_to_explicit.bl_options
    scene = scenes.reset(size=8)
    a = bpy.data.materials.new("A")
    if a.node_tree is None:
        a.use_nodes = True
    node = next(n for n in a.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    node.inputs["Roughness"].default_value = 0.5
    node.inputs["Base Color"].default_value = (0.2, 0.3, 0.4, 1.0)
    b = scenes.material("B", shininess=100.0)
    obj_a, obj_b = scenes.plane(scene, material=a), scenes.plane(scene, material=b)
    with bpy.context.temp_override(material=a, object=obj_a):
        assert bpy.ops.shading_lab.principled_to_explicit() == {"FINISHED"}
    assert a.shading_lab.use_base_color and tuple(a.shading_lab.base_color) == pytest.approx((0.2, 0.3, 0.4))
    node.inputs["Base Color"].default_value = (1.0, 0.0, 0.0, 1.0)  # the explicit copy now wins
    assert materials.material_params(a).base_color == pytest.approx((0.2, 0.3, 0.4))
    with bpy.context.temp_override(material=a, object=obj_a):
        bpy.ops.shading_lab.convert_roughness(direction="TO_SHININESS")
    assert a.shading_lab.shininess == pytest.approx(30.0)  # r 0.5: 2 / 0.0625 - 2
    with bpy.context.temp_override(selected_objects=[obj_a, obj_b], material=a):
        bpy.ops.shading_lab.convert_roughness(direction="TO_ROUGHNESS", scope="SELECTED")
    assert b.shading_lab.use_roughness
    assert b.shading_lab.roughness == pytest.approx((2 / 102) ** 0.25, rel=1e-5)
    layout = _draw(ui.SHADINGLAB_PT_material, SimpleNamespace(material=a))
    assert ("operator", "shading_lab.convert_roughness", True) in layout.log


def test_material_preset_menu_keeps_its_items_and_names_its_error(tmp_path, monkeypatch):
    """The dynamic menu returns the same (kept-alive) items while the library file is unchanged,
    reads it again when it changes, and a broken library is one item with a real identifier."""
    from addon.blender import operators
    from addon.scene import presets

    library = tmp_path / "materials.toml"
    library.write_text((presets.PRESETS_DIR / "materials.toml").read_text(encoding="utf-8"), encoding="utf-8")
    monkeypatch.setattr(presets, "PRESETS_DIR", tmp_path)
    monkeypatch.setattr(operators, "_PRESET_ITEMS", {"stamp": None, "items": []})
    reads = []
    load = presets.load_material_presets
    monkeypatch.setattr(presets, "load_material_presets",
                        lambda path=None: reads.append(1) or load(tmp_path / "materials.toml"))
    first = operators._preset_items(None, None)
    assert operators._preset_items(None, None) is first and len(reads) == 1
    assert ("gold", "Gold") == first[[i[0] for i in first].index("gold")][:2]
    library.write_text("[broken\n", encoding="utf-8")
    broken = operators._preset_items(None, None)
    assert len(reads) == 2
    assert [item[0] for item in broken] == [operators.UNREADABLE] and "materials.toml" in broken[0][2]


def test_render_panel_says_how_the_empirical_models_white_is_displayed():
    """Blinn-Phong and Phong clamp to [0, 1] in scene-linear: under AgX (Blender's default) 1 is
    light grey, so the panel says to use Standard; not under Standard, nor for the physically
    based model alone."""
    scene = scenes.reset(size=8)
    context = SimpleNamespace(scene=scene)
    scene.view_settings.view_transform = "AgX"
    scene.shading_lab.model = "BLINN_PHONG"
    assert any("AgX shows 1 as light grey" in t for t in _draw(ui.SHADINGLAB_PT_render, context).labels())
    scene.shading_lab.model = "PBR"
    assert not any("light grey" in t for t in _draw(ui.SHADINGLAB_PT_render, context).labels())
    scene.shading_lab.compare_mode = "SPLIT"  # Blinn-Phong | physically based by default
    assert any("light grey" in t for t in _draw(ui.SHADINGLAB_PT_render, context).labels())
    scene.view_settings.view_transform = "Standard"
    assert not any("light grey" in t for t in _draw(ui.SHADINGLAB_PT_render, context).labels())


def test_material_panel_shows_the_auto_choice_and_its_verification(monkeypatch):
    from addon.blender import engine
    from addon.plan import auto_terms

    scene = scenes.reset(size=8)
    mat = scenes.material("Rough gold", roughness=0.6, metalness=1.0)
    context = SimpleNamespace(material=mat, scene=scene)
    assert not any("Auto" in t for t in _draw(ui.SHADINGLAB_PT_material, context).labels())
    scene.shading_lab.term_set = "AUTO"
    assert any("not chosen yet" in t for t in _draw(ui.SHADINGLAB_PT_material, context).labels())
    choice = auto_terms.Choice("MULTISCATTER", auto_terms.CANDIDATE_TERMS["MULTISCATTER"], 0.43,
                               "multiple scattering", "metal, roughness 0.60", samples=512)
    monkeypatch.setitem(engine.last_term_choices, mat.name_full, choice)
    monkeypatch.setitem(engine.last_verification, mat.name_full, auto_terms.Verification(1.7, 120, 1.0))
    layout = _draw(ui.SHADINGLAB_PT_material, context)
    labels = layout.labels()
    assert "Auto: default + multiple scattering" in labels, labels
    assert any("Predicted ΔE_ITP 0.43 (bound 0.50" in t for t in labels), labels
    assert "Needs multiple scattering: metal, roughness 0.60" in labels, labels
    assert any("Measured ΔE_ITP 1.70 on 120 pixels: over the bound 1.00" in t for t in labels), labels
    assert ("operator", "shading_lab.verify_auto_terms", True) in layout.log
    merged = auto_terms.Choice("PRINCIPLED", auto_terms.REFERENCE, 0.0, samples=512, alone="MULTISCATTER",
                               costs_ms=0.0213)
    monkeypatch.setitem(engine.last_term_choices, mat.name_full, merged)
    labels = _draw(ui.SHADINGLAB_PT_material, context).labels()
    assert "Auto: Principled set" in labels, labels
    assert ("Alone it would take default + multiple scattering: a program of its own would save 0.02 ms "
            "a frame, too little to repay its compile") in labels, labels
