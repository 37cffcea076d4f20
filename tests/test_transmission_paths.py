"""Transmission's ways through closed objects (glsl/transmission.glsl, passes.RefractionPass) against
Cycles: lights seen through glass, the far face of rough glass, perspective cameras and the
viewport, partly transparent glass; and the far face's math in the numpy twin.

The scenes are test_transmission's (a glass sphere, a tilted slab or a one-face plane seen from above
by an orthographic camera, 48 px; Cycles with two transmission bounces, no glossy ones, no sample
clamping, at pixel centres). Lights seen through glass: nothing behind it (a black world), a point
light or a sun below it that casts shadows (Cycles then reaches it only from the far face, the
near face's shadow ray crossing the object). The far face: an emitting checker ground and no
light, so that the refraction alone is compared. The error is the covered pixels' absolute error
over their mean radiance in Cycles; where the light is the whole image, the sum of the image too.
"""

from __future__ import annotations

import math

import bpy
import mathutils
import numpy as np
import pytest
import scenes
from glsl_harness import evaluate
from gpu_harness import run_on_gpu, viewport_image
from test_transmission import (
    CENTRE,
    GPU_DEFINES,
    GPU_TERMS,
    RADIUS,
    SIZE,
    _covered,
    _cycles,
    _glass,
    _principled,
    _scene,
)

from addon.plan import programs
from addon.reference import brdf
from addon.reference import transmission as T


def _error(ours, ref, covered):
    """(mean, 99th percentile) of the covered pixels' absolute error over their mean in Cycles, and
    the ratio of the covered pixels' sums (ours over Cycles')."""
    scale = ref.max(-1)[covered].mean()
    rel = np.abs(ours - ref).max(-1)[covered] / scale
    return float(rel.mean()), float(np.quantile(rel, 0.99)), float(ours[covered].sum() / ref[covered].sum())


def _render(scene, path):
    return scenes.render(scene, path)[..., :3].astype(np.float64)


# --- lights seen through glass ------------------------------------------------------------------

def _point(z, radius=0.0):
    """A point light below the glass (a sphere light of ``radius``)."""
    return (("POINT", {"energy": 50.0, "location": (0.2, 0.1, z), "use_shadow": True,
                       "shadow_soft_size": radius}),)


def _sun_below(x_deg, y_deg):
    return (("SUN", {"energy": 3.0, "rotation": (math.radians(x_deg), math.radians(y_deg), 0.0),
                     "use_shadow": True}),)


#: name -> (shape, its tilt, roughness, lights, Cycles' samples)
LIGHT_CASES = {
    "plane-point-0.3": ("PLANE", 0.0, 0.3, _point(-0.8), 64),
    "plane-sun-0.6": ("PLANE", 30.0, 0.6, _sun_below(160.0, 0.0), 64),
    "slab-point-0.3": ("SLAB", 0.0, 0.3, _point(-0.8), 256),
    "slab-sun-0.6": ("SLAB", 30.0, 0.6, _sun_below(160.0, 0.0), 256),
    "sphere-point-0.3": ("SPHERE", 0.0, 0.3, _point(-1.2), 256),
    "sphere-sun-0.6": ("SPHERE", 0.0, 0.6, _sun_below(165.0, 10.0), 256),
    "plane-sphere-light-0.3": ("PLANE", 0.0, 0.3, _point(-0.8, 0.2), 512),
    "sphere-sphere-light-0.6": ("SPHERE", 0.0, 0.6, _point(-1.2, 0.2), 512),
}
#: (mean, 99th percentile, sum ratio) measured with bpy 5.0.1. Lit at the near face alone (as a
#: single interface, the engine before) the slab and sphere cases were 76 / 168 / 230 / 150 % mean,
#: their sums 1.20 / 1.26 / 2.39 / 2.07x Cycles'. Without the lobes' compensation for what single
#: scattering loses (glass_compensation): the planes 0.15 % / 2.5 % mean, sums 0.999 / 0.975; the
#: slabs 16.3 % / 5.7 % (sums 0.992 / 1.012), the spheres 23.0 % / 38.1 % (1.085 / 0.848). With it,
#: before the far face's spread took its compensated closure's share (transmission_exit_fraction):
#: slab sun 7.9 % (1.071), spheres 23.2 % / 37.7 % (1.092 / 0.930); before the curved far face's
#: eight rays (the lobes' mean there too): slab sun 4.7 % (1.027), spheres 23.4 % / 43.7 %
#: (1.093 / 0.976), the sphere light through the sphere 54 % (1.54).
LIGHT_MEASURED = {"plane-point-0.3": (7.0e-4, 2.0e-3, 1.000), "plane-sun-0.6": (2.0e-4, 2.0e-4, 1.000),
                  "slab-point-0.3": (0.163, 3.13, 0.998), "slab-sun-0.6": (0.0277, 0.187, 0.998),
                  "sphere-point-0.3": (0.298, 3.90, 1.080), "sphere-sun-0.6": (0.0520, 0.487, 1.041),
                  # a sphere light of radius 0.2 m, as a point (the engine before): 160 % / 89 % mean
                  "plane-sphere-light-0.3": (0.539, 8.55, 0.838),
                  "sphere-sphere-light-0.6": (0.264, 0.712, 0.805)}
