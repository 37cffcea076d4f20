"""Scene and material presets: the shipped files load and build, the material library holds
measured values, and every kind of bad file is refused with the file, the key and what was
expected named in the message."""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import bpy
import numpy as np
import pytest
import scenes

from addon.blender import extract, scene_builder
from addon.blender import materials as material_reader
from addon.scene import presets as P
from addon.scene import snapshot as S

ROOT = Path(__file__).resolve().parent.parent

#: preset -> (mesh objects, lights) when built without a variant
SHIPPED = {
    "fresnel": (2, 2),
    "long_tail": (5, 1),
    "hdr": (4, 2),
    "roughness_sweep": (13, 2),
    "softbox": (13, 2),
    "material_grid": (19, 2),
    "portability": (6, 3),
    "furnace": (12, 42),
    "world": (6, 0),
    "car_paint": (3, 2),
    "velvet": (3, 2),
    "tinted_metal": (3, 2),
    "brushed_metal": (3, 2),
    "oil_film": (3, 2),
    "glass_of_water": (5, 2),
    "wax_candle": (3, 2),
}
MATERIALS = {"gold", "copper", "aluminium", "silver", "iron", "titanium", "plastic", "rubber", "glass",
             "water", "skin", "car_paint", "velvet", "tinted_metal", "brushed_metal", "oil_film",
             "clear_glass", "wax"}


def _meshes(scene):
    return [o for o in scene.objects if o.type == "MESH"]


def _lights(scene):
    return [o for o in scene.objects if o.type == "LIGHT"]


def _triangles(objects) -> int:
    total = 0
    for ob in objects:
        ob.data.calc_loop_triangles()
        total += len(ob.data.loop_triangles)
    return total


def _forward(ob) -> np.ndarray:
    """The world direction of an object's local -Z axis (where a camera or light points)."""
    m = np.array(ob.matrix_world)
    axis = -m[:3, 2]
    return axis / np.linalg.norm(axis)


# --- the shipped presets -----------------------------------------------------------------------

def test_every_shipped_scene_is_listed():
    assert P.scene_preset_names() == sorted(SHIPPED)


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_scene_builds(name):
    preset = P.load_scene_preset(name)
    assert preset.description.strip() and preset.name
    scene = scenes.reset()
    built = scene_builder.build_scene(preset, scene)
    meshes, lights = SHIPPED[name]
    assert len(_meshes(scene)) == meshes == len(built.objects)
    assert len(_lights(scene)) == lights == len(built.lights)
    assert scene.camera is built.camera and scene.camera.type == "CAMERA"
    assert (scene.render.resolution_x, scene.render.resolution_y) == preset.resolution
    assert scene.shading_lab.model == preset.model
    triangles = _triangles(_meshes(scene))
    assert 0 < triangles < 100_000
    assert triangles == preset.triangle_estimate()
    for ob in _lights(scene):
        if ob.data.type in ("POINT", "SPOT"):
            assert ob.data.shadow_soft_size == 0.0


def test_material_library_values():
    lib = P.load_material_presets()
    assert set(lib) == MATERIALS
    for name, m in lib.items():
        assert all(0.0 <= c <= 1.0 for c in m.base_color), name
        assert 0.0 <= m.roughness <= 1.0 and m.metalness in (0.0, 1.0), name
        assert 0.0 <= m.dielectric_f0 <= 0.1, name  # every real dielectric is below 10 %
        assert m.description, name
    gold = lib["gold"].base_color
    assert gold[0] > gold[1] > gold[2]
    copper = lib["copper"].base_color
    assert copper[0] > copper[1] > copper[2]
    metals = {n for n, m in lib.items() if m.metalness == 1.0}
    assert metals == {"gold", "copper", "aluminium", "silver", "iron", "titanium", "tinted_metal",
                      "brushed_metal"}
    assert min(lib["silver"].base_color) > max(lib["iron"].base_color)  # silver is the brighter
    assert lib["water"].dielectric_f0 == pytest.approx(0.02)
    assert lib["skin"].dielectric_f0 == pytest.approx(0.028)
    assert lib["glass"].dielectric_f0 == pytest.approx(((1.52 - 1) / (1.52 + 1)) ** 2)
    for name in ("glass", "water", "skin"):  # no transmission or subsurface: said so
        assert "OPAQUE" in lib[name].description, name


