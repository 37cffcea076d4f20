"""The subsurface's random walk (glsl/subsurface.glsl's subsurface_walk_at, twin
addon/reference/subsurface.py): its reflectance over the Lambert base, which Cycles' Random Walk
methods' Anisotropy and entry (IOR, roughness) change, against Cycles' walk.

The table (addon/reference/subsurface_walk.npz, scripts/subsurface_walk_table.py) is held to the twin's
walk recomputed, the entry's quadrature to sampling, the twin to Cycles on a slab (a plane: a half-space
for the walk) and the GPU to the twin; then the engine against Cycles' walk on tests/test_subsurface.py's
sphere (its brightness bins: the walk is noisy per pixel) across Anisotropy and IOR, each input read
no worse than the defaults and ignoring it measurably worse.
"""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes
from glsl_harness import evaluate
from test_cycles import _cycles
from test_material_render import _scene, _tree
from test_subsurface import _bins, _subsurface_material

from addon.plan import programs
from addon.reference import subsurface as SS
from addon.scene import snapshot as S

# --- the twin: the table, the entry's quadrature ---------------------------------------------------


#: (albedo node, g node) cells recomputed, and the walks per entry node
RECOMPUTED = ((8, 0), (12, 18), (16, 10))
RECOMPUTE_PATHS = 6000


def test_table_reproduces_the_walk():
    """Sample cells of the shipped tables (R / albedo, the drift's moment per unit sine, the convex gain
    per unit rho) against the twin's walk recomputed with other random numbers: within 4.5 standard
    errors of their difference (both Monte Carlo: the table's paths, these); the drift forward and the
    gain positive (a convex surface lets more walks out) at every node of the tables."""
    table, drifts, gains = SS.walk_table(), SS.walk_drift_table(), SS.walk_gain_table()
    with np.load(SS.WALK_SHIPPED) as data:
        paths, moment_paths = int(data["paths"]), int(data["moment_paths"])
    mus = np.maximum(SS.walk_mus(), 1e-6)
    worst = 0.0
    for i, j in RECOMPUTED:
        albedo, g = max(SS.walk_albedos()[i], 1e-4), SS.walk_gs()[j]
        entries = np.append(mus[:-1], SS.WALK_DRIFT_LAST_MU)
        means, errors = SS.walk_moments(albedo, g, entries, RECOMPUTE_PATHS, seed=7 + i + j)
        again, error = SS.walk_reflectance(albedo, g, mus, RECOMPUTE_PATHS, seed=7 + i + j, spread=True)
        sigma = error * math.sqrt(1.0 + RECOMPUTE_PATHS / paths)
        off = np.abs(again - table[i, j, :SS.WALK_MU_NODES]) / sigma
        widen = math.sqrt(1.0 + RECOMPUTE_PATHS / moment_paths)
        off_drift = np.abs(means[1] - drifts[i, j]) / (errors[1] * widen)
        # the gain at the cosine nodes the table walks (2-5: 0 and 1 take 2's, 6 is walked at 1)
        off_gain = (np.abs(means[2, 2:-1] - gains[i, j, 2:SS.WALK_MU_NODES - 1])
                    / (errors[2, 2:-1] * widen))
        worst = max(worst, float(off.max()), float(off_drift.max()), float(off_gain.max()))
        print(f"albedo {albedo:.3f}, g {g:.2f}: table {np.round(table[i, j], 3)}, "
              f"again {np.round(again, 3)}, "
              f"{off.max():.2f} standard errors apart; drift {np.round(drifts[i, j], 3)}, "
              f"{off_drift.max():.2f} apart; gain {np.round(gains[i, j], 2)}, {off_gain.max():.2f} apart")
        assert np.all(drifts[i, j] > 0.0) and np.all(gains[i, j] > 0.0), (drifts[i, j], gains[i, j])
    assert worst < 4.5, worst
    assert paths >= 20000 and moment_paths >= 5000, (paths, moment_paths)
    assert np.all(drifts > 0.0) and np.all(gains > 0.0)