if bpy.app.version < (5, 0, 0):  # measured with bpy 4.5.15: Cycles 4.5's light through one face of
    # rough glass differs from 5.0's by 0.5 % (the sum by 0.5 %), the slab's by 2.6 % in its sum
    LIGHT_MEASURED.update({"plane-point-0.3": (5.0e-3, 3.9e-3, 0.995),
                           "slab-point-0.3": (0.177, 2.65, 0.972)})


@pytest.mark.parametrize("case", LIGHT_CASES)
def test_lights_through_glass_match_cycles(case, tmp_path):
    """A light behind rough glass: its highlight through the one face of a plane (one crossing), or
    through both faces of a slab or a sphere (the far face's and the near face's lobes). The whole
    image is the light's: the sum of the covered pixels is held too (a model that drew nothing, or
    twice the light, fails it)."""
    shape, tilt, roughness, lights, samples = LIGHT_CASES[case]
    scene = _scene(_glass(1.5, roughness=roughness), shape, ground=None, lights=lights, tilt=tilt)
    ours = _render(scene, tmp_path / "ours.exr")
    ref = _cycles(scene, tmp_path / "cycles.exr", samples)
    mean, q, ratio = _error(ours, ref, _covered(shape, tilt))
    print(f"{case}: mean {mean:.2%}, 99th percentile {q:.2%}, sum ours / Cycles {ratio:.3f}")
    assert np.isfinite(ours).all() and (ours >= 0.0).all(), case
    m_mean, m_q, m_ratio = LIGHT_MEASURED[case]
    assert mean <= 3.0 * m_mean, f"{case}: mean {mean:.2%} (measured {m_mean:.2%})"
    assert q <= 3.0 * m_q, f"{case}: 99th percentile {q:.2%} (measured {m_q:.2%})"
    assert abs(math.log(ratio)) <= max(3.0 * abs(math.log(m_ratio)), 0.01), \
        f"{case}: sum ratio {ratio:.3f} (measured {m_ratio:.3f})"


# --- the far face ---------------------------------------------------------------------------------

#: (shape, roughness) -> Cycles' samples; what lies behind emits, no light
FAR_CASES = {("SPHERE", 0.0): 32, ("SPHERE", 0.3): 128, ("SPHERE", 0.6): 128,
             ("SLAB", 0.0): 32, ("SLAB", 0.3): 128, ("SLAB", 0.6): 128}
#: (mean, 99th percentile) measured with bpy 5.0.1; the far face's smooth Fresnel (before its
#: spread) measured 12.0 % / 30.0 % mean on the rough spheres, 7.5 % / 24.7 % on the slabs; averaged
#: over a spread of 0.25 roughness radians (before the compensated closure's share): 7.7 % / 12.5 %,
#: 10.2 % / 20.5 % (the slab's middle 12 % brighter than Cycles', its narrow sides black)
FAR_MEASURED = {("SPHERE", 0.0): (6.35e-2, 0.447), ("SPHERE", 0.3): (6.40e-2, 0.253),
                ("SPHERE", 0.6): (0.104, 0.242), ("SLAB", 0.0): (6.69e-2, 0.512),
                ("SLAB", 0.3): (9.27e-2, 0.293), ("SLAB", 0.6): (9.26e-2, 0.280)}


