"""Light passes named as EEVEE names them ("Diffuse Direct", "Glossy Direct"), switched by the
view layer's toggles: each lobe's radiance, Combined their sum (plus the ambient term, through
the model's clamp for Blinn-Phong)."""

from __future__ import annotations

import math
from dataclasses import replace

import bpy
import numpy as np
import pytest
import scenes


def _scene(model):
    scene = scenes.reset(size=32)
    scene.shading_lab.model = model
    scene.shading_lab.ambient = 0.1
    scenes.ortho_camera(scene, scale=4.0)
    scenes.plane(scene, size=8.0, material=scenes.material(base_color=(0.6, 0.4, 0.2), roughness=0.35,
                                                           ambient_color=(0.6, 0.4, 0.2)))
    scenes.light(scene, "POINT", energy=40.0, location=(0.4, 0.2, 1.0))
    scenes.light(scene, "SUN", energy=0.5, rotation=(math.radians(30), 0, 0))
    vl = scene.view_layers[0]
    vl.use_pass_diffuse_direct = True
    vl.use_pass_glossy_direct = True
    return scene


@pytest.mark.parametrize("model", ["PBR", "BLINN_PHONG"])
def test_light_passes_sum_to_combined(model, tmp_path):
    scene = _scene(model)
    bpy.ops.render.render()
    layers = scenes.read_exr_layers(scenes.save_result(scene, tmp_path / "passes.exr", "MULTILAYER"))
    from addon.blender.engine import LIGHT_PASSES

    diffuse_name, glossy_name = LIGHT_PASSES  # "Diffuse Direct", "Glossy Direct" (DiffDir, GlossDir in 4.x)
    assert {diffuse_name, glossy_name} <= set(layers)
    diffuse, glossy = layers[diffuse_name][..., :3], layers[glossy_name][..., :3]
    combined = layers["Combined"][..., :3].astype(np.float64)
    assert diffuse.max() > 0.05 and glossy.max() > 0.05, "both lobes contribute in this scene"
    total = diffuse.astype(np.float64) + glossy
    if model == "PBR":
        np.testing.assert_allclose(combined, total, rtol=1e-5, atol=1e-6)  # no ambient term in PBR
    else:
        ambient = 0.1 * np.array([0.6, 0.4, 0.2])
        np.testing.assert_allclose(combined, np.clip(total + ambient, 0.0, 1.0), rtol=1e-5, atol=1e-6)
        assert (total + ambient).max() > 1.0, "the Blinn-Phong passes stay unclamped"


#: The closed-form scene's sun: straight above the camera's view, tilted 30 degrees about x, 2 W/m^2.
SUN_TILT, SUN_E = math.radians(30.0), 2.0


def _closed_form_lobes(model):
    """Each lobe's radiance on a plane seen from straight above (n = v) under a sun 30 degrees
    off the normal, written here from the definitions, not from the engine's twin: PBR's
    Lambert (1 - F) rho / pi (eq. 1.18) and GGX D (1.15) x Smith height-correlated V (1.16-1.17)
    x Schlick F (1.11) at h.v; Blinn-Phong's c_PL = E / pi (section 1.2.7) times the diffuse
    colour (n.l) and the specular colour (n.h)^s (eq. 1.7)."""
    base, NoL, NoH = np.array([0.6, 0.4, 0.2]), math.cos(SUN_TILT), math.cos(SUN_TILT / 2.0)
    if model == "BLINN_PHONG":
        spec, s = np.array([0.3, 0.25, 0.2]), 12.0
        return base * SUN_E / math.pi * NoL, spec * SUN_E / math.pi * NoH ** s
    f0, alpha = 0.04, 0.35 ** 2
    a2 = alpha * alpha
    D = a2 / (math.pi * (NoH * NoH * (a2 - 1.0) + 1.0) ** 2)
    V = 0.5 / (NoL * math.sqrt(1.0 * (1.0 - a2) + a2) + 1.0 * math.sqrt(NoL * NoL * (1.0 - a2) + a2))
    F = f0 + (1.0 - f0) * (1.0 - NoH) ** 5  # h.v = cos(15 degrees) = n.h here
    return (1.0 - F) * base / math.pi * SUN_E * NoL, np.full(3, D * V * F * SUN_E * NoL)