def _sampled_factor(cos_v, eta, alpha, albedo, g, count=100_000, seed=3):
    """The walk's factor with the entry's directions sampled independently of the quadrature: GGX
    microfacet normals drawn by D(h) (n.h) (Walter et al. 2007) and weighted to the view's visible
    normals, G1(v) max(0, v.h) / ((n.v) (n.h)) (Heitz 2014), each ray refracted by 1 / eta and looked
    up in the table at its cosine (linear in sqrt(mu) between the nodes, as the engine spreads it)."""
    rng = np.random.default_rng(seed)
    u = rng.random((2, count))
    tan2 = alpha * alpha * u[0] / np.maximum(1.0 - u[0], 1e-300)
    cos_h = 1.0 / np.sqrt(1.0 + tan2)
    sin_h = np.sqrt(np.maximum(1.0 - cos_h * cos_h, 0.0))
    phi = 2.0 * math.pi * u[1]
    h = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], -1)
    v = np.array([math.sqrt(1.0 - cos_v * cos_v), 0.0, cos_v])
    cos_hv = h @ v
    tan2_v = (1.0 - cos_v * cos_v) / (cos_v * cos_v)
    g1 = 2.0 / (1.0 + math.sqrt(1.0 + alpha * alpha * tan2_v))
    weight = g1 * np.maximum(cos_hv, 0.0) / (cos_v * cos_h)
    root = np.sqrt(np.maximum(1.0 - (1.0 - cos_hv ** 2) / eta ** 2, 0.0))
    wo_z = -v[2] / eta + (cos_hv / eta - np.maximum(root, 1e-7)) * h[:, 2]
    ok = (cos_hv > 0.0) & (wo_z < 0.0)
    mu = np.where(ok, -wo_z, 0.0)
    x = np.sqrt(mu) * (SS.WALK_MU_NODES - 1.0)
    i = np.minimum(np.floor(x), SS.WALK_MU_NODES - 2.0).astype(int)
    f = x - i
    rows = SS.walk_lookup(np.full(3, albedo), g)[0]  # one channel
    values = (1.0 - f) * rows[i] + f * rows[i + 1]
    return float(np.sum(np.where(ok, values, 0.0) * weight) / count)


#: the quadrature against sampling: the largest relative difference of the factors, measured with the
#: shipped table (the sampling's noise ~0.2 % included)
ENTRY_MEASURED = 5.68e-3


def test_entry_quadrature_against_sampling():
    """The factor from the entry's 8-point quadrature (entry_weights) against the same with the entry's
    directions sampled (100,000 microfacet normals; its noise ~0.2 %): rough and smooth interfaces,
    IORs 1.01 to 3, views from grazing to normal."""
    worst = 0.0
    for alpha in (0.0, 0.25, 1.0):
        for eta in (1.01, 1.4, 3.0):
            for cos_v in (0.1, 0.5, 1.0):
                for albedo, g in ((0.3, 0.0), (0.8, 0.9)):
                    walk = np.array([g, eta, alpha, 0.0])
                    quad = float(SS.walk_factor(cos_v, np.full(3, albedo), walk)[0])
                    sampled = _sampled_factor(cos_v, eta, max(alpha, 1e-6), albedo, g)
                    worst = max(worst, abs(quad - sampled) / sampled)
    print(f"the entry's quadrature against sampling: {worst:.3%} worst")
    assert worst <= 3.0 * ENTRY_MEASURED, worst