@pytest.fixture(scope="module")
def emitting_ground(tmp_path_factory):
    """Cycles' emitting ground alone: what the glass changes."""
    path = tmp_path_factory.mktemp("emitting") / "ground.exr"
    return _cycles(_scene(_glass(1.5), None, ground="EMITTING", lights=()), path, 1)


@pytest.mark.parametrize("shape, roughness", FAR_CASES)
def test_far_face_matches_cycles(shape, roughness, emitting_ground, tmp_path):
    """What lies behind seen through both faces, the refraction alone (an emitting ground, no
    light): rough glass's far face passes less than its smooth Fresnel where the first face's
    lobe turns rays towards its critical angle (transmission_exit_fraction)."""
    scene = _scene(_glass(1.5, roughness=roughness), shape, ground="EMITTING", lights=())
    ours = _render(scene, tmp_path / "ours.exr")
    ref = _cycles(scene, tmp_path / "cycles.exr", FAR_CASES[shape, roughness])
    covered = _covered(shape)
    mean, q, ratio = _error(ours, ref, covered)
    effect = float((np.abs(ref - emitting_ground).max(-1)[covered]).mean() / ref.max(-1)[covered].mean())
    print(f"{shape} {roughness}: mean {mean:.2%}, 99th percentile {q:.2%}, sum ratio {ratio:.3f}; "
          f"the glass changes Cycles' image by {effect:.2%}")
    m_mean, m_q = FAR_MEASURED[shape, roughness]
    assert mean <= 3.0 * m_mean, f"mean {mean:.2%} (measured {m_mean:.2%})"
    assert q <= 3.0 * m_q, f"99th percentile {q:.2%} (measured {m_q:.2%})"
    assert effect >= 3.0 * mean, f"the glass changes {effect:.2%}, our error {mean:.2%}"


#: roughness -> (mean, sum ratio) measured with bpy 5.0.1: a sun in front of a rough sphere, casting no
#: shadow, lights its far face from inside (reflected there, seen through the near face); nothing
#: behind. Before (nothing drawn there): 78 % / 65 % mean, sums 0.22 / 0.35; without the far face's
#: compensation (glass_compensation) 20.9 % / 23.0 %, sums 0.967 / 0.801.
INSIDE_MEASURED = {0.3: (0.209, 0.976), 0.6: (0.194, 0.898)}


@pytest.mark.parametrize("roughness", INSIDE_MEASURED)
def test_far_face_lit_from_inside_matches_cycles(roughness, tmp_path):
    scene = _scene(_glass(1.5, roughness=roughness), "SPHERE", ground=None)
    ours = _render(scene, tmp_path / "ours.exr")
    ref = _cycles(scene, tmp_path / "cycles.exr", 256)
    mean, q, ratio = _error(ours, ref, _covered("SPHERE"))
    print(f"lit from inside, roughness {roughness}: mean {mean:.2%}, 99th percentile {q:.2%}, sum ratio "
          f"{ratio:.3f}")
    m_mean, m_ratio = INSIDE_MEASURED[roughness]
    assert mean <= 3.0 * m_mean, f"mean {mean:.2%} (measured {m_mean:.2%})"
    assert abs(math.log(ratio)) <= 3.0 * abs(math.log(m_ratio)), \
        f"sum ratio {ratio:.3f} (measured {m_ratio:.3f})"


# --- perspective cameras and the viewport --------------------------------------------------------

CAMERA = (0.0, -2.6, 2.0)
TARGET = (0.05, 0.05, -0.3)
LENS = 40.0


def _perspective(scene):
    data = bpy.data.cameras.new("Perspective")
    data.lens = LENS
    data.clip_start, data.clip_end = 0.05, 100.0
    camera = bpy.data.objects.new("Perspective", data)
    camera.location = CAMERA
    camera.rotation_euler = (mathutils.Vector(TARGET) - mathutils.Vector(CAMERA)).to_track_quat("-Z", "Y") \
        .to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera
    return scene


