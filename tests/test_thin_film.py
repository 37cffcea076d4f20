"""The Principled BSDF's Thin Film (glsl/thin_film.glsl, twin addon/reference/thin_film.py): the
iridescent Fresnel against Cycles, the GPU against the twin, the twin against the exact film
summed over wavelengths, and only where a material has one (the film at its extremes:
test_principled_lobes.py's checks over every lobe).

Cycles' Fresnel itself is read off mirror spheres (roughness 0, black base) in a uniform white
world: each pixel's radiance is the Fresnel at the pixel's n.v, exactly (one sample at the pixel's
centre, one glossy bounce). Whole renders follow test_principled_lobes' method (direct light, a
point light and a sun, the film swept by a node graph and at fixed values).
"""

from __future__ import annotations

import dataclasses
import math

import bpy
import numpy as np
import OpenEXR
import pytest
import scenes
import test_principled_lobes as PL
from glsl_harness import evaluate
from test_material_render import _against_cycles, _scene, _within

from addon.blender import materials
from addon.materials import convert
from addon.plan import programs
from addon.reference import thin_film as T
from addon.scene import snapshot as S

#: The rule of the running Blender's Cycles (snapshot.THIN_FILM_RULES), and its version's key of the
#: measured tables below
RULE = S.thin_film_rule(bpy.app.version)
CYCLES_5 = RULE == "CYCLES_5"
VERSION = f"{bpy.app.version[0]}.{bpy.app.version[1]}"

# --- Cycles' Fresnel on mirror spheres --------------------------------------------------------------

#: (thickness nm, film IOR) of each mirror sphere; base IOR 1.5 (the metal: a gold-ish F0)
MIRRORS = [(d, n2) for d in (0.0, 150.0, 300.0, 600.0, 1000.0) for n2 in (1.0, 1.33, 2.0)] + [(0.5, 1.33)]
METAL_F0 = (0.9, 0.6, 0.3)