def _slab(cos_v, method, inputs, size=16):
    """A 4 m plane tilted from the orthographic camera's axis by acos(cos_v), its surface a Subsurface
    Scattering node of colour SLAB_COLOR, Radius (1, 1, 1) (the twin walks one channel: Cycles' channel
    sampling with radii far apart loses ~1 % more of the widest), Scale 0.01 (a half-space to the
    walk), under a sun along the camera's axis of irradiance 1."""
    scene = scenes.reset(size=size)
    scenes.ortho_camera(scene, location=(0.0, 0.0, 3.0), scale=0.5)
    mat, tree, out = _tree("Slab")
    node = tree.nodes.new("ShaderNodeSubsurfaceScattering")
    node.falloff = method
    node.inputs["Color"].default_value = (*SLAB_COLOR, 1.0)
    node.inputs["Scale"].default_value = 0.01
    node.inputs["Radius"].default_value = (1.0, 1.0, 1.0)
    for socket, value in inputs.items():  # by identifier: unavailable sockets too
        next(s for s in node.inputs if s.identifier == socket).default_value = value
    tree.links.new(node.outputs["BSSRDF"], out.inputs["Surface"])
    scenes.plane(scene, size=4.0, rotation=(math.acos(cos_v), 0.0, 0.0), material=mat)
    scenes.light(scene, "SUN", energy=1.0)
    scene.cycles.light_sampling_threshold = 0.0
    return scene


SLAB_COLOR = (0.8, 0.5, 0.4)
#: name -> (the view's cosine, method, the node's inputs)
SLAB_CASES = {
    "normal-g0": (1.0, "RANDOM_WALK", {"IOR": 1.4, "Roughness": 0.0, "Anisotropy": 0.0}),
    "grazing-ior-1.01": (0.15, "RANDOM_WALK", {"IOR": 1.01, "Roughness": 0.0, "Anisotropy": 0.0}),
    "oblique-g0.9": (0.4, "RANDOM_WALK", {"IOR": 1.01, "Roughness": 0.0, "Anisotropy": 0.9}),
    "rough-ior-2": (0.4, "RANDOM_WALK", {"IOR": 2.0, "Roughness": 0.5, "Anisotropy": 0.5}),
    "skin": (0.15, "RANDOM_WALK_SKIN", {"IOR": 1.4, "Anisotropy": 0.0}),
}
#: Cycles' samples per pixel on the slab (256 pixels): its noise ~0.3 % (Blender 4.5's sampler: at 64,
#: 1 % for Skin)
SLAB_SAMPLES = 256
#: the largest relative difference of the channels' R / albedo, twin against Cycles at SLAB_SAMPLES,
#: measured with bpy 5.0.1
SLAB_MEASURED = {"normal-g0": 3.6e-3, "grazing-ior-1.01": 2.6e-3, "oblique-g0.9": 5.2e-3,
                 "rough-ior-2": 8.6e-3, "skin": 2.9e-3}
if bpy.app.version < (5, 0, 0):  # Blender 4.2's and 4.5's Cycles: Skin's slab 0.93 % off (their sampler's
    SLAB_MEASURED["skin"] = 9.3e-3  # noise at 256 samples, ~0.6 % from 5.0's image)


@pytest.fixture(scope="module")
def slabs(tmp_path_factory):
    """Per SLAB_CASES' case: Cycles' R / albedo per channel (the pixels' mean over the Lambert base's
    colour x cos / pi)."""
    tmp = tmp_path_factory.mktemp("slabs")
    out = {}
    for case, (cos_v, method, inputs) in SLAB_CASES.items():
        image = _cycles(_slab(cos_v, method, inputs), tmp / f"{case}.exr", samples=SLAB_SAMPLES)[..., :3]
        out[case] = image.reshape(-1, 3).astype(np.float64).mean(0) / (np.array(SLAB_COLOR) * cos_v / math.pi)
    return out


@pytest.mark.parametrize("case", SLAB_CASES)
def test_twin_matches_cycles_on_a_slab(case, slabs):
    """The twin's factor (walk_factor: the table and the entry) against Cycles' walk on a slab, per
    channel: within 3x what was measured; the Lambert base (1) farther off where the view grazes."""
    cos_v, method, inputs = SLAB_CASES[case]
    if method == "RANDOM_WALK_SKIN":
        row = SS.walk_row(method, 1.5, 0.5, inputs["IOR"], inputs["Anisotropy"])
    else:
        row = SS.walk_row(method, inputs["IOR"], 0.5, 1.4, inputs["Anisotropy"])
    if method == "RANDOM_WALK":  # the node's Roughness is the entry's alpha itself
        row[2] = inputs["Roughness"]
    twin = SS.walk_factor(cos_v, np.array(SLAB_COLOR), row)
    cycles = slabs[case]
    error = float(np.abs(twin / cycles - 1.0).max())
    print(f"{case}: Cycles {np.round(cycles, 4)}, twin {np.round(twin, 4)}: {error:.2%}; "
          f"Lambert {np.abs(1.0 / cycles - 1.0).max():.2%}")
    assert error <= 3.0 * SLAB_MEASURED[case], error