def test_material_grid_shows_every_material():
    preset = P.load_scene_preset("material_grid")
    shown = [o.material.preset for o in preset.objects if o.primitive == "uv_sphere"]
    assert sorted(shown) == sorted(P.load_material_presets())


def test_roughness_sweep_ramps_rows():
    scene = scenes.reset()
    built = scene_builder.build_scene(P.load_scene_preset("roughness_sweep"), scene)
    for row, metal in (("Gold", 1.0), ("Plastic", 0.0)):
        spheres = sorted((o for o in built.objects if o.name.startswith(row)), key=lambda o: o.location.x)
        assert len(spheres) == 6
        rough = [material_reader.material_params(o.active_material).roughness for o in spheres]
        assert rough == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0], abs=1e-6)
        assert {material_reader.material_params(o.active_material).metalness for o in spheres} == {metal}
        assert np.diff([o.location.x for o in spheres]) == pytest.approx([1.0] * 5)


def test_portability_variants():
    preset = P.load_scene_preset("portability")
    assert preset.variant_names == ("studio", "noon", "sunset", "spot")
    kinds = {}
    for name, count in (("studio", 3), ("noon", 2), ("sunset", 2), ("spot", 1)):
        scene = scenes.reset()
        built = scene_builder.build_scene(preset, scene, variant=name)
        assert len(_lights(scene)) == count == len(built.lights)
        assert len(_meshes(scene)) == 6
        kinds[name] = sorted(o.data.type for o in built.lights)
        materials = sorted(material_reader.material_params(o.active_material).name for o in built.objects)
        assert materials == sorted(["Floor", "gold", "aluminium", "plastic", "rubber", "skin"])
    assert kinds["spot"] == ["SPOT"] and kinds["sunset"] == ["SUN", "SUN"]
    with pytest.raises(P.PresetError, match="no such lighting variant.*studio, noon"):
        preset.lighting("moonlight")


def test_world_variants_light_with_bundled_worlds():
    """The world preset has no lights: each variant's world is one of Blender's bundled HDRIs,
    which Shading Lab reads as an image (not the flat colour), turned by the variant's rotation."""
    preset = P.load_scene_preset("world")
    assert preset.variant_names == ("forest", "city", "studio", "sunset")
    for name in preset.variant_names:
        scene = scenes.reset()
        built = scene_builder.build_scene(preset, scene, variant=name)
        assert not built.lights and len(built.objects) == 6
        env = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment")
        assert os.path.samefile(env.image.filepath, scene_builder.bundled_world_path(name))
        world = extract.snapshot(bpy.context.evaluated_depsgraph_get(), 8, 8).world
        (term,) = world.lighting
        assert term.image is not None and term.image.pixels.shape[1] == 2 * term.image.pixels.shape[0]
        turned = np.array(term.lookup)[:3, :3]
        angle = math.degrees(math.atan2(turned[1, 0], turned[0, 0]))
        assert angle == pytest.approx(90.0 if name == "city" else 0.0, abs=1e-4), (name, turned)  # Rz(+90)