def _mirror_scene(metal: bool):
    """A row of mirror spheres, one per MIRRORS entry, in a white world; AOVs: the film's thickness
    and IOR, the shading normal and the incoming direction."""
    scene = scenes.reset(size=24)
    scene.render.resolution_x, scene.render.resolution_y = 24 * len(MIRRORS), 24
    scenes.ortho_camera(scene, location=(0.0, 0.0, 10.0), scale=2.0 * len(MIRRORS))
    world = bpy.data.worlds.new("White")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    for name, kind in (("d", "VALUE"), ("n2", "VALUE"), ("N", "COLOR"), ("I", "COLOR")):
        aov = scene.view_layers[0].aovs.add()
        aov.name, aov.type = name, kind
    for i, (d, n2) in enumerate(MIRRORS):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.95,
                                             location=(-len(MIRRORS) + 1.0 + 2.0 * i, 0.0, 0.0))
        bpy.ops.object.shade_smooth()
        mat = bpy.data.materials.new(f"Mirror{i}")
        tree = scenes.node_tree(mat)
        tree.nodes.clear()
        bpy.context.active_object.data.materials.append(mat)
        bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
        tree.links.new(bsdf.outputs["BSDF"], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
        bsdf.inputs["Roughness"].default_value = 0.0
        bsdf.inputs["Base Color"].default_value = (*METAL_F0, 1.0) if metal else (0.0, 0.0, 0.0, 1.0)
        bsdf.inputs["Metallic"].default_value = 1.0 if metal else 0.0
        bsdf.inputs["Thin Film Thickness"].default_value = d
        bsdf.inputs["Thin Film IOR"].default_value = n2
        geometry = tree.nodes.new("ShaderNodeNewGeometry")
        for name, socket in (("d", None), ("n2", None), ("N", geometry.outputs["Normal"]),
                             ("I", geometry.outputs["Incoming"])):
            node = tree.nodes.new("ShaderNodeOutputAOV")
            node.aov_name = name
            if socket is None:
                value = tree.nodes.new("ShaderNodeValue")
                value.outputs[0].default_value = d if name == "d" else n2
                socket = value.outputs[0]
            tree.links.new(socket, node.inputs["Value" if name in ("d", "n2") else "Color"])
    return scene


def _mirror_render(metal: bool, tmp):
    """Cycles' mirror spheres: (radiance, n.v, thickness, film IOR) of the pixels whose reflection
    reaches the world above (n.v > 0.8: the others may see the neighbouring spheres)."""
    scene = _mirror_scene(metal)
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device, c.samples, c.use_adaptive_sampling, c.use_denoising = "CPU", 1, False, False
    c.max_bounces, c.glossy_bounces, c.diffuse_bounces = 1, 1, 0
    c.pixel_filter_type, c.filter_width, c.seed = "GAUSSIAN", 0.01, 1
    scenes.render(scene, tmp / "mirror.exr")
    path = scenes.save_result(scene, tmp / "mirror_aovs.exr", "MULTILAYER")
    with OpenEXR.File(str(path)) as f:
        ch = {name: np.asarray(x.pixels, np.float64) for part in f.parts for name, x in part.channels.items()}

    def rows(name):
        a = ch[name]
        return a.reshape(-1, a.shape[-1]) if a.ndim == 3 else a.ravel()

    combined, n, i = rows("ViewLayer.Combined"), rows("ViewLayer.N")[:, :3], rows("ViewLayer.I")[:, :3]
    cos = np.sum(n * i, axis=1)
    keep = (combined[:, 3] > 0.999) & (cos > 0.8)
    d, n2 = rows("ViewLayer.d.X")[keep], rows("ViewLayer.n2.X")[keep]
    return combined[keep, :3], cos[keep], d, n2


@pytest.fixture(scope="module")
def mirrors(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("mirrors")
    return {metal: _mirror_render(metal, tmp) for metal in (False, True)}


def _twin_fresnel(metal: bool, cos, d, n2, rule=RULE):
    """The twin's Fresnel of the mirror spheres by Cycles' ``rule``: the Principled BSDF's dielectric
    (IOR 1.5, F0 0.04) or metal (F0 METAL_F0, white tint) under a film of thickness d and IOR n2 (none
    at 0.1 nm or less; 4.x's metal bare)."""
    table, blend = T.engine_sensitivity(rule), T.BLEND_NM[rule]
    film = d > T.THICKNESS_CUTOFF
    if metal:
        f0 = np.broadcast_to(METAL_F0, (len(cos), 3))
        bare = T.f82(cos[:, None], f0, 0.0)
        filmed = T.iridescence_metal(cos, d, n2, f0, 0.0, table, blend) if rule == "CYCLES_5" else bare
    else:
        bare = np.repeat(T.iridescence_dielectric(cos, 0.0, 1.0, 1.5, table), 1, axis=0)
        filmed = T.dielectric_fresnel(cos, d, n2, 1.5, np.full((len(cos), 3), 0.04), table, blend)
    return np.where(film[:, None], filmed, bare)


#: Largest difference from Cycles' mirror spheres (absolute, the Fresnel in [0, 1]), the dielectric's
#: and the metal's, per Blender (4.2 and 4.5: their Gaussian fit of the CIE functions' transform in
#: XYZ, a 30 nm blend, the metal bare), measured with bpy 5.0.1, 4.5.15 and 4.2.23
MIRROR_MEASURED = {"5.0": {False: 3.1e-7, True: 6.8e-7}, "4.5": {False: 3.8e-7, True: 1.7e-7},
                   "4.2": {False: 3.7e-7, True: 8.8e-8}}
#: The film's effect on the mirrors, and the other rule's difference, against that difference (at
#: least): 5.0's, 4.x's (the film's effect on the dielectric alone: their metal has none)
MIRROR_EFFECT = {"CYCLES_5": 1000.0, "CYCLES_4": 1000.0}


@pytest.mark.parametrize("metal", [False, True], ids=["dielectric", "metal"])
def test_twin_fresnel_matches_cycles_mirrors(mirrors, metal):
    """The twin's iridescent Fresnel (and the bare one at 0 nm and film IOR 1) equals what Cycles'
    mirror spheres reflect of a white world at every pixel's n.v, for thickness 0-1000 nm and film
    IOR 1, 1.33 and 2."""
    radiance, cos, d, n2 = mirrors[metal]
    err = np.abs(_twin_fresnel(metal, cos, d, n2) - radiance)
    worst = float(err.max())
    film = d > T.THICKNESS_CUTOFF
    effect = float(np.abs(_twin_fresnel(metal, cos, np.zeros_like(d), n2) - radiance)[film].max())
    other = "CYCLES_4" if CYCLES_5 else "CYCLES_5"
    other_err = float(np.abs(_twin_fresnel(metal, cos, d, n2, other) - radiance).max())
    print(f"Blender {VERSION}, {'metal' if metal else 'dielectric'} mirrors: {len(cos)} pixels, largest "
          f"difference {worst:.3g} (mean {err.mean():.3g}); the film changes the Fresnel by up to "
          f"{effect:.3g}; the other rule ({other}) differs by {other_err:.3g}")
    measured = MIRROR_MEASURED[VERSION][metal]
    assert worst <= 3.0 * measured, f"{worst:.3g} (measured {measured:.3g})"
    if CYCLES_5 or not metal:  # (4.x's metal has no film)
        assert effect >= MIRROR_EFFECT[RULE] * measured, effect
    assert other_err >= MIRROR_EFFECT[RULE] * measured, f"the other rule: {other_err:.3g}"  # it can tell them


# --- the GPU against the twin -------------------------------------------------------------------------

#: (thickness, film IOR, base IOR, tint, metal F0 / None, n.v) rows for the GPU's F_ThinFilm*
GPU_CASES = [(d, n2, eta, tint, f0) for d in (0.0, 0.5, 150.0, 300.0, 1000.0, 5000.0, 1e5)
             for n2 in (1.0, 1.33, 2.0, 4.0) for eta, tint, f0 in ((1.5, (1.0, 1.0, 1.0), None),
                                                                  (1.0, (1.0, 1.0, 1.0), None),
                                                                  (2.4, (1.0, 0.5, 0.2), None),
                                                                  (1.5, (1.0, 1.0, 1.0), (0.95, 0.64, 0.54)),
                                                                  (1.5, (1.0, 1.0, 1.0), (0.04, 0.2, 1.0)))]
COSINES = np.array([1.0, 0.9, 0.6, 0.3, 0.1, 0.01, 0.0])


#: The GPU's float32 against the twin, per rule: the largest difference, and the largest where n.v >= 0.1
#: (both over the metal of F0 (0.04, 0.2, 1): Gulbrandsen's k from 1 - r at r = 0.999, as Cycles'; the
#: dielectric's 1 - R12 R23 no longer cancels: thin_film.glsl's optical cosines, was 2.6e-4 at n.v 0.01)
GPU_MEASURED = {"CYCLES_5": (5.1e-5, 3.1e-5), "CYCLES_4": (4.1e-5, 3.1e-5)}


@pytest.mark.parametrize("rule", S.THIN_FILM_RULES)
def test_gpu_fresnel_matches_twin(rule):
    """thin_film.glsl's F_ThinFilmTinted and F_ThinFilmMetal against the twin over thickness 0 to
    1e5 nm, film IOR 1 to 4, base IOR 1 to 2.4 (tinted), metals, n.v from 1 to 0: float32 agreement,
    by each Blender's rule (its define, as programs.Features sets it)."""
    rows, want = [], []
    for d, n2, eta, tint, f0 in GPU_CASES:
        film = np.array([d, n2, S.THIN_FILM_RULES.index(rule), 0.0])
        f0_tinted = np.clip(((eta - 1.0) / (eta + 1.0)) ** 2 * np.array(tint), 0.0, 1.0)
        cos = COSINES
        if f0 is None:
            tinted = np.broadcast_to(f0_tinted, (len(cos), 3))
            F = T.dielectric(np.broadcast_to(film, (len(cos), 4)), eta, tinted, cos)
            kind = 0.0
            color = f0_tinted
        else:
            F = T.metal(np.broadcast_to(film, (len(cos), 4)), np.broadcast_to(f0, (len(cos), 3)), 0.0, cos)
            kind = 1.0
            color = np.asarray(f0)
        for c, value in zip(cos, F):
            rows.append(([d, n2, eta, c], [*color, kind]))
            want.append(value)
    a = np.array([r[0] for r in rows])
    b = np.array([r[1] for r in rows])
    body = ("vec4 film = vec4(a.x, a.y, 0.0, 0.0);\n"
            "vec3 n, k, g;\n"
            "thin_film_metal_ior(b.rgb, vec3(0.0), n, k, g);\n"
            "vec3 F = b.w > 0.5 ? F_ThinFilmMetal(film, n, k, g, a.w)\n"
            "                   : F_ThinFilmTinted(film, a.z, b.rgb, a.w);\n"
            "result = vec4(F, 1.0);")
    features = programs.Features("PBR", 1, frozenset({"POINT"}), S.Terms(principled=True),
                                 lobes=frozenset({"THIN_FILM"}), thin_film_rule=rule)
    defines = {k: v for k, v in features.defines() if k.startswith("SL_THIN_FILM")}
    gpu = evaluate(body, {"a": a, "b": b}, defines)[:, :3]
    want = np.array(want)
    err = np.abs(gpu - want)
    worst = int(np.argmax(err.max(axis=1)))
    print(f"{rule}: GPU against the twin: {len(want)} rows, largest difference {err.max():.3g} at "
          f"{a[worst]}, {b[worst]}")
    assert np.all(np.isfinite(gpu))
    print(f"median {np.median(err):.3g}, n.v >= 0.1: {err[a[:, 3] >= 0.1].max():.3g}")
    worst_all, worst_lit = GPU_MEASURED[rule]
    assert err.max() <= 3.0 * worst_all, f"{err.max():.3g} at {a[worst]}, {b[worst]}"
    assert err[a[:, 3] >= 0.1].max() <= 3.0 * worst_lit, err[a[:, 3] >= 0.1].max()


# --- the twin against the exact film summed over wavelengths -----------------------------------------

def _spectral_reference(cos, d, n2, eta3, xyz_to_rgb):
    """The exact film's reflectance (T.airy_spectral, every order, per wavelength) integrated against
    the CIE 1931 2-degree functions (colour-science's, 1 nm) into the scene linear Rec. 709 of
    ``xyz_to_rgb``, normalised so that a white reflector gives 1 (the colour matching functions of
    unit area)."""
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    lam = cmfs.wavelengths
    rgb = cmfs.values @ np.asarray(xyz_to_rgb).T
    R = T.airy_spectral(lam, np.atleast_1d(cos), d, n2, eta3)  # (N, L)
    return (R @ rgb) / rgb.sum(axis=0)


#: The twin (Belcour & Barla's summation, three orders: as Cycles 5.0 tabulates the CIE functions'
#: transform, its entries 18.7 nm of path difference apart interpolated linearly; as Cycles 4.2 and
#: 4.5 fit it by Gaussians in XYZ) against the exact film over wavelengths: largest difference of the
#: reflectance (absolute), measured with a dielectric substrate of IOR 1.5 (the films at 30 nm or more:
#: no rule's blend).
AIRY_MEASURED = {"CYCLES_5": 5.6e-4, "CYCLES_4": 1.7e-2}


@pytest.mark.parametrize("rule", S.THIN_FILM_RULES)
def test_twin_approximates_the_exact_film(rule):
    """The twin's iridescent Fresnel by each rule against the classic thin-film formula summed over
    360-830 nm (written here, independent of the Fourier-space summation) on a substrate of IOR 1.5:
    thickness 50-1000 nm, film IOR 1.33 and 2, n.v 1 (normal incidence), 0.7 and 0.3."""
    table = T.engine_sensitivity(rule)
    xyz_to_rgb = convert.XYZ_TO_RGB if rule == "CYCLES_5" else convert.XYZ_TO_RGB_4
    cos = np.array([1.0, 0.7, 0.3])
    worst, at, mean = 0.0, None, []
    for d in (50.0, 150.0, 300.0, 600.0, 1000.0):
        for n2 in (1.33, 2.0):
            got = T.iridescence_dielectric(cos, d, n2, 1.5, table)
            want = _spectral_reference(cos, d, n2, 1.5, xyz_to_rgb)
            err = np.abs(got - want)
            mean.append(err.mean())
            if err.max() > worst:
                worst, at = float(err.max()), (d, n2, cos[int(np.argmax(err.max(axis=1)))])
    print(f"{rule}: the twin against the exact film over wavelengths: largest difference {worst:.3g} at "
          f"(d, n2, n.v) = {at}, mean {np.mean(mean):.3g}")
    assert worst <= 3.0 * AIRY_MEASURED[rule], f"{worst:.3g} at {at}"


# --- whole renders against Cycles ---------------------------------------------------------------------

def _film_graph(name, metal: bool):
    """Thin Film Thickness = 1000 u nm, Thin Film IOR 1 + v (1 to 2), over a dark dielectric of IOR
    1.5 (or a gold-ish metal) of roughness 0.3."""
    mat, tree, bsdf, u, v = PL._graph(name)
    bsdf.inputs["Base Color"].default_value = (0.9, 0.6, 0.3, 1.0) if metal else (0.02, 0.03, 0.05, 1.0)
    bsdf.inputs["Metallic"].default_value = 1.0 if metal else 0.0
    bsdf.inputs["Roughness"].default_value = 0.3
    thickness = tree.nodes.new("ShaderNodeMath")
    thickness.operation = "MULTIPLY"
    tree.links.new(u, thickness.inputs[0])
    thickness.inputs[1].default_value = 1000.0
    tree.links.new(thickness.outputs[0], bsdf.inputs["Thin Film Thickness"])
    ior = tree.nodes.new("ShaderNodeMath")
    ior.operation = "ADD"
    tree.links.new(v, ior.inputs[0])
    ior.inputs[1].default_value = 1.0
    tree.links.new(ior.outputs[0], bsdf.inputs["Thin Film IOR"])
    return mat


def _film(name, thickness, ior, metal=False, **inputs):
    """The constant path: a Principled BSDF of these values (a dark dielectric, or a gold-ish metal)."""
    base = (0.9, 0.6, 0.3, 1.0) if metal else (0.02, 0.03, 0.05, 1.0)
    return PL._principled(name, base_color=base, metallic=1.0 if metal else 0.0,
                          thin_film_thickness=thickness, thin_film_ior=ior, **{"roughness": 0.3, **inputs})


#: name -> (material, lights): the sweep through a graph, the constant path at the brief's points
FILM_CASES = {
    "graph-dielectric": (lambda: _film_graph("FilmSwept", False), ("SUN", "POINT")),
    "graph-metal": (lambda: _film_graph("FilmSweptMetal", True), ("SUN", "POINT")),
    "soap-150": (lambda: _film("Soap150", 150.0, 1.33), ("SUN", "POINT")),
    "soap-300": (lambda: _film("Soap300", 300.0, 1.33, roughness=0.15), ("SUN", "POINT")),
    "oil-600": (lambda: _film("Oil600", 600.0, 2.0), ("SUN", "POINT")),
    "thick-1000": (lambda: _film("Thick1000", 1000.0, 1.33), ("SUN", "POINT")),
    "metal-300": (lambda: _film("Metal300", 300.0, 2.0, metal=True), ("SUN", "POINT")),
    "metal-1000": (lambda: _film("Metal1000", 1000.0, 1.33, metal=True, roughness=0.5), ("POINT", "BACK")),
    "tinted": (lambda: _film("TintedFilm", 300.0, 1.6, specular_tint=(1.0, 0.5, 0.2, 1.0)), ("SUN", "POINT")),
}
#: (mean, 99th percentile) relative error of the lit pixels per Blender, measured with bpy 5.0.1,
#: 4.5.15 and 4.2.23 (each drawn by its own rule)
FILM_MEASURED = {
    "5.0": {"graph-dielectric": (8.9e-4, 2.82e-3), "graph-metal": (1.1e-3, 3.07e-3),
            "soap-150": (2.25e-4, 1.45e-3), "soap-300": (2.4e-3, 8.77e-3), "oil-600": (8.52e-4, 2.76e-3),
            "thick-1000": (1.92e-4, 1.22e-3), "metal-300": (1.03e-3, 3.0e-3),
            "metal-1000": (6.9e-4, 6.11e-3), "tinted": (5.46e-4, 2.38e-3)},
    "4.5": {"graph-dielectric": (1.01e-3, 2.71e-3), "graph-metal": (1.07e-3, 2.83e-3),
            "soap-150": (2.57e-4, 1.82e-3), "soap-300": (2.92e-3, 6.41e-3), "oil-600": (9.22e-4, 2.67e-3),
            "thick-1000": (2.12e-4, 1.49e-3), "metal-300": (1.07e-3, 2.83e-3),
            "metal-1000": (7.94e-4, 7.1e-3), "tinted": (6.38e-4, 2.65e-3)},
    "4.2": {"graph-dielectric": (1.01e-3, 2.72e-3), "graph-metal": (1.07e-3, 2.83e-3),
            "soap-150": (2.58e-4, 1.82e-3), "soap-300": (2.93e-3, 6.52e-3), "oil-600": (9.22e-4, 2.67e-3),
            "thick-1000": (2.12e-4, 1.49e-3), "metal-300": (1.07e-3, 2.83e-3),
            "metal-1000": (7.94e-4, 7.1e-3), "tinted": (6.38e-4, 2.65e-3)},
}


@pytest.mark.parametrize("case", FILM_CASES)
def test_thin_film_matches_cycles(case, tmp_path):
    """Ours against Cycles under a sun and a point light, the film turned off (Thickness 0) changing
    Cycles' image by at least 5x our error (test_principled_lobes' _lobe_against_cycles); Blender 4.2
    and 4.5 leave the metal bare: there the metal cases hold ours to Cycles alone (a film drawn on the
    metal would be far off)."""
    make, lights = FILM_CASES[case]
    measured = FILM_MEASURED[VERSION][case]
    if CYCLES_5 or "metal" not in case:
        PL._lobe_against_cycles(make, {"Thin Film Thickness": 0.0}, measured,
                                f"thin film (Blender {VERSION}), {case}", tmp_path, lights=lights,
                                eevee=case == "graph-dielectric")
        return
    scene, _ = _scene(make, lights=tuple(k for k in lights if k in ("SUN", "POINT")))
    if "BACK" in lights:
        scenes.light(scene, "SUN", energy=3.0, rotation=(math.radians(160.0), 0.0, 0.0))
    scene.cycles.light_sampling_threshold = 0.0
    _, _, rel = _against_cycles(scene, tmp_path)
    _within(rel, *measured, f"thin film (Blender {VERSION}), {case}")


def test_film_ior_1_and_thickness_0_are_no_film(tmp_path):
    """A film of IOR 1 reflects nothing of its own: ours against Cycles; a thickness of 0 is no film at
    all: the same image as a material without one."""
    scene, sphere = _scene(lambda: _film("AirFilm", 300.0, 1.0))
    scene.cycles.light_sampling_threshold = 0.0
    _, _, rel = _against_cycles(scene, tmp_path)
    _within(rel, 2.6e-4, 2.3e-3, "film IOR 1")
    air = scenes.render(scene, tmp_path / "ior1.exr")
    sphere.data.materials[0] = _film("NoFilm", 0.0, 1.33)
    bare = scenes.render(scene, tmp_path / "zero.exr")
    sphere.data.materials[0] = PL._principled("Bare", base_color=(0.02, 0.03, 0.05, 1.0), roughness=0.3)
    plain = scenes.render(scene, tmp_path / "plain.exr")
    assert np.array_equal(bare, plain), float(np.abs(bare - plain).max())
    # a film of IOR 1 differs from none only in the layer's albedo estimate (Cycles takes the Fresnel at
    # the view where a film is, its table where none is): printed
    print(f"film IOR 1 against no film: {float(np.abs(air - plain).max()):.3g} of {float(plain.max()):.3g}")


def test_twin_thickness_0_is_no_film():
    """The twin: thickness 0 (and at most Cycles' cutoff 0.1 nm) gives the bare Fresnel exactly."""
    from addon.reference import shading

    cos = np.linspace(0.0, 1.0, 21)
    n = np.broadcast_to([0.0, 0.0, 1.0], (21, 3))
    v = np.stack([np.sqrt(1.0 - cos * cos), np.zeros(21), cos], -1)
    for d in (0.0, 0.1):
        for metal in (0.0, 1.0):
            bare = S.MaterialParams(base_color=(0.9, 0.6, 0.3), metalness=metal, roughness=0.3)
            m = dataclasses.replace(bare, thin_film_thickness=d)
            a = shading.principled_specular_tint(shading.Surface(np.zeros((21, 3)), n, v, m), cos)
            b = shading.principled_specular_tint(shading.Surface(np.zeros((21, 3)), n, v, bare), cos)
            assert np.array_equal(a, b), (d, metal)


# --- the GPU against the twin in whole programs, and at the extremes ----------------------------------

@pytest.mark.parametrize("sizes", [False, True], ids=["points", "sphere-lights"])
def test_gpu_matches_twin_in_programs(sizes, tmp_path):
    """test_twin's random planes and lights (every kind; point and spot lights with a radius), the
    Principled set with a film: float32 agreement (test_principled_lobes' bound). The twin's material
    holds the running Blender's film rule as the reader sets it (4.x: the Gaussian fit, the metal bare,
    a 30 nm blend), the program its define."""
    from test_twin import _compare

    lobes = dict(thin_film_thickness=420.0, thin_film_ior=1.7, specular_tint=(1.0, 0.8, 0.6),
                 **materials._thin_film_version())
    for seed in range(2):
        _compare("PBR", 700 + seed + (100 if sizes else 0), tmp_path / str(seed), sizes=sizes, lobes=lobes)


# The film at its extremes: test_principled_lobes.py's LOBE_CHECKS["THIN_FILM"] (FILM_EXTREMES, the
# float32-only cases FILM_FLOAT32), checked there with every lobe's.


# --- only what the scene requires, and Auto naming the lobe --------------------------------------------

def test_only_materials_with_a_film_compile_it():
    """SL_THIN_FILM only for a Principled BSDF whose Thickness is above 0 (linked: on), its table
    sampled only there."""
    from addon.blender import nodes as reader
    from addon.materials import graph, surface

    assert S.MaterialParams(thin_film_thickness=300.0).lobes == {"THIN_FILM"}
    assert S.MaterialParams(thin_film_thickness=0.0).lobes == frozenset()
    scenes.reset(size=8)
    linked = _film_graph("Linked", False)
    g, groups = reader.read_material(linked, "ALL", None)
    assert surface._lobes(graph.flatten(g, groups)) == {"THIN_FILM"}
    point, terms = frozenset({"POINT"}), S.Terms(principled=True)
    features = programs.Features("PBR", 1, point, terms, lobes=frozenset({"THIN_FILM"}))
    assert ("SL_THIN_FILM", "1") in features.defines() and features.uses_thin_film_table
    bare = programs.Features("PBR", 1, point, terms, lobes=frozenset({"COAT"}))
    assert ("SL_THIN_FILM", "1") not in bare.defines() and not bare.uses_thin_film_table
    # Blender 4.x's rule: its define and no table; a program without a film is one program for every rule
    old = programs.Features("PBR", 1, point, terms, lobes=frozenset({"THIN_FILM"}), thin_film_rule="CYCLES_4")
    names = dict(old.defines())
    assert "SL_THIN_FILM_CYCLES_4" in names and "SL_THIN_FILM_RGB" in names and not old.uses_thin_film_table
    assert "SL_THIN_FILM_CYCLES_4" not in dict(features.defines())
    coat_4 = programs.Features("PBR", 1, point, terms, lobes=frozenset({"COAT"}), thin_film_rule="CYCLES_4")
    assert coat_4 == bare
    with pytest.raises(ValueError, match="thin film rule"):
        programs.Features("PBR", 1, point, terms, lobes=frozenset({"THIN_FILM"}), thin_film_rule="CYCLES_3")


def test_reader_picks_the_rule_of_its_blender():
    """The reader's material holds the rule of the running Blender's Cycles (the define its program
    gets): 4.2 to 4.5 the Gaussian fit, 5.0 on the table."""
    from addon.blender import extract

    assert [S.thin_film_rule(v) for v in ((4, 2, 0), (4, 5, 15), (5, 0, 1), (5, 1))] == \
        ["CYCLES_4", "CYCLES_4", "CYCLES_5", "CYCLES_5"]
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    scene.shading_lab.term_set = "PRINCIPLED"
    m = materials.material_params(_film("Read", 300.0, 1.33))
    assert m.thin_film_rule == RULE and m.lobes == {"THIN_FILM"}, m.thin_film_rule
    features = programs.Features.from_snapshot(extract.snapshot(bpy.context.evaluated_depsgraph_get(), 8, 8),
                                               "PBR", material=m)
    assert "THIN_FILM" in features.lobes and features.thin_film_rule == RULE, features
    assert ("SL_THIN_FILM_CYCLES_4" in dict(features.defines())) == (RULE == "CYCLES_4")


def test_auto_names_the_thin_film():
    """Auto predicts a soap-bubble-like film against the Principled set with it: at a loose bound the
    film alone keeps the Principled set, and it is named the limiting lobe."""
    from addon.blender import extract

    scene, _ = _scene(lambda: _film("Bubble", 400.0, 1.33, roughness=0.1))
    scene.shading_lab.term_set = "AUTO"
    scene.shading_lab.auto_error_bound = 4.0
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get(), 1920, 1920)
    choices = {key.split(".")[0]: c for key, c in snap.term_choices.items()}
    c = choices["Bubble"]
    print(f"Bubble: {c.name} (alone: {c.alone or c.name}), {dict(c.errors)}, limiting {c.limiting}")
    assert c.name == "PRINCIPLED" and c.limiting.startswith("thin film"), c