def test_gpu_matches_twin():
    """subsurface_walk_at on the GPU against the twin's walk_factor over random rows and their extremes
    (views at and below the horizon, alpha 0 and 1, IORs 0 (no walk), 1 and 100, albedos and g beyond
    their ranges, the Principled BSDF's alpha from its roughness): finite, at least 0, float32 agreement."""
    rng = np.random.default_rng(11)
    n = 512
    cos_v = np.concatenate([rng.uniform(0.0, 1.0, n - 8), [-0.5, 0.0, 1e-7, 1.0, 1.0, 0.3, 0.05, 0.7]])
    albedo = rng.uniform(0.0, 1.0, (n, 3))
    albedo[-8:] = [[0.0, 1.0, 0.5], [2.0, -1.0, 0.3], [1e-4, 0.004, 0.99], [0.8, 0.5, 0.4], [0.0, 0.0, 0.0],
                   [1.0, 1.0, 1.0], [0.3, 0.6, 0.9], [0.25, 0.5, 0.75]]
    walk = np.column_stack([rng.uniform(0.0, 0.9, n), rng.uniform(1.01, 3.8, n), rng.uniform(0.0, 1.0, n),
                            rng.choice([0.0, 0.5], n)])
    walk[-8:] = [[0.5, 1.4, 0.3, 0.0], [-1.0, 1.4, 1.0, 0.5], [2.0, 100.0, 0.0, 0.0], [0.9, 1.0, 1.0, 1.0],
                 [0.3, 0.0, 0.5, 0.0], [0.0, 3.8, -1.0, 0.0], [0.9, 1.01, 0.0, 0.0], [0.45, 2.0, -1.0, 0.0]]
    roughness = np.concatenate([rng.uniform(0.0, 1.0, n - 8), [0.5, 0.5, 0.5, 0.5, 0.5, -1.0, 0.0, 2.0]])
    inputs = {"a": np.column_stack([albedo, cos_v]), "b": walk,
              "c": np.column_stack([roughness, np.zeros((n, 3))])}
    features = programs.Features("PBR", 1, frozenset({"SUN"}), S.Terms(principled=True),
                                 lobes=frozenset({"SUBSURFACE"}))
    body = ("vec3 v = vec3(sqrt(max(1.0 - a.w * a.w, 0.0)), 0.0, a.w);"
            "result = vec4(subsurface_walk_at(vec3(0.0, 0.0, 1.0), v, a.rgb, b, c.x), 0.0);")
    gpu = evaluate(body, inputs, dict(features.defines()), terms=S.Terms(principled=True))[:, :3]
    twin, twin_drift, twin_gain = SS.walk_factor(cos_v, albedo, walk, roughness, drift=True)
    assert np.isfinite(gpu).all() and (gpu >= 0.0).all()
    error = float((np.abs(gpu - twin) / np.maximum(twin, 1.0)).max())
    print(f"subsurface_walk_at GPU against twin: {error:.2e}")
    assert error < 1e-5, error
    assert np.all(gpu[walk[:, 1] <= 0.0] == 1.0)  # Christensen-Burley: no walk
    # the walk's drift (units of the mean free path; the view in the xz plane: away from it is -x) and
    # its gain on a convex surface per unit rho
    for name, index, expected in (("drift", 0, twin_drift), ("gain", 1, twin_gain)):
        body = ("vec3 v = vec3(sqrt(max(1.0 - a.w * a.w, 0.0)), 0.0, a.w); vec3 part[2];"
                "subsurface_walk_at(vec3(0.0, 0.0, 1.0), v, a.rgb, b, c.x, part[0], part[1]);"
                f"result = vec4(part[{index}], 0.0);")
        gpu = evaluate(body, inputs, dict(features.defines()), terms=S.Terms(principled=True))[:, :3]
        assert np.isfinite(gpu).all()
        error = float(np.abs(gpu - expected).max())
        print(f"the walk's {name} GPU against twin: {error:.2e} (largest {np.abs(expected).max():.3f})")
        assert error < 1e-4 * max(1.0, float(np.abs(expected).max())), (name, error)
        assert np.all(gpu[walk[:, 1] <= 0.0] == 0.0)  # Christensen-Burley: no walk, no drift, no gain