def _sphere_pixels(scene) -> np.ndarray:
    """The pixels (top row first) whose centre's ray from the perspective camera meets the sphere, a
    pixel's angle inside its outline."""
    camera = scene.camera
    bpy.context.view_layer.update()
    corners = [camera.matrix_world @ c for c in camera.data.view_frame(scene=scene)]  # tr, br, bl, tl
    origin = np.array(camera.matrix_world.translation)
    tr, br, bl, tl = (np.array(c) for c in corners)
    u = (np.arange(SIZE) + 0.5) / SIZE
    x, y = np.meshgrid(u, u)  # y down the image from the top row
    points = tl + x[..., None] * (tr - tl) + y[..., None] * (bl - tl)
    d = points - origin
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    to_centre = np.array(CENTRE) - origin
    along = d @ to_centre
    miss = np.sqrt(np.maximum(to_centre @ to_centre - along ** 2, 0.0))
    pixel_angle = np.linalg.norm(tr - tl) / SIZE / np.linalg.norm(0.5 * (tl + br) - origin)
    return miss < RADIUS - pixel_angle * np.linalg.norm(to_centre)


#: roughness -> (mean, 99th percentile) measured with bpy 5.0.1
PERSPECTIVE_MEASURED = {0.0: (0.195, 1.230), 0.3: (0.199, 0.915)}  # 0.3: 21.8 % / 92 % before the far
# face's spread took its compensated closure's share


@pytest.fixture(scope="module")
def perspective_ground(tmp_path_factory):
    path = tmp_path_factory.mktemp("perspective") / "ground.exr"
    return _cycles(_perspective(_scene(_glass(1.5), None)), path, 4)


@pytest.mark.parametrize("roughness", PERSPECTIVE_MEASURED)
def test_perspective_camera_matches_cycles(roughness, perspective_ground, tmp_path):
    """The glass sphere over the lit checker, seen obliquely by a perspective camera (the refracted
    rays marched perspective-correctly, the far face found in a perspective depth map)."""
    scene = _perspective(_scene(_glass(1.5, roughness=roughness), "SPHERE"))
    ours = _render(scene, tmp_path / "ours.exr")
    ref = _cycles(scene, tmp_path / "cycles.exr", 64)
    covered = _sphere_pixels(scene)
    mean, q, _ratio = _error(ours, ref, covered)
    effect = float((np.abs(ref - perspective_ground).max(-1)[covered]).mean() / ref.max(-1)[covered].mean())
    print(f"perspective, roughness {roughness}: mean {mean:.2%}, 99th percentile {q:.2%}; the glass "
          f"changes Cycles' image by {effect:.2%} ({int(covered.sum())} pixels)")
    assert covered.sum() > 150, covered.sum()
    m_mean, m_q = PERSPECTIVE_MEASURED[roughness]
    assert mean <= 3.0 * m_mean, f"mean {mean:.2%} (measured {m_mean:.2%})"
    assert q <= 3.0 * m_q, f"99th percentile {q:.2%} (measured {m_q:.2%})"
    assert effect >= 3.0 * mean, f"the glass changes {effect:.2%}, our error {mean:.2%}"


@pytest.mark.parametrize("perspective", [False, True])
def test_viewport_draws_glass_as_the_final_render(perspective, tmp_path):
    """The viewport's session draws the refraction pass too: rough glass (its blurred levels, the far
    face) the same as the final render, to the viewport target's half floats."""
    scene = _scene(_glass(1.5, roughness=0.3), "SPHERE")
    if perspective:
        _perspective(scene)
    final = _render(scene, tmp_path / "final.exr")
    shown = viewport_image(scene, SIZE)[::-1, :, :3].astype(np.float64)
    assert np.isfinite(shown).all()
    diff = float(np.abs(shown - final).max())
    print(f"viewport against the final render: largest difference {diff:.2e} (up to {final.max():.2f})")
    np.testing.assert_allclose(shown, final, rtol=2e-3, atol=2e-3)


# --- partly transparent glass ---------------------------------------------------------------------

#: Alpha -> (mean, 99th percentile) measured with bpy 5.0.1 (peeled as a dielectric, before: 53 % /
#: 72 % mean). Cycles mixes a Transparent BSDF at each face: a closed object shows what is behind
#: through one face's refraction alone for 2 Alpha (1 - Alpha) of it; ours takes that half refracted
#: through both faces, half straight through.
ALPHA_MEASURED = {0.5: (0.235, 0.529), 0.8: (0.204, 0.494)}  # (its Roughness 0.5; 25.1 % / 23.2 % mean
# before the far face's spread took its compensated closure's share)