def test_built_materials_carry_the_preset_values():
    """Through the renderer's own reading of a material: the Principled BSDF alone carries base
    colour, metalness, roughness and F0 (no Shading Lab tick box set)."""
    scenes.reset()
    for name, m in P.load_material_presets().items():
        mat = scene_builder.apply_material_preset(bpy.data.materials.new(name), m)
        got = material_reader.material_params(mat)
        assert got.base_color == pytest.approx(m.base_color, abs=1e-6), name
        assert got.metalness == pytest.approx(m.metalness) and got.roughness == pytest.approx(m.roughness)
        assert got.f0 == pytest.approx(m.dielectric_f0, abs=1e-6), name
        assert not any(getattr(mat.shading_lab, "use_" + k) for k in
                       ("base_color", "metalness", "roughness", "f0", "shininess", "specular_color"))
        node = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        sockets = {socket.identifier: socket for socket in node.inputs}
        for key, spec in P.PRINCIPLED_INPUTS.items():  # every lobe input: the preset's, else the default
            want = dict(m.principled).get(key, spec.default)
            value = sockets[spec.socket].default_value
            assert (tuple(value)[:3] if spec.color else value) == pytest.approx(want, rel=1e-6), (name, key)
            if hasattr(got, key):  # a lobe the renderer reads
                assert getattr(got, key) == pytest.approx(want, rel=1e-6), (name, key)
        drawn = {lobe for lobe in m.lobes if lobe in got.lobes}
        assert drawn == m.lobes & set(S.LOBES), (name, m.lobes, got.lobes)


def test_a_library_preset_replaces_the_lobes_of_the_material():
    """Applying a preset without a coat to a coated material leaves no coat; an inline override of
    a lobe input keeps the library entry's others."""
    scenes.reset()
    lib = P.load_material_presets()
    mat = scene_builder.apply_material_preset(bpy.data.materials.new("Paint"), lib["car_paint"])
    assert material_reader.material_params(mat).lobes == {"COAT"}
    scene_builder.apply_material_preset(mat, lib["velvet"])
    got = material_reader.material_params(mat)
    assert got.lobes == {"SHEEN"} and got.coat_weight == 0.0 and got.sheen_roughness == pytest.approx(0.3)
    preset = P.load_scene_preset("car_paint")
    torus = next(o.material for o in preset.objects if o.name == "Paint torus")
    assert dict(torus.principled)["coat_weight"] == 1.0
    assert P.lobe_off("COAT") == {"coat_weight": 0.0}
    assert P.lobe_off("SPECULAR_TINT") == {"specular_tint": (1.0, 1.0, 1.0)}


def test_every_lobe_has_a_scene_and_a_library_material():
    """Each lobe the presets can set has one scene that names it (the lobes benchmark's), showing a
    library material with the lobe on."""
    scenes_of = {}
    for name in P.scene_preset_names():
        preset = P.load_scene_preset(name)
        if preset.lobe is not None:
            scenes_of.setdefault(preset.lobe, []).append(name)
    assert sorted(scenes_of) == sorted(P.LOBE_NAMES), scenes_of
    assert all(len(v) == 1 for v in scenes_of.values()), scenes_of
    library = {lobe for m in P.load_material_presets().values() for lobe in m.lobes}
    assert library == set(P.LOBE_NAMES)