# --- the walk's drift against Cycles: a shadow's edge on a slab --------------------------------------

#: The slab's edge: its pixels across (an orthographic view 0.6 m wide), Radius x Scale (d = 15.9 mm)
EDGE_WIDTH, EDGE_SPAN, EDGE_SCALE, EDGE_ALBEDO = 64, 0.6, 0.2, 0.8


def _edge_scene(theta, ior, roughness, anisotropy=0.0):
    """A 8 m slab (Subsurface Scattering node, Random Walk, grey EDGE_ALBEDO, Radius 1, Scale
    EDGE_SCALE) under a sun straight down, a blocker 0.5 m above shadowing x < 0 (hidden from the camera:
    a sharp edge along y at x = 0), an orthographic camera tilted by ``theta`` about y (from +x: the
    view's direction along the surface, away from the camera, is -x: its walks drift into the shadow)."""
    scene = scenes.reset(size=EDGE_WIDTH)
    scene.render.resolution_y = 4
    scenes.ortho_camera(scene, location=(3.0 * math.sin(theta), 0.0, 3.0 * math.cos(theta)),
                        rotation=(0.0, theta, 0.0), scale=EDGE_SPAN)
    mat, tree, out = _tree("Edge")
    node = tree.nodes.new("ShaderNodeSubsurfaceScattering")
    node.falloff = "RANDOM_WALK"
    node.inputs["Color"].default_value = (EDGE_ALBEDO, EDGE_ALBEDO, EDGE_ALBEDO, 1.0)
    node.inputs["Scale"].default_value = EDGE_SCALE
    node.inputs["Radius"].default_value = (1.0, 1.0, 1.0)
    # by identifier
    for socket, value in (("IOR", ior), ("Roughness", roughness), ("Anisotropy", anisotropy)):
        next(s for s in node.inputs if s.identifier == socket).default_value = value
    tree.links.new(node.outputs["BSSRDF"], out.inputs["Surface"])
    scenes.plane(scene, size=8.0, material=mat)
    blocker = scenes.plane(scene, size=4.0, location=(-2.0, 0.0, 0.5))
    blocker.visible_camera = False
    scenes.light(scene, "SUN", energy=1.0, use_shadow=True)
    scene.cycles.light_sampling_threshold = 0.0
    return scene


#: name -> (the view's angle from the normal (degrees; below 0 from -x: drifting into the light), the
#: entry's IOR and GGX alpha, the Anisotropy)
EDGE_CASES = {"grazing-smooth": (72.5, 1.01, 0.0, 0.0), "grazing-smooth-mirrored": (-72.5, 1.01, 0.0, 0.0),
              "oblique-rough-1.5": (45.0, 1.5, 0.25, 0.0), "steep-rough-1.5": (20.0, 1.5, 0.25, 0.0),
              "grazing-anisotropy-0.5": (72.5, 1.01, 0.0, 0.5)}
#: per case |Cycles' edge shift - the twin's drift| in units of d, measured with bpy 5.0.1 (Cycles at
#: EDGE_SAMPLES: its noise ~0.03 d)
EDGE_MEASURED = {"grazing-smooth": 0.034, "grazing-smooth-mirrored": 0.107, "oblique-rough-1.5": 0.039,
                 "steep-rough-1.5": 0.01, "grazing-anisotropy-0.5": 0.017}  # (steep: 0.000, the noise's 0.01)