@pytest.fixture(scope="module")
def lit_ground(tmp_path_factory):
    path = tmp_path_factory.mktemp("lit") / "ground.exr"
    return _cycles(_scene(_glass(1.5), None), path, 4)


@pytest.mark.parametrize("alpha", ALPHA_MEASURED)
def test_partly_transparent_glass_matches_cycles(alpha, lit_ground, tmp_path):
    """A glass sphere of Alpha under 1: refracted where it is glass, what is behind it straight
    through where it is not (Cycles' Principled BSDF mixes a Transparent BSDF by 1 - Alpha)."""
    def make():
        return _principled("Partly", **{"Transmission Weight": 1.0, "IOR": 1.5, "Alpha": alpha})

    scene = _scene(make, "SPHERE")
    ours = _render(scene, tmp_path / "ours.exr")
    ref = _cycles(scene, tmp_path / "cycles.exr", 64, transparent_max_bounces=8)
    covered = _covered("SPHERE")
    mean, q, _ratio = _error(ours, ref, covered)
    effect = float((np.abs(ref - lit_ground).max(-1)[covered]).mean() / ref.max(-1)[covered].mean())
    print(f"Alpha {alpha}: mean {mean:.2%}, 99th percentile {q:.2%}; the glass changes Cycles' image by "
          f"{effect:.2%}")
    m_mean, m_q = ALPHA_MEASURED[alpha]
    assert mean <= 3.0 * m_mean, f"mean {mean:.2%} (measured {m_mean:.2%})"
    assert q <= 3.0 * m_q, f"99th percentile {q:.2%} (measured {m_q:.2%})"
    assert effect >= 2.0 * mean, f"the glass changes {effect:.2%}, our error {mean:.2%}"


# --- what the refraction pass makes ---------------------------------------------------------------

@pytest.mark.parametrize("roughness, levels", [(0.0, 1), (0.3, programs.REFRACTION_LEVELS)])
def test_blurred_levels_only_for_rough_glass(roughness, levels):
    """Smooth glass reads the copy of what is behind unblurred: a frame of smooth glass makes no
    blurred levels (nor the texture they are packed in); rough glass makes them all."""
    from addon.blender import extract
    from addon.frame import passes, renderer

    _scene(_glass(1.5, roughness=roughness))

    def render(depsgraph):
        r = renderer.Renderer()
        try:
            r.render(extract.snapshot(depsgraph, SIZE, SIZE))
            step = next(s for s in r._passes.values() if isinstance(s, passes.RefractionPass))
            return len(step.levels), step.atlas is not None
        finally:
            r.free()

    made, packed = run_on_gpu(render)
    assert made == levels and packed == (levels > 1), (made, packed)


# --- the twin -------------------------------------------------------------------------------------