def test_apply_material_preset_sets_explicit_values_and_replaces_the_surface():
    scenes.reset()
    mat = bpy.data.materials.new("Was diffuse")
    tree = scenes.node_tree(mat)
    for node in [n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"]:
        tree.nodes.remove(node)
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(diffuse.outputs["BSDF"], out.inputs["Surface"])
    mat.shading_lab.use_roughness, mat.shading_lab.roughness = True, 0.9  # a stale explicit value
    preset = P.MaterialPreset("shiny", base_color=(0.2, 0.4, 0.6), roughness=0.3, f0=0.05,
                              shininess=120.0, specular_color=(0.5, 0.6, 0.7))
    scene_builder.apply_material_preset(mat, preset)
    assert out.inputs["Surface"].links[0].from_node.bl_idname == "ShaderNodeBsdfPrincipled"
    got = material_reader.material_params(mat)
    assert got.roughness == pytest.approx(0.3) and got.f0 == pytest.approx(0.05)
    assert got.shininess == pytest.approx(120.0)
    assert got.specular_color == pytest.approx((0.5, 0.6, 0.7))
    props = mat.shading_lab
    assert props.use_shininess and props.use_specular_color and not props.use_roughness


def test_lights_and_camera_follow_the_preset():
    preset = P.load_scene_preset("fresnel")
    scene = scenes.reset()
    built = scene_builder.build_scene(preset, scene)
    low = next(o for o in built.lights if o.name == "Low sun")
    spec = next(light for light in preset.lights if light.name == "Low sun")
    assert low.data.type == "SUN" and low.data.energy == pytest.approx(3.0) == spec.energy  # W/m^2
    want = np.array(spec.direction) / np.linalg.norm(spec.direction)
    assert _forward(low) == pytest.approx(want, abs=1e-6)
    cam = built.camera
    to_target = np.array(preset.camera.look_at) - np.array(preset.camera.location)
    assert _forward(cam) == pytest.approx(to_target / np.linalg.norm(to_target), abs=1e-6)
    up = np.array(cam.matrix_world)[:3, 1]
    assert up[2] > 0.9  # the camera's Y points up: no roll
    assert cam.data.lens == pytest.approx(35.0) and cam.data.clip_end == pytest.approx(500.0)
    # spot cone and power in Blender's units
    spot = scene_builder.build_scene(P.load_scene_preset("portability"), scenes.reset(), "spot").lights[0]
    assert spot.data.energy == pytest.approx(1500.0)
    assert spot.data.spot_size == pytest.approx(math.radians(50.0))
    assert spot.data.shadow_soft_size == 0.0


def test_presets_module_does_not_import_bpy():
    code = "import sys, addon.scene.presets; sys.exit('bpy' in sys.modules)"
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr


# --- writing presets ---------------------------------------------------------------------------

HEADER = """
[scene]
name = "Test"
description = "A test scene."
resolution = [64, 64]

[camera]
location = [0.0, -5.0, 1.0]
look_at = [0.0, 0.0, 0.0]

[[lights]]
kind = "point"
location = [0.0, -2.0, 3.0]
power = 100
"""

SPHERE = """
[[objects]]
primitive = "uv_sphere"
radius = 0.5
"""


def _write(folder: Path, text: str, name: str = "test.toml") -> Path:
    path = folder / name
    path.write_text(text)
    shutil.copy(P.PRESETS_DIR / "materials.toml", folder / "materials.toml")
    return path


def test_arrays_expand_with_ramps(tmp_path):
    path = _write(tmp_path, HEADER + """
[[objects]]
primitive = "plane"

[[arrays]]
count = 3
step = [0.0, 2.0, 0.0]
ramp = { metalness = [1.0, 0.0], f0 = [0.02, 0.08] }
[arrays.object]
name = "Ball"
primitive = "ico_sphere"
subdivisions = 2
location = [1.0, 0.0, 0.5]
material = { preset = "copper", ior = 1.5 }
""")
    preset = P.load_scene_preset(path)
    balls = preset.objects[1:]
    assert [o.name for o in balls] == ["Ball 1", "Ball 2", "Ball 3"]
    assert [o.location for o in balls] == [(1.0, 0.0, 0.5), (1.0, 2.0, 0.5), (1.0, 4.0, 0.5)]
    assert [o.material.metalness for o in balls] == pytest.approx([1.0, 0.5, 0.0])
    assert [o.material.dielectric_f0 for o in balls] == pytest.approx([0.02, 0.05, 0.08])
    assert all(o.material.ior is None and o.material.base_color == (0.955, 0.638, 0.538) for o in balls)
    assert balls[0].triangle_estimate() == 320


def test_readme_example_builds(tmp_path):
    text = (ROOT / "presets" / "README.md").read_text()
    example = re.search(r"### A complete example\s+```toml\n(.*?)```", text, re.S).group(1)
    preset = P.load_scene_preset(_write(tmp_path, example))
    scene = scenes.reset()
    built = scene_builder.build_scene(preset, scene)
    assert len(built.objects) == 3 and len(built.lights) == 1
    assert scene.shading_lab.model == "BLINN_PHONG"
    glossy_object = next(o for o in built.objects if o.name == "Glossy plastic")
    glossy = material_reader.material_params(glossy_object.active_material)
    assert glossy.shininess == pytest.approx(120.0)
    assert glossy.base_color == pytest.approx((0.6, 0.05, 0.03))


def test_file_objects_inside_the_folder_build(tmp_path):
    """A .blend object (appended) and a .glb (imported) referenced from a preset."""
    scene = scenes.reset()
    mesh = bpy.data.meshes.new("Block")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [], [(0, 1, 2, 3)])
    block = bpy.data.objects.new("Block", mesh)
    block.location = (0.0, 0.0, 1.0)
    scene.collection.objects.link(block)
    (tmp_path / "models").mkdir()
    bpy.data.libraries.write(str(tmp_path / "models" / "block.blend"), {block})
    with bpy.context.temp_override(scene=scene):
        bpy.ops.export_scene.gltf(filepath=str(tmp_path / "models" / "block.glb"), export_format="GLB",
                                  use_selection=False, export_cameras=False, export_lights=False)
    path = _write(tmp_path, HEADER + """
[[objects]]
file = "models/block.blend"
object = "Block"
location = [2.0, 0.0, 0.0]
material = { preset = "gold" }

[[objects]]
file = "./models/block.glb"
scale = 2
""")
    scene = scenes.reset()
    built = scene_builder.build_scene(P.load_scene_preset(path), scene)
    assert len(built.objects) == 2
    appended, imported = built.objects
    assert tuple(appended.matrix_world.translation) == pytest.approx((2.0, 0.0, 1.0))  # file's z kept
    assert material_reader.material_params(appended.active_material).name == "gold"
    assert tuple(imported.matrix_world.to_scale()) == pytest.approx((2.0, 2.0, 2.0), abs=1e-6)
    assert tuple(imported.matrix_world.translation) == pytest.approx((0.0, 0.0, 2.0), abs=1e-6)
    assert _triangles(built.objects) == 4
    bad = _write(tmp_path, HEADER + '[[objects]]\nfile = "models/block.blend"\nobject = "Blok"\n', "bad.toml")
    with pytest.raises(P.PresetError, match=r"bad\.toml: objects\[0\]\.object: expected an object of "
                                            r"block\.blend: one of Block, got \"Blok\""):
        scene_builder.build_scene(P.load_scene_preset(bad), scenes.reset())