if bpy.app.version < (5, 0, 0):  # Blender 4.2's and 4.5's Cycles (their sampler): the grazing edges 0.1 d
    # nearer the entry point, measured with bpy 4.5.15 (4.2.23 alike)
    EDGE_MEASURED = {"grazing-smooth": 0.133, "grazing-smooth-mirrored": 0.098, "oblique-rough-1.5": 0.054,
                     "steep-rough-1.5": 0.015, "grazing-anisotropy-0.5": 0.092}
EDGE_SAMPLES = 256


@pytest.mark.parametrize("case", EDGE_CASES)
def test_drift_against_cycles_at_a_shadow_edge(case, tmp_path):
    """The walk's mean drift away from the viewer (walk_factor's, from the table's drift moments and
    the entry's quadrature) against Cycles' own: a sharp shadow's edge on a slab, blurred by the walk,
    moves by the walks' mean displacement across it -- the integral of (the image over the lit level
    - the unblurred step) across the edge; within 3x what was measured, and the shift at least 5x
    that (in the grazing cases, 0.8-0.9 d). Drift linear in the entry cosine between the table's
    nodes (its moment rather than per unit sine) was 0.15 and 0.12 d off in the rough cases."""
    degrees, ior, alpha, anisotropy = EDGE_CASES[case]
    theta = math.radians(degrees)
    image = _cycles(_edge_scene(theta, ior, alpha, anisotropy), tmp_path / "edge.exr", samples=EDGE_SAMPLES)
    profile = image[..., 0].astype(np.float64).mean(0)
    profile /= profile[-8:].mean()  # the lit level
    cos_v = math.cos(theta)
    x = ((np.arange(EDGE_WIDTH) + 0.5) / EDGE_WIDTH - 0.5) * EDGE_SPAN / cos_v  # the pixels on the slab
    d = EDGE_SCALE / (4.0 * math.pi)
    shift = float(np.sum(profile - (x > 0.0)) * (x[1] - x[0])) / d  # towards the light (+x): > 0
    row = np.array([anisotropy, ior, alpha, 0.0])
    _, drift, _ = SS.walk_factor(cos_v, np.full(3, EDGE_ALBEDO), row, drift=True)
    expected = -math.copysign(float(drift[0]), degrees)
    error = abs(shift - expected)
    print(f"{case}: Cycles' edge moved {shift:+.3f} d, the twin's drift {expected:+.3f} d: "
          f"{error:.3f} d apart")
    assert error <= 3.0 * EDGE_MEASURED[case], (case, shift, expected)
    if abs(degrees) > 60.0:
        assert abs(shift) >= 5.0 * error, (case, shift, error)


# --- the sphere against Cycles' random walk ---------------------------------------------------------

#: name -> (the material's arguments (test_subsurface's _subsurface_material: base colour (0.8, 0.5, 0.4),
#: Radius (1, 0.2, 0.1), a sphere of radius 0.9 under a point light), the same with the input swept at
#: its default: what ignoring it draws; None: an input whose default the engine cannot draw apart (the
#: Principled BSDF's IOR is its specular layer's too) or the defaults themselves)
SPHERE_CASES = {
    "defaults": (dict(scale=0.2), None),
    "anisotropy-0.5": (dict(scale=0.2, **{"Subsurface Anisotropy": 0.5}), dict(scale=0.2)),
    "anisotropy-0.9": (dict(scale=0.2, **{"Subsurface Anisotropy": 0.9}), dict(scale=0.2)),
    # the Subsurface Scattering node, a smooth entry (Roughness 0): its IOR bends the entering ray
    "node-ior-1.01": (dict(node=True, scale=0.1, IOR=1.01, Roughness=0.0),
                      dict(node=True, scale=0.1, Roughness=0.0)),
    "node-ior-2.0": (dict(node=True, scale=0.1, IOR=2.0, Roughness=0.0),
                     dict(node=True, scale=0.1, Roughness=0.0)),
    # its default entry (Roughness 1): the IOR barely matters to Cycles' image
    "node-rough-ior-2.0": (dict(node=True, scale=0.1, IOR=2.0), dict(node=True, scale=0.1)),
    "node-roughness-0": (dict(node=True, scale=0.1, Roughness=0.0), dict(node=True, scale=0.1)),
    "principled-ior-1.01": (dict(scale=0.2, IOR=1.01), None),
    "principled-ior-2.0": (dict(scale=0.2, IOR=2.0), None),
    "skin-ior-2.0": (dict(scale=0.1, method="RANDOM_WALK_SKIN", **{"Subsurface IOR": 2.0}), None),
}
#: The cases not held to the defaults' error: Anisotropy 0.5's darkest bin, by the terminator, is 2.8 %
#: dark in red (cause not found: its drift matches Cycles' at a shadow's edge within 0.02-0.07 d)
#: (docs/limits.md)
DRIFT = ("anisotropy-0.5",)
#: Cycles' random walk's samples per pixel
SPHERE_SAMPLES = 64