def _unit(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_twin_far_face_is_smooth_at_roughness_zero_and_through_parallel_faces_peaks_straight():
    """The far face's fraction is the smooth Fresnel's from inside at roughness 0 (at any spread of
    incidence angles it is averaged over: there, its mean); rough glass passes some beyond the
    critical angle, where smooth glass passes none; a light seen through two parallel faces (a slab)
    of smooth glass is brightest straight through, along the view, at every view."""
    cos = np.linspace(0.0, 1.0, 201)
    eta = np.full_like(cos, 1.5)
    np.testing.assert_allclose(T.transmission_exit_fraction(cos, eta, 0.0, 0.0),
                               T.transmission_fraction(cos, 1.0 / eta), rtol=0.0, atol=1e-12)
    critical = math.cos(math.asin(1.0 / 1.5))
    beyond = T.transmission_exit_fraction(critical - 0.05, 1.5, 0.5, 0.0)
    assert T.transmission_fraction(critical - 0.05, 1.0 / 1.5) == 0.0 and beyond > 0.05, beyond
    n = np.array([0.0, 0.0, 1.0])
    for view_deg in (0.0, 25.0, 50.0, 70.0):
        for alpha in (0.001, 0.01):  # (wider lobes tilt towards the normal by their masking)
            v = np.array([math.sin(math.radians(view_deg)), 0.0, math.cos(math.radians(view_deg))])
            inner = T.transmission_direction(-v[None], n[None], np.array([1.5]))[0]
            angles = np.radians(np.linspace(-20.0, 20.0, 4001))
            straight = math.atan2(-v[0], -v[2])
            ls = np.stack([np.sin(straight + angles), 0.0 * angles, np.cos(straight + angles)], axis=1)
            rows = [np.tile(x, (len(ls), 1)) for x in (n, v, inner, n)]
            light = T.transmission_exit_light(*rows, ls, np.full(len(ls), 1.5), alpha, math.sqrt(alpha),
                                              programs.REFRACTION_EXIT_ALPHA, programs.REFRACTION_EXIT_SPREAD)
            peak = math.degrees(angles[np.argmax(light)])
            assert abs(peak) <= 0.15, (view_deg, alpha, peak)  # measured 0.12 at 70 degrees, alpha 0.01


def _normals_and_views(rng, count):
    """``count`` random unit normals and views on their side (n.v >= 0.05 or flipped there)."""
    n = _unit(rng, count)
    v = _unit(rng, count)
    return n, np.where((np.einsum("ij,ij->i", v, n) < 0.05)[:, None], -v, v)


def test_gpu_far_face_matches_the_twin():
    """glsl/transmission.glsl's transmission_exit_fraction and transmission_exit_light against the
    twin at random views, far faces, lights, IORs and roughnesses: float32 agreement."""
    rng = np.random.default_rng(5)
    count = 2048
    n, v = _normals_and_views(rng, count)
    eta = rng.uniform(1.1, 2.0, count)
    inner = T.transmission_direction(-v, n, eta)
    exit_n = _unit(rng, count)
    exit_n = np.where((np.einsum("ij,ij->i", exit_n, inner) > 0.0)[:, None], -exit_n, exit_n)
    l = _unit(rng, count)
    roughness = rng.uniform(0.1, 1.0, count)
    alpha = roughness ** 2
    zero = np.zeros(count)
    inputs = {"vn": np.c_[n, eta], "vv": np.c_[v, alpha], "vi": np.c_[inner, roughness],
              "ve": np.c_[exit_n, zero], "vl": np.c_[l, zero]}
    factor, spread = programs.REFRACTION_EXIT_ALPHA, programs.REFRACTION_EXIT_SPREAD
    body = ("Surface s; s.n = vn.xyz; s.v = vv.xyz; s.NoV = dot(vn.xyz, vv.xyz); s.alpha = vv.w;\n"
            "s.roughness = vi.w;\n"
            "s.transmission.eta = vn.w; s.transmission.weight = 1.0; s.transmission.fresnel = true;\n"
            "s.transmission.tint = vec3(1.0); s.transmission.reflection_tint = vec3(1.0);\n"
            "s.transmission.inside = vec3(1.0); s.transmission.inner = vi.xyz;\n"
            "s.transmission.exit_n = ve.xyz;\n"
            "LightData light; light.position_kind = vec4(0.0); light.shape = vec4(0.0);\n"
            "s.transmission.exit = true; exit_curved = 0.0;\n"
            f"transmission_prepare_lights(s, {spread!r});\n"
            f"vec3 c = transmission_exit_light(s, light, vl.xyz, vec3(1.0), vec4(1.0), {factor!r});\n"
            "float cos2 = -dot(vi.xyz, ve.xyz);\n"
            "result = vec4(c.x, transmission_exit_fraction(cos2, vn.w, vi.w, 0.3 * vi.w, true), 0.0, 0.0);")
    gpu = evaluate(body, inputs, GPU_DEFINES, terms=GPU_TERMS)
    light = T.transmission_exit_light(n, v, inner, exit_n, l, eta, alpha, roughness, factor, spread)
    fraction = T.transmission_exit_fraction(-np.einsum("ij,ij->i", inner, exit_n), eta, roughness,
                                            0.3 * roughness)
    err = np.abs(gpu[:, 0] - light) / np.maximum(np.abs(light), 1.0)
    print(f"far face's light: largest relative error {err.max():.3g} ({int((light > 0).sum())} lit)")
    assert (light > 0.0).sum() > count // 4
    assert err.max() <= 5e-6, err.max()
    diff = np.abs(gpu[:, 1] - fraction)
    print(f"far face's fraction: largest difference {diff.max():.3g}")
    assert diff.max() <= 5e-5, diff.max()


def _glass_crossing(rng, wi, alpha, eta):
    """One crossing of Cycles' compensated GGX glass closure (normal +z, wi above it), sampled as
    bsdf_microfacet_ggx_sample samples it -- a visible normal, reflection by the Fresnel's
    probability -- times microfacet_ggx_preserve_energy's scale: (direction, weight, transmitted)."""
    count = len(wi)
    m = T._vndf(alpha, wi, rng.random(count), rng.random(count))
    c = np.einsum("ij,ij->i", wi, m)
    F = brdf.F_Dielectric(eta, np.maximum(c, 0.0))
    through = rng.random(count) >= F
    k = np.maximum(1.0 - (1.0 - c * c) / eta ** 2, 0.0)
    refracted = -wi / eta + (c / eta - np.sqrt(k))[:, None] * m
    out = np.where(through[:, None], refracted, 2.0 * c[:, None] * m - wi)
    lam_i, lam_o = T._lambda_ggx(wi[:, 2], alpha), T._lambda_ggx(out[:, 2], alpha)
    valid = np.where(through, out[:, 2] < 0.0, out[:, 2] > 0.0)
    weight = np.where(valid, (1.0 + lam_i) / (1.0 + lam_i + lam_o), 0.0)
    return out, weight * T.glass_compensation(math.sqrt(alpha), wi[:, 2], eta), through


#: The mean |difference| measured over the cases (largest 0.026, at 50 degrees, roughness 0.6; the
#: smooth Fresnel averaged over 0.25 roughness radians, the engine before: 0.041, largest 0.10)
SLAB_FAR_FRACTION_MEASURED = 0.0103


def test_far_face_fraction_matches_a_monte_carlo_of_cycles_two_crossings():
    """What passes through a rough slab along the view (the first crossing's 1 - F times
    transmission_exit_fraction at the central refracted ray, its spread from
    transmission_inner_spread) against a Monte-Carlo integration of Cycles' two compensated rough
    crossings (the second from inside; a reflection inside ends the path, as Cycles' transmission
    tests' glossy bounces do): IOR 1.5, roughness 0.3 and 0.6, views 0, 30 and 50 degrees."""
    rng = np.random.default_rng(23)
    eta, count = 1.5, 200_000
    diffs = []
    for roughness in (0.3, 0.6):
        alpha = roughness * roughness
        for view_deg in (0.0, 30.0, 50.0):
            v = np.array([math.sin(math.radians(view_deg)), 0.0, math.cos(math.radians(view_deg))])
            inner, w1, t1 = _glass_crossing(rng, np.tile(v, (count, 1)), alpha, eta)
            ok = t1 & (w1 > 0.0)
            # the far face seen from inside: the frame turned over (its normal +z facing the inside)
            wi2 = np.where(ok[:, None], np.c_[-inner[:, :2], -inner[:, 2]], [0.0, 0.0, 1.0])
            _out, w2, t2 = _glass_crossing(rng, wi2, alpha, 1.0 / eta)
            mc = float(np.where(ok & t2, w1 * w2, 0.0).mean())
            cos_t = -T.transmission_direction(-v[None], np.array([[0.0, 0.0, 1.0]]), np.array([eta]))[0, 2]
            spread = T.transmission_inner_spread(v[2], cos_t, eta, alpha, programs.REFRACTION_EXIT_SPREAD)
            exit_fraction = T.transmission_exit_fraction(cos_t, eta, roughness, spread)
            ours = float(T.transmission_fraction(v[2], eta) * exit_fraction)
            diffs.append(abs(ours - mc))
            print(f"roughness {roughness}, view {view_deg:.0f} degrees: Monte Carlo {mc:.4f}, "
                  f"ours {ours:.4f}")
    mean = float(np.mean(diffs))
    print(f"mean |difference| {mean:.4f} (largest {max(diffs):.4f})")
    assert mean <= 3.0 * SLAB_FAR_FRACTION_MEASURED, mean


def test_gpu_exit_rays_and_quadrature_match_the_twin():
    """glsl/transmission.glsl's first-crossing rays (transmission_exit_ray: visible normals of a fixed
    grid, each ray's direction and weight) and the far face's quadrature towards a point light and a
    sun (transmission_exit_quadrature) against the twin, at random views, IORs, roughnesses and far
    normals turned with each ray; and the rays' weights average to the first crossing's transmitted
    albedo (the glass tables' T at the view, to the grid's quadrature error)."""
    rng = np.random.default_rng(29)
    count = 1024
    n, v = _normals_and_views(rng, count)
    eta = rng.uniform(1.2, 1.8, count)
    roughness = rng.uniform(0.1, 0.9, count)
    alpha = roughness ** 2
    exit_n = n + 0.3 * _unit(rng, count)  # facing the inside, against the rays
    exit_n /= np.linalg.norm(exit_n, axis=1, keepdims=True)
    light = rng.normal(size=(count, 3)) - 2.0 * n
    inputs = {"vn": np.c_[n, eta], "vv": np.c_[v, alpha], "ve": np.c_[exit_n, roughness],
              "vl": np.c_[light, np.zeros(count)]}
    body = ("Surface s; s.n = vn.xyz; s.v = vv.xyz; s.NoV = dot(vn.xyz, vv.xyz); s.alpha = vv.w;\n"
            "s.roughness = ve.w; s.transmission.eta = vn.w; s.transmission.fresnel = true;\n"
            "s.transmission.exit_p = vec3(0.0); exit_curved = 1.0;\n"
            "float total = 0.0;\n"
            "for (int k = 0; k < EXIT_RAYS; k++) {\n"
            "  vec3 d; float w = transmission_exit_ray(s, vn.w, k, d);\n"
            "  exit_ray_dir[k] = d; exit_ray_point[k] = d;\n"
            "  exit_ray_normal[k] = normalize(ve.xyz - 0.5 * d);\n"
            "  exit_ray_weight[k] = w; total += w;\n"
            "}\n"
            "LightData light; light.position_kind = vec4(vl.xyz, float(LIGHT_POINT));\n"
            "float at_point = transmission_exit_quadrature(s, light, vec3(0.0), vv.w);\n"
            "light.position_kind.w = float(LIGHT_SUN);\n"
            "float from_sun = transmission_exit_quadrature(s, light, normalize(vl.xyz), vv.w);\n"
            "result = vec4(at_point, from_sun, total / float(EXIT_RAYS), exit_ray_dir[3].x);")
    gpu = evaluate(body, inputs, GPU_DEFINES, terms=GPU_TERMS)
    rays = [T.transmission_exit_ray(n, v, eta, alpha, k) for k in range(T.EXIT_RAYS)]
    dirs = np.stack([d for d, _w in rays])
    weights = np.stack([w for _d, w in rays])
    normals = exit_n[None] - 0.5 * dirs
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    zero = np.zeros((count, 3))
    at_point = T.transmission_exit_quadrature(dirs, dirs, normals, weights, zero, None, eta, alpha, light)
    sun = light / np.linalg.norm(light, axis=1, keepdims=True)
    from_sun = T.transmission_exit_quadrature(dirs, dirs, normals, weights, zero, sun, eta, alpha)
    for name, got, want in (("point light", gpu[:, 0], at_point), ("sun", gpu[:, 1], from_sun),
                            ("mean weight", gpu[:, 2], weights.mean(0)),
                            ("a ray", gpu[:, 3], dirs[3, :, 0])):
        err = float((np.abs(got - want) / np.maximum(np.abs(want), 1.0)).max())
        print(f"{name}: largest relative difference {err:.2e}")
        assert err <= 2e-4, (name, err)
    lit = min(int((at_point > 0.0).sum()), int((from_sun > 0.0).sum()))
    print(f"lit: {lit} of {count}")
    assert lit > count // 4, lit
    cos_v = np.einsum("ij,ij->i", n, v)
    transmitted = T._glass_lookup("T", roughness, cos_v, eta)
    gap = float(np.abs(weights.mean(0) - transmitted).mean())
    print(f"the rays' mean weight against the glass tables' T: mean difference {gap:.4f}")
    assert gap <= 0.036, gap  # measured 0.012 (eight rays)