@pytest.mark.parametrize("model", ["PBR", "BLINN_PHONG"])
def test_each_light_pass_holds_its_own_lobe(model, tmp_path):
    """Diffuse Direct and Glossy Direct each equal their lobe's closed form: swapped passes, or a
    lobe written to the wrong pass, fail here (the sum test above cannot see them)."""
    scene = scenes.reset(size=8)
    scene.shading_lab.model = model
    scene.shading_lab.ambient = 0.1
    scenes.ortho_camera(scene, scale=2.0)
    scenes.plane(scene, size=8.0, material=scenes.material(
        base_color=(0.6, 0.4, 0.2), roughness=0.35, specular_color=(0.3, 0.25, 0.2), shininess=12.0))
    scenes.light(scene, "SUN", energy=SUN_E, rotation=(SUN_TILT, 0.0, 0.0))
    vl = scene.view_layers[0]
    vl.use_pass_diffuse_direct = vl.use_pass_glossy_direct = True
    bpy.ops.render.render()
    layers = scenes.read_exr_layers(scenes.save_result(scene, tmp_path / "lobes.exr", "MULTILAYER"))
    from addon.blender.engine import LIGHT_PASSES

    want = dict(zip(LIGHT_PASSES, _closed_form_lobes(model)))
    for name, expected in want.items():
        got = layers[name][..., :3].reshape(-1, 3).astype(np.float64)
        err = np.abs(got / expected - 1.0).max()
        print(f"{model} {name}: {got.mean(axis=0)} against {expected}, relative error {err:.2e}")
        assert err < 5e-6, f"{name}: relative error {err:.2e} against its closed form (measured <= 8.8e-7)"


def test_renders_read_into_the_buffers_the_last_one_handed_back(tmp_path):
    """A final render reads each output into a buffer of its own, hands the buffers back once
    Blender has the pixels, and the next render reads into them: every pass keeps its own
    pixels (the lobes still sum to Combined), a changed scene changes them, and the first scene
    again gives its first image bit for bit."""
    from addon.blender.engine import LIGHT_PASSES
    from addon.frame.gpu_library import LIBRARY

    scene = _scene("PBR")
    material = scene.objects["Plane"].active_material
    LIBRARY.drop_spares()
    layers = []
    for colour in ((0.6, 0.4, 0.2), (0.1, 0.5, 0.7), (0.6, 0.4, 0.2)):
        material.shading_lab.base_color = colour
        bpy.ops.render.render()
        saved = scenes.save_result(scene, tmp_path / "passes.exr", "MULTILAYER")
        layers.append(scenes.read_exr_layers(saved))
        kept = LIBRARY.spare_bytes("read buffer")
        assert kept == 3 * 32 * 32 * 16, f"{kept} bytes kept: Combined's, the two lobes' buffers"
    diffuse_name, glossy_name = LIGHT_PASSES
    for frame in layers:
        total = frame[diffuse_name][..., :3].astype(np.float64) + frame[glossy_name][..., :3]
        np.testing.assert_allclose(frame["Combined"][..., :3], total, rtol=1e-5, atol=1e-6)
    changed = np.abs(layers[1]["Combined"] - layers[0]["Combined"]).max()
    print(f"the second scene changed Combined by up to {changed:.3f}")
    assert changed > 0.25, f"{changed}: the second scene's image (measured 0.55)"
    for name in ("Combined", diffuse_name, glossy_name):
        again = np.abs(layers[2][name] - layers[0][name]).max()
        assert again == 0.0, f"{name}: {again} from the first render of the same scene"