@pytest.fixture(scope="module")
def spheres(tmp_path_factory):
    """Per case: (ours, ours with the input at its default (None: the case is the defaults), Cycles'
    random walk, Cycles' Lambert base: the bins' brightness)."""
    tmp = tmp_path_factory.mktemp("walk")
    out = {}
    for case, (args, ignored) in SPHERE_CASES.items():
        scene, sphere = _scene(lambda args=args: _subsurface_material(**args), lights=("POINT",))
        scene.cycles.light_sampling_threshold = 0.0
        ours = scenes.render(scene, tmp / f"{case}-ours.exr")[..., :3].astype(np.float64)
        walk = _cycles(scene, tmp / f"{case}-walk.exr", samples=SPHERE_SAMPLES)[..., :3].astype(np.float64)
        scene.render.engine = "SHADING_LAB"
        default = walk_default = None
        if ignored is not None:
            sphere.data.materials[0] = _subsurface_material("Ignored" + case, **ignored)
            default = scenes.render(scene, tmp / f"{case}-default.exr")[..., :3].astype(np.float64)
            walk_default = _cycles(scene, tmp / f"{case}-walk-default.exr",
                                   samples=SPHERE_SAMPLES)[..., :3].astype(np.float64)
            scene.render.engine = "SHADING_LAB"
        sphere.data.materials[0] = _subsurface_material("Lambert" + case, weight=0.0, scale=0.2)
        lambert = _cycles(scene, tmp / f"{case}-lambert.exr", samples=4)[..., :3].astype(np.float64)
        out[case] = (ours, default, walk, lambert, walk_default)
    return out


#: per case: the largest |ours / walk - 1| over test_subsurface's brightness bins and the channels,
#: measured with bpy 5.0.1 (the walk at SPHERE_SAMPLES); before the walk's drift, its convex gain and
#: the light's curvature over its spread were drawn: 0.018, 0.029, 0.020, 0.038, 0.014, 0.023, 0.013,
#: 0.061, 0.023, 0.013
SPHERE_MEASURED = {"defaults": 0.013, "anisotropy-0.5": 0.028, "anisotropy-0.9": 0.017,
                   "node-ior-1.01": 0.014, "node-ior-2.0": 0.014, "node-rough-ior-2.0": 0.014,
                   "node-roughness-0": 0.014,
                   "principled-ior-1.01": 0.015, "principled-ior-2.0": 0.008, "skin-ior-2.0": 0.015}


def _bins_off(image, reference, lambert) -> float:
    """The largest |image / reference - 1| over the brightness bins and the channels."""
    return float(np.abs(_bins(image, lambert) / _bins(reference, lambert) - 1.0).max())