# --- refusing bad files ------------------------------------------------------------------------

BAD = {
    # id: (file text, [substrings of the message after the file name])
    "toml_syntax": (HEADER + SPHERE + "segments = 32.\n",
                    ["line 19 (objects[0].segments)", "TOML syntax error", "expected valid TOML"]),
    "wrong_type_location": (HEADER + SPHERE + 'location = "up"\n',
                            ['objects[0].location: expected 3 numbers, got "up"']),
    "wrong_type_bool_number": (HEADER + '[[objects]]\nprimitive = "uv_sphere"\nradius = true\n',
                               ["objects[0].radius: expected a number > 0, got true"]),
    "vector_length": (HEADER + SPHERE + "location = [1, 2]\n",
                      ["objects[0].location: expected 3 numbers, got [1, 2]"]),
    "unknown_key": (HEADER + SPHERE + "material = { roughnes = 0.5 }\n",
                    ['objects[0].material.roughnes: unknown key (did you mean "roughness"?)',
                     "expected one of: anisotropic, anisotropic_rotation, base_color"]),
    "unknown_top_level": (HEADER + SPHERE + "[[light]]\nkind = \"sun\"\nstrength = 1\n",
                          ['light: unknown key (did you mean "lights"?)', "expected one of: arrays"]),
    "out_of_range_roughness": (HEADER + SPHERE + "material = { roughness = 1.5 }\n",
                               ["objects[0].material.roughness: expected a number in [0, 1], got 1.5"]),
    "out_of_range_f0": (HEADER + SPHERE + "material = { f0 = -0.1 }\n",
                        ["objects[0].material.f0: expected a number in [0, 1], got -0.1"]),
    "negative_power": (HEADER.replace("power = 100", "power = -5") + SPHERE,
                       ["lights[0].power: expected a number >= 0, got -5"]),
    "resolution": (HEADER.replace("[64, 64]", "[64, 20000]") + SPHERE,
                   ["scene.resolution: expected [width, height]: 2 integers in [1, 16384], got [64, 20000]"]),
    "power_on_sun": (HEADER + SPHERE + '[[lights]]\nkind = "sun"\npower = 3\n',
                     ["lights[1].power: sun lights take strength (W/m^2), not power", "expected one of:"]),
    "missing_strength": (HEADER + SPHERE + '[[lights]]\nkind = "sun"\n',
                         ["lights[1].strength: missing; expected this key to be set"]),
    "unknown_preset": (HEADER + SPHERE + 'material = { preset = "gould" }\n',
                       ['objects[0].material.preset: did you mean "gold"?', "expected a material preset"]),
    "primitive_key": (HEADER + '[[objects]]\nprimitive = "cube"\nradius = 1\n',
                      ["objects[0].radius: not used by a cube", "expected one of:"]),
    "no_objects": (HEADER, ["objects: the scene is empty; expected at least one [[objects]]"]),
    "array_ramp": (HEADER + '[[arrays]]\ncount = 3\nramp = { roughness = [0, 2] }\n'
                   '[arrays.object]\nprimitive = "cube"\nmaterial = { preset = "iron" }\n',
                   ["arrays[0].ramp.roughness: expected a number in [0, 1], got 2"]),
    "escape_dotdot": (HEADER + '[[objects]]\nfile = "../x.blend"\nobject = "X"\n',
                      ['objects[0].file: ".." leaves the presets folder', "expected a relative path",
                       'got "../x.blend"']),
    "escape_absolute": (HEADER + '[[objects]]\nfile = "/tmp/x.blend"\nobject = "X"\n',
                        ["objects[0].file: absolute paths are refused", "expected a relative path"]),
    "escape_symlink_dir": (HEADER + '[[objects]]\nfile = "etc_link/passwd.blend"\nobject = "X"\n',
                           ["objects[0].file: resolves to /etc/passwd.blend, outside the presets folder",
                            "expected a relative path"]),
    "escape_symlink_file": (HEADER + '[[objects]]\nfile = "outside.blend"\nobject = "X"\n',
                            ["objects[0].file: resolves to", "outside the presets folder"]),
    "missing_file": (HEADER + '[[objects]]\nfile = "nothing.glb"\n',
                     ["objects[0].file: no such file", "expected a relative path"]),
    "world_unknown": (HEADER.replace('[64, 64]', '[64, 64]\nworld_image = "forrest"') + SPHERE,
                      ['scene.world_image: did you mean "forest"?', '"city", "courtyard", "forest"']),
    "world_strength_alone": (HEADER.replace('[64, 64]', '[64, 64]\nworld_strength = 2') + SPHERE,
                             ["scene.world_strength: expected a world_image beside it, got 2"]),
    "lobe_out_of_range": (HEADER + SPHERE + "material = { coat_ior = 5.0 }\n",
                          ["objects[0].material.coat_ior: expected a number in [1, 4], got 5.0"]),
    "lobe_tint_length": (HEADER + SPHERE + "material = { sheen_tint = [1.0, 0.5] }\n",
                         ["objects[0].material.sheen_tint: expected 3 numbers [r, g, b] (linear) in [0, 1]"]),
    "lobe_unknown": (HEADER + SPHERE + "material = { coat_wieght = 1.0 }\n",
                     ['objects[0].material.coat_wieght: unknown key (did you mean "coat_weight"?)']),
    "scene_lobe_unused": (HEADER.replace('[64, 64]', '[64, 64]\nlobe = "sheen"') + SPHERE
                          + 'material = { preset = "car_paint" }\n',
                          ["scene.lobe: no object's material has it; expected a material with sheen on",
                           'got "sheen"']),
    "scene_lobe_unknown": (HEADER.replace('[64, 64]', '[64, 64]\nlobe = "shen"') + SPHERE,
                           ['scene.lobe: did you mean "sheen"?', '"specular_tint", "coat"']),
    "variant_unlit": (HEADER + SPHERE + '[[variants]]\nname = "dark"\n',
                      ["variants[0].lights: expected at least one [[variants.lights]] table, or a "
                       "world_image"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_preset_is_refused(case, tmp_path):
    text, parts = BAD[case]
    folder = tmp_path / "presets"
    folder.mkdir()
    os.symlink("/etc", folder / "etc_link")
    outside = tmp_path / "elsewhere.blend"
    outside.write_bytes(b"BLENDER")
    os.symlink(outside, folder / "outside.blend")
    path = _write(folder, text, f"{case}.toml")
    with pytest.raises(P.PresetError) as info:
        P.load_scene_preset(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ") or message.startswith(f"{P._display(path)}: "), message
    assert info.value.file.endswith(f"{case}.toml")
    for part in parts:
        assert part in message, message


def test_oversized_file_is_refused(tmp_path):
    path = _write(tmp_path, HEADER + SPHERE + "#" * (P.MAX_FILE_BYTES + 10) + "\n", "big.toml")
    with pytest.raises(P.PresetError, match=r"big\.toml: \(file size\): expected at most 1048576 bytes "
                                            r"\(1 MiB\), got 1048\d\d\d\b"):
        P.load_scene_preset(path)


def test_bad_material_library_is_refused(tmp_path):
    path = tmp_path / "materials.toml"
    path.write_text('[gold]\nbase_color = [1.0, 0.78]\nmetalness = 1.0\nroughness = 0.3\n')
    with pytest.raises(P.PresetError, match=r"materials\.toml: gold\.base_color: expected 3 numbers "
                                            r"\[r, g, b\] \(linear\) in \[0, 1\], got \[1\.0, 0\.78\]"):
        P.load_material_presets(path)
    path.write_text('[gold]\nbase_color = [1.0, 0.78, 0.34]\nmetalness = 1.0\n')
    with pytest.raises(P.PresetError, match=r"gold\.roughness: missing; expected this key to be set"):
        P.load_material_presets(path)


def test_unknown_scene_name_is_refused():
    hint = r'no such scene preset \(did you mean "fresnel"\?\); expected one of brushed_metal, car_paint'
    with pytest.raises(P.PresetError, match=hint):
        P.load_scene_preset("fresnell")


def test_furnace_preset_bounds_white_spheres(tmp_path):
    """The furnace stands in for a uniform environment of radiance 1: the rough white spheres'
    radiance is their directional albedo, <= 1, and ~1 for the white metal with multiple-scattering
    compensation (cross-checked with the numpy twin's furnace albedo in test_reference.py)."""
    import numpy as np

    from addon.blender import scene_builder
    from addon.scene import presets as P

    scene = scenes.reset(size=8)
    scene_builder.build_scene(P.load_scene_preset("furnace"), scene)
    scene.render.engine = "SHADING_LAB"
    scene.render.resolution_x, scene.render.resolution_y = 480, 200
    scene.shading_lab.multiscatter = True
    image = scenes.render(scene, tmp_path / "furnace.exr")[..., 0]
    metal_rough = image[50, 40 + 80 * 3:: 80]  # sphere centres, roughness 0.6 .. 1
    dielectric_rough = image[150, 40 + 80 * 3:: 80]
    np.testing.assert_allclose(metal_rough, 1.0, atol=0.02)
    assert np.all(dielectric_rough <= 1.02) and np.all(dielectric_rough > 0.9)