def test_pass_names_are_eevees(tmp_path):
    """The same strings EEVEE writes for the same view-layer toggles in this Blender."""
    from addon.blender.engine import LIGHT_PASSES

    scene = _scene("PBR")
    scene.render.engine = "BLENDER_EEVEE" if bpy.app.version >= (5, 0, 0) else "BLENDER_EEVEE_NEXT"
    scene.render.resolution_x = scene.render.resolution_y = 8
    bpy.ops.render.render()
    eevee = set(scenes.read_exr_layers(scenes.save_result(scene, tmp_path / "eevee.exr", "MULTILAYER")))
    assert set(LIGHT_PASSES) <= eevee, f"EEVEE wrote {sorted(eevee)}"


def _run(job, r, **switches):
    """``run_on_gpu(job)``, then the passes' ``switches`` set back (name=value) and ``r`` freed."""
    from gpu_harness import run_on_gpu

    from addon.frame import passes

    try:
        return run_on_gpu(job)
    finally:
        for name, value in switches.items():
            setattr(passes, name, value)
        run_on_gpu(lambda _d: r.free())


def _veil(scene) -> None:
    """A partly transparent plane across the camera's view, 3 m in front of it."""
    from mathutils import Matrix

    glass = scenes.material("Veil", base_color=(0.2, 0.5, 0.9), roughness=0.3)
    scenes.node_tree(glass).nodes["Principled BSDF"].inputs["Alpha"].default_value = 0.5
    veil = scenes.plane(scene, size=30.0, material=glass)
    veil.matrix_world = scene.camera.matrix_world @ Matrix.Translation((0.0, 0.0, -3.0))


@pytest.mark.parametrize("preset", ["material_grid", "world", "portability", "softbox"])
def test_opaque_surfaces_drawn_against_the_occlusion_prepass_change_no_pixel(preset):
    """Where the world's occlusion draws its prepass (or, in a black world, costly shading asks for
    the prepass alone, depth alone: softbox's area lights), the opaque pass takes that depth and shades
    each pixel once: exactly the image drawn with a depth test of its own (and a partly
    transparent plane in front, which peels against that depth, blends as before)."""
    from gpu_harness import run_on_gpu

    from addon.blender import extract, scene_builder
    from addon.frame import passes, renderer
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset(preset), scene)
    # softbox's prepass pays only with more pixels than its spheres' ~28k triangles
    w, h = (256, 144) if preset == "softbox" else (96, 54)
    scene.render.resolution_x, scene.render.resolution_y = w, h
    _veil(scene)
    r = renderer.Renderer()

    def job(depsgraph):
        out = {}
        passes.DEFERRED = False  # forward: the prepass's depth or the target's own
        for once in (True, False):
            passes.SHADE_ONCE = once
            out[once] = r.render(extract.snapshot(depsgraph, w, h))
            out[once, "shared"] = r._passes[passes.OpaquePass, "main"].target.shares_depth
            occlusion = r._passes[passes.OcclusionPass, "main"]
            out[once, "occlusion"] = occlusion.target is not None
            out[once, "depth alone"] = occlusion.prepass is not None and occlusion.prepass.colors == 0
        return out

    try:
        out = run_on_gpu(job)
    finally:
        passes.SHADE_ONCE = True
        passes.DEFERRED = True
        run_on_gpu(lambda _d: r.free())
    assert out[True, "shared"] and not out[False, "shared"], "the preset's shading asks for a prepass"
    assert out[True, "occlusion"] == (preset != "softbox"), "occlusion only where the world lights"
    # the prepass alone draws depth alone: no colour target (its normals would go unread)
    assert out[True, "depth alone"] == (preset == "softbox"), out[True, "depth alone"]
    lit = out[False][..., :3].max(axis=2) > 0.0
    assert lit.mean() > 0.5, lit.mean()
    differ = np.abs(out[True] - out[False]).max()
    assert differ == 0.0, f"{differ} largest difference"