@pytest.mark.parametrize("case", SPHERE_CASES)
def test_walk_inputs_against_cycles(case, spheres):
    """Ours against Cycles' random walk over the brightness bins: within 3x what was measured and, but
    for DRIFT's cases, no worse than 1.5x the defaults' error plus 1 % (the walk's noise at 64
    samples). Where the input is swept and it changes Cycles' image by at least 3x our error, the
    material drawn with the input at its default (ignoring it) is at least 2x farther off than ours;
    where Cycles' image barely changes, that is printed (the input read all the same)."""
    ours, default, walk, lambert, walk_default = spheres[case]
    error = _bins_off(ours, walk, lambert)
    base = _bins_off(lambert, walk, lambert)
    ours_defaults = _bins_off(spheres["defaults"][0], spheres["defaults"][2], lambert)
    note = f"{case}: bins {error:.3f} (the defaults' {ours_defaults:.3f}; the Lambert base {base:.3f})"
    if default is not None:
        effect = _bins_off(walk, walk_default, lambert)
        ignored = _bins_off(default, walk, lambert)
        note += f"; the input changes Cycles' image by {effect:.3f}, ignored we would be {ignored:.3f} off"
    print(note)
    assert error <= 3.0 * SPHERE_MEASURED[case], (case, error)
    if case not in DRIFT:
        assert error <= 1.5 * ours_defaults + 0.01, (case, error, ours_defaults)
    if default is not None and effect >= 3.0 * error:
        assert ignored >= 2.0 * error, (case, error, ignored)


#: the world's light on it: the largest |ours / walk - 1| of the channels' means over rings of the view's
#: cosine, measured with bpy 5.0.1 (Cycles at WORLD_SAMPLES; 4.5 alike). Blender 4.2's Cycles draws a
#: channel whose Radius x Scale is under a quarter of the pixel's footprint as a plain diffuse
#: (bssrdf_setup; 4.5 no longer does): here the blue (5 mm against 10 mm), which the engine walks: ours
#: 15 % off its blue, measured there, and not held to the Lambert base's error (docs/limits.md)
WORLD_MEASURED = 0.025 if bpy.app.version >= (4, 5, 0) else 0.148
WORLD_SAMPLES = 64
#: the rings of n.v (the sphere seen from its axis: its radius)
RINGS = ((0.7, 1.01), (0.35, 0.7), (0.1, 0.35))


def test_world_light_on_the_walk(tmp_path):
    """A uniform world (0.5) on the sphere, no lights (Principled BSDF, Random Walk, Anisotropy 0.5, Scale
    0.05): the world's light on the subsurface is the Lambert base's times the walk's factor at the view
    (principled.glsl's principled_environment), against Cycles' walk over rings of the view's cosine;
    the Lambert base (before the factor) farther off."""
    from test_principled_diffuse_roughness import world_lit

    def make():
        return _subsurface_material(scale=0.05, **{"Subsurface Anisotropy": 0.5})

    scene, sphere, ours, walk = world_lit(make, tmp_path, WORLD_SAMPLES)
    sphere.data.materials[0] = _subsurface_material("WorldLambert", weight=0.0, scale=0.05)
    lambert = _cycles(scene, tmp_path / "lambert.exr", samples=WORLD_SAMPLES).astype(np.float64)
    h, w = ours.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    r = np.hypot((x + 0.5) / w - 0.5, (y + 0.5) / h - 0.5) * 2.0 * 1.0 / 0.9  # the camera spans 2 m
    cos_v = np.sqrt(np.clip(1.0 - r * r, 0.0, 1.0))
    inside = (ours[..., 3] > 0.999) & (walk[..., 3] > 0.999) & (r < 1.0)
    rows = []
    for lo, hi in RINGS:
        ring = inside & (cos_v > lo) & (cos_v <= hi)
        rows.append([img[ring, :3].mean(0) for img in (ours, walk, lambert)])
    rows = np.array(rows)  # (rings, image, channel)
    error = float(np.abs(rows[:, 0] / rows[:, 1] - 1.0).max())
    base = float(np.abs(rows[:, 2] / rows[:, 1] - 1.0).max())
    print(f"world light on the walk: ours {error:.3f}, the Lambert base {base:.3f}; per ring ours / walk "
          f"{np.round(rows[:, 0] / rows[:, 1], 3).tolist()}")
    assert error <= 3.0 * WORLD_MEASURED, error
    if bpy.app.version >= (4, 5, 0):
        assert base >= 2.0 * error, (error, base)