def test_the_depth_prepass_is_drawn_where_shading_is_costly_and_the_geometry_is_not():
    """Without occlusion the prepass is drawn alone for programs costly per pixel (penumbrae, area
    lights, the world sampled per pixel, many lights), not for a light or two without penumbrae,
    and not where the triangles outnumber the pixels (their second draw would cost more)."""
    from dataclasses import replace

    from addon.frame import passes
    from addon.plan import programs

    cheap = programs.Features(light_kinds=frozenset({"POINT"}), max_lights=2, shadow_layers=6,
                              shadow_size=1024)
    costly = [replace(cheap, soft_shadows=True), replace(cheap, light_kinds=frozenset({"AREA"})),
              replace(cheap, environment="MAP", env_samples=16), replace(cheap, max_lights=8)]
    pixels = 640 * 360
    assert not passes.depth_prepass_pays([(cheap, [])], 1000, pixels)
    for features in costly:
        assert passes.depth_prepass_pays([(cheap, []), (features, [])], 1000, pixels), features
        assert not passes.depth_prepass_pays([(features, [])], pixels + 1, pixels), features
    # many lights count by those a pixel evaluates: light culling's ~4 of 64 are not many
    many = replace(cheap, max_lights=64, light_tiles=True)
    assert passes.depth_prepass_pays([(many, [])], 1000, pixels)
    assert not passes.depth_prepass_pays([(many, [])], 1000, pixels, lights=4.1)
    assert passes.depth_prepass_pays([(many, [])], 1000, pixels, lights=passes.MANY_LIGHTS)


def test_light_culling_counts_the_lights_a_pixel_evaluates():
    """64 point lights that each reach a disc of a sixteenth of the view: with light culling a
    pixel evaluates the lights of its tile, on average a little more than reach it (counted here
    pixel by pixel: 3.55, the discs at the border partly outside; a tile lists every light
    reaching some of its pixels), too few for the depth prepass; without culling every light, and
    the prepass drawn."""
    import math

    from addon.blender import extract
    from addon.frame import passes, renderer

    size, view = 1024, 8.0  # 8-pixel tiles of 0.0625 m, a light's disc 2.26 m across
    scene = scenes.reset(size=size)
    scenes.ortho_camera(scene, scale=view)
    scenes.plane(scene, size=2 * view)
    disc = math.sqrt(view * view / 16.0 / math.pi)
    centres = ((np.arange(8) + 0.5) / 8 - 0.5) * view
    for y in centres:
        for x in centres:
            light = scenes.light(scene, "POINT", energy=20.0, location=(x, y, 0.25))
            light.data.use_custom_distance, light.data.cutoff_distance = True, math.hypot(disc, 0.25)
    grid = (np.arange(256) + 0.5) / 256 * view - view / 2  # points on the plane, a grid
    dx2 = (grid[:, None] - centres[None, :]) ** 2  # (point x, light x)
    reaching = (dx2[:, None, :, None] + dx2[None, :, None, :] < disc * disc).sum(axis=(2, 3)).mean()
    r = renderer.Renderer()

    def job(depsgraph):
        out = {}
        for culling in (True, False):
            scene.shading_lab.light_culling = culling
            snapshot = extract.snapshot(depsgraph, size, size)
            r.render(snapshot)
            out[culling] = (r.scene.lights_per_pixel(None, size, size),
                            r._passes[passes.OcclusionPass, "main"].prepass is not None)
        return out

    out = _run(job, r)
    lights, prepass = out[True]
    print(f"lights a pixel evaluates with culling: {lights:.3f}, reaching it: {reaching:.3f}")
    assert reaching <= lights <= 1.2 * reaching, f"{lights:.3f} lights a pixel, {reaching:.3f} reach it"
    assert not prepass, "no prepass for ~4 lights a pixel"
    assert out[False] == (64.0, True), out[False]


def test_deferred_shading_is_chosen_by_the_shading_cost_and_the_triangles_size():
    """passes.deferred_pays: costly programs on triangles of 32 px or less on average, the
    heaviest (area lights, 5+ lights) up to 64 px; never a cheap program, a node graph's or a
    peeled surface, or a view beyond DEFERRED_PIXELS."""
    from addon.frame import passes
    from addon.plan import programs

    pixels = 640 * 360
    cheap = programs.Features(model="PBR", max_lights=2, light_kinds=frozenset({"POINT"}))
    world = replace(cheap, environment="UNIFORM")
    area = replace(cheap, light_kinds=frozenset({"AREA"}))
    many = replace(cheap, max_lights=8, shadow_layers=8)
    penumbrae = replace(cheap, soft_shadows=True, shadow_layers=6)  # costly, not of the heaviest
    cases = [(cheap, 10 ** 6, False), (world, pixels // 32, True), (world, pixels // 32 - 1, False),
             (penumbrae, pixels // 32, True), (penumbrae, pixels // 32 - 1, False),
             (area, pixels // 64, True), (area, pixels // 64 - 1, False), (many, pixels // 64, True),
             (many, pixels // 64 - 1, False),
             (replace(area, graph=programs.ZERO_AOV), 10 ** 6, False),  # a node graph: forward
             (replace(area, peel=True), 10 ** 6, False)]
    for features, triangles, expected in cases:
        assert passes.deferred_pays(features, triangles, pixels) == expected, (features, triangles)
    big = passes.DEFERRED_PIXELS + 1
    assert not passes.deferred_pays(area, big, big)


@pytest.mark.parametrize("preset", ["material_grid", "softbox", "world"])
def test_deferred_shading_changes_no_pixel(preset):
    """Shading the opaque surfaces deferred (their G-buffer first, then each program over its own
    pixels) gives exactly the forward image: with a surface that stays forward (an image-mapped
    plane), a mirrored object, a partly transparent veil in front and 2 x 2 supersampling; and so
    does the G-buffer drawn by the occlusion pass in its prepass's place (the same depth, normals
    and facing)."""

    from addon.blender import extract, scene_builder
    from addon.frame import passes, renderer
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset(preset), scene)
    scene.render.resolution_x, scene.render.resolution_y = 96, 54
    image = bpy.data.images.new("Checks", 4, 4)
    image.pixels.foreach_set(np.tile([0.9, 0.2, 0.1, 1.0, 0.1, 0.3, 0.8, 1.0], 8).astype(np.float32))
    mapped = scenes.material("Mapped", roughness=0.4)
    tree = scenes.node_tree(mapped)
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    tree.links.new(node.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    board = scenes.plane(scene, size=1.5, location=(0.3, 0.2, 0.9), rotation=(1.2, 0.0, 0.4), material=mapped)
    board.data.uv_layers.new(name="UVMap").data.foreach_set(
        "uv", np.array([(0, 0), (1, 0), (1, 1), (0, 1)], np.float32).ravel())
    mirrored = scenes.plane(scene, size=1.0, location=(-1.0, -0.5, 0.6), rotation=(0.9, 0.0, 0.0),
                            material=scenes.material("Mirrored", base_color=(0.2, 0.8, 0.3)))
    mirrored.scale = (-1.0, 1.0, 1.0)
    _veil(scene)
    r = renderer.Renderer()

    def job(depsgraph):
        out = {}
        snapshot = extract.snapshot(depsgraph, 96, 54)
        for deferred, ahead in ((True, True), (True, False), (False, True)):
            passes.DEFERRED, passes.GBUFFER_AHEAD = deferred, ahead
            out[deferred, ahead] = r.render(snapshot, samples=2).copy()
            occlusion = r._passes[passes.OcclusionPass, "main"]
            out[deferred, ahead, "gbuffer"] = (r._passes[passes.OpaquePass, "main"].gbuffer is not None,
                                               occlusion.gbuffer is not None, occlusion.prepass is not None)
            out[deferred, "kinds"] = {passes.deferred_pays(f, snapshot.triangle_count, 4 * 96 * 54)
                                      for f, _ in r.scene.draw_lists(None, False).opaque}
        return out

    out = _run(job, r, DEFERRED=True, GBUFFER_AHEAD=True)
    assert out[True, "kinds"] == {True, False}, "the mapped plane forward, the rest deferred"
    # where the world lights, the occlusion pass draws the G-buffer in its prepass's place
    occluded = preset != "softbox"
    assert out[True, True, "gbuffer"] == (not occluded, occluded, False), out[True, True, "gbuffer"]
    assert out[True, False, "gbuffer"] == (True, False, occluded), out[True, False, "gbuffer"]
    assert out[False, True, "gbuffer"] == (False, False, occluded), out[False, True, "gbuffer"]
    lit = out[False, True][..., :3].max(axis=2) > 0.0
    assert lit.mean() > 0.5, lit.mean()
    for deferred in ((True, True), (True, False)):
        differ = np.abs(out[deferred] - out[False, True]).max()
        assert differ == 0.0, f"{differ} largest difference ({deferred})"


def test_each_deferred_group_shaded_over_its_rectangle_changes_no_pixel(monkeypatch):
    """Two deferred groups (softbox's spheres, one of them on exact Fresnel: a program of its own),
    each shaded over the rectangle around its surfaces on screen (deferred_rectangle) and behind
    the depth test against its pixels' groups (depth_gated: GBuffer.write_groups): the image
    equals the one shaded over the whole target with neither and the forward one, to the bit,
    2 x 2 supersampled; the one sphere's rectangle is a small part of the target; a rectangle a
    pixel short on each side loses that sphere's edge pixels."""
    from addon.blender import extract, scene_builder
    from addon.frame import passes, renderer
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset("softbox"), scene)
    scene.render.resolution_x, scene.render.resolution_y = 96, 54
    sphere = next(obj for obj in scene.objects if obj.type == "MESH" and obj.active_material is not None
                  and "Floor" not in obj.name and "Ground" not in obj.name)
    sphere.active_material = sphere.active_material.copy()
    sphere.active_material.shading_lab.fresnel = "EXACT"
    r = renderer.Renderer()
    rectangles = []
    deferred_rectangle = passes.deferred_rectangle

    def recorded(frame, view, draws, width, height):
        rectangles.append((len(draws), deferred_rectangle(frame, view, draws, width, height), width, height))
        return rectangles[-1][1]

    monkeypatch.setattr(passes, "deferred_rectangle", recorded)

    def job(depsgraph):
        out = {}
        snapshot = extract.snapshot(depsgraph, 96, 54)
        for label, deferred, scissor in (("scissor", True, True), ("whole", True, False),
                                         ("forward", False, True)):
            passes.DEFERRED, passes.DEFERRED_SCISSOR = deferred, scissor
            passes.DEFERRED_DEPTH_TEST = label == "scissor"
            out[label] = r.render(snapshot, samples=2).copy()
            if label == "scissor":
                opaque = r._passes[passes.OpaquePass, "main"]
                out["gated"] = opaque.gbuffer is not None and opaque.gbuffer.group_depth is not None
        passes.DEFERRED, passes.DEFERRED_SCISSOR, passes.DEFERRED_DEPTH_TEST = True, True, True

        def short(frame, view, draws, width, height):
            x, y, w, h = deferred_rectangle(frame, view, draws, width, height)
            return x + 1, y + 1, w - 2, h - 2

        monkeypatch.setattr(passes, "deferred_rectangle", short)
        out["short"] = r.render(snapshot, samples=2).copy()
        return out

    out = _run(job, r, DEFERRED=True, DEFERRED_SCISSOR=True, DEFERRED_DEPTH_TEST=True)
    assert out["gated"], "two groups: the groups' depth written and tested"
    assert len(rectangles) >= 2 and rectangles[0][0] != rectangles[1][0], rectangles  # two groups
    one = min(rectangles[:2], key=lambda g: g[0])  # the one sphere's group
    share = one[1][2] * one[1][3] / (one[2] * one[3])
    print(f"the one sphere's rectangle {one[1]}: {share:.3f} of the {one[2]} x {one[3]} target")
    assert 0.0 < share < 0.25, share
    for label in ("whole", "forward"):
        differ = float(np.abs(out["scissor"] - out[label]).max())
        assert differ == 0.0, f"{differ} largest difference against {label}"
    lost = float(np.abs(out["scissor"] - out["short"]).max())
    print(f"a rectangle a pixel short on each side: largest difference {lost:.3f}")
    assert lost > 0.3, f"a rectangle a pixel short changed no pixel: {lost}"  # measured 1.04


def _closed_sphere(scene, name, radius, location, inward=False, scale=(1.0, 1.0, 1.0)):
    """A closed UV sphere object with its own material (``inward``: its faces turned in)."""
    import bmesh

    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=radius)
    if inward:
        bmesh.ops.reverse_faces(bm, faces=bm.faces[:])
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(scenes.material(name, base_color=(0.7, 0.6, 0.5), roughness=0.5))
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    obj.location, obj.scale = location, scale
    return obj


def test_closed_surfaces_seen_from_outside_cull_their_hidden_faces_changing_no_pixel():
    """Closed surfaces wholly beyond the camera's near plane are drawn with the faces turned from
    the camera culled (prepass, G-buffer and forward shading): their nearest face along each ray
    faces the camera, so nothing changes to the bit, forward and deferred; a mirrored sphere and
    one whose faces turn in cull the other side; a sphere around the camera (seen from inside)
    and a sphere the near plane cuts (its inside seen through the cut) cull nothing."""
    from mathutils import Vector

    from addon.blender import extract, scene_builder
    from addon.frame import passes, renderer
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset("material_grid"), scene)
    scene.render.resolution_x, scene.render.resolution_y = 96, 54
    camera = scene.camera.matrix_world
    forward = (camera.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
    right = (camera.to_3x3() @ Vector((1.0, 0.0, 0.0))).normalized()
    eye = camera.translation
    _closed_sphere(scene, "Mirrored", 0.5, eye + 6.0 * forward - 1.0 * right, scale=(-1.0, 1.0, 1.0))
    _closed_sphere(scene, "Inward", 0.5, eye + 6.0 * forward + 1.0 * right, inward=True)
    # around everything, the camera inside: its inside is what the camera sees beyond the spheres
    # (the floor taken away)
    bpy.data.objects.remove(scene.objects["Floor"])
    _closed_sphere(scene, "Room", 15.0, eye)
    scene.camera.data.clip_end = 100.0
    # across the near plane (0.1 m): its inside seen through the cut, on the right of the view
    _closed_sphere(scene, "Cut", 0.3, eye + (scene.camera.data.clip_start + 0.05) * forward + 0.35 * right)
    r = renderer.Renderer()

    def job(depsgraph):
        out = {}
        snapshot = extract.snapshot(depsgraph, 96, 54)
        for deferred in (True, False):
            for cull in (True, False):
                passes.DEFERRED, passes.CULL_CLOSED_SURFACES = deferred, cull
                out[deferred, cull] = r.render(snapshot).copy()
        draws = [d for _f, group in r.scene.draw_lists(None, False).opaque for d in group]
        facing = r.scene.view_facing(draws, snapshot.camera.view_projection)
        out["facing"] = {}
        for draw, f in zip(draws, facing):
            out["facing"].setdefault(snapshot.items[draw.order].materials[0], set()).add(int(f))
        return out

    out = _run(job, r, DEFERRED=True, CULL_CLOSED_SURFACES=True)
    facing = {next((n for n in ("Mirrored", "Inward", "Room", "Cut") if n in key), key): f
              for key, f in out["facing"].items()}
    assert facing["Mirrored"] == {-1} and facing["Inward"] == {-1}, facing
    assert facing["Room"] == {0} and facing["Cut"] == {0}, facing
    grid = {key: f for key, f in facing.items() if key not in ("Mirrored", "Inward", "Room", "Cut")}
    assert len(grid) == 18 and all(f == {1} for f in grid.values()), f"the grid's 6 x 3 spheres: {facing}"
    for deferred in (True, False):
        image = out[deferred, True]
        lit = (image[..., :3].max(axis=2) > 0.0).mean()
        assert lit > 0.9, f"the room's inside fills the background: {lit:.3f} of the pixels lit"
        differ = np.abs(image - out[deferred, False]).max()
        assert differ == 0.0, f"{differ} largest difference (deferred {deferred})"


def test_a_renderer_takes_the_last_ones_target_textures_and_shows_none_of_their_pixels(monkeypatch):
    """A finished renderer hands its targets' textures (G-buffer, occlusion, scene, peeling) to
    the library, and the next renderer's targets of the same size and format take them instead of
    allocating: its image, of another view of the scene, is bit for bit the one drawn into fresh
    textures -- nothing of the pixels they held shows."""
    from gpu_harness import run_on_gpu
    from mathutils import Matrix

    from addon.blender import extract, scene_builder
    from addon.frame import gpu_library, renderer
    from addon.scene import presets

    library = gpu_library.LIBRARY
    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset("material_grid"), scene)
    bpy.data.objects.remove(scene.objects["Floor"])  # pixels without a surface, where they had one
    scene.render.resolution_x, scene.render.resolution_y = 96, 54
    _veil(scene)

    def render(depsgraph):
        r = renderer.Renderer()
        try:
            image = r.render(extract.snapshot(depsgraph, 96, 54), samples=2).copy()
            kinds = {type(step).__name__ for step in r._passes.values() if step.textures()}
        finally:
            r.free()
        return image, kinds

    library.drop_spares()
    first, kinds = run_on_gpu(render)
    assert {"OcclusionPass", "OpaquePass", "TransparencyPass"} <= kinds, kinds
    kept = library.spare_bytes("texture")
    # 2 x 2 supersampled 96 x 54: the G-buffer's three float32 textures alone are 248,832 bytes
    assert kept > 3 * 16 * 192 * 108, kept
    scene.camera.matrix_world = Matrix.Translation((0.4, 0.3, 0.0)) @ scene.camera.matrix_world
    taken = []
    take = library.take_texture
    monkeypatch.setattr(library, "take_texture", lambda *key: taken.append(take(*key)) or taken[-1])
    reused, _ = run_on_gpu(render)
    library.drop_spares()
    fresh, _ = run_on_gpu(render)
    made = len(taken) // 2
    assert made >= 10 and all(t is not None for t in taken[:made]), taken
    assert all(t is None for t in taken[made:]), "the spares were dropped"
    moved = float(np.abs(reused - first).max())
    assert moved > 0.05, f"moving the camera changed the image by only {moved}"
    assert np.array_equal(reused, fresh), float(np.abs(reused - fresh).max())


def test_views_beyond_the_deferred_budget_are_shaded_forward():
    """A view with more pixels than passes.DEFERRED_PIXELS keeps no G-buffer (its memory) and
    gives the deferred image exactly."""
    from gpu_harness import run_on_gpu

    from addon.blender import extract, scene_builder
    from addon.frame import passes, renderer
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset("material_grid"), scene)
    r = renderer.Renderer()

    def job(depsgraph):
        out = {}
        snapshot = extract.snapshot(depsgraph, 64, 36)
        for budget in (64 * 36, 64 * 36 - 1):
            passes.DEFERRED_PIXELS = budget
            out[budget] = r.render(snapshot).copy()
            out[budget, "gbuffer"] = any(r._passes[kind, "main"].gbuffer is not None
                                         for kind in (passes.OpaquePass, passes.OcclusionPass))
        return out

    try:
        out = run_on_gpu(job)
    finally:
        passes.DEFERRED_PIXELS = 3840 * 2160
        run_on_gpu(lambda _d: r.free())
    assert out[64 * 36, "gbuffer"] and not out[64 * 36 - 1, "gbuffer"]
    differ = np.abs(out[64 * 36] - out[64 * 36 - 1]).max()
    assert differ == 0.0, f"{differ} largest difference"
