"""Random scenes for the Auto term set: four spheres on a ground plane, each with its own random
material, under 1-8 random lights of every kind, a black or uniform world, seen by an orthographic
camera from a frontal or a grazing elevation; and the per-material error of one render against
another, measured on the pixels each material covers (found by intersecting the pixels' rays with
the analytic spheres and plane, not from the engine)."""

from __future__ import annotations

import math
from pathlib import Path

import bpy
import numpy as np
import scenes

SIZE = 96
SCALE = 4.4  # the orthographic view's width (m)
SPHERES = ((-1.5, 0.45), (-0.5, 0.45), (0.5, 0.45), (1.5, 0.45))  # (x, radius), on the plane z = 0


def random_material(rng, name: str) -> bpy.types.Material:
    """Roughness 0-1, metal or dielectric (IOR 1.3-2.5), a random base colour."""
    metal = bool(rng.random() < 0.5)
    ior = float(rng.uniform(1.3, 2.5))
    return scenes.material(name, base_color=tuple(float(c) for c in rng.uniform(0.05, 0.95, 3)),
                           roughness=float(rng.random()), metalness=1.0 if metal else 0.0,
                           f0=((ior - 1.0) / (ior + 1.0)) ** 2)


def random_light(rng, scene, index: int):
    kind = str(rng.choice(["POINT", "SPOT", "SUN", "AREA"]))
    location = (float(rng.uniform(-3, 3)), float(rng.uniform(-3, 1)), float(rng.uniform(1.5, 4.0)))
    target = np.array([rng.uniform(-1.5, 1.5), 0.0, 0.4])
    d = target - np.array(location)
    pitch = math.atan2(math.hypot(d[0], d[1]), -d[2])
    yaw = math.atan2(-d[0], d[1])  # the light's -Z axis turned towards the target
    energy = {"POINT": 150.0, "SPOT": 150.0, "SUN": 2.0, "AREA": 100.0}[kind] * float(rng.uniform(0.3, 1.5))
    obj = scenes.light(scene, kind, energy=energy, location=location, rotation=(pitch, 0.0, yaw),
                       color=tuple(float(c) for c in rng.uniform(0.6, 1.0, 3)))
    obj.name = f"Light {index}"
    data = obj.data
    data.use_shadow = True
    if kind in ("POINT", "SPOT"):
        data.shadow_soft_size = float(rng.choice([0.0, rng.uniform(0.05, 0.5)]))
        if kind == "SPOT":
            data.spot_size = float(rng.uniform(0.6, 1.6))
            data.spot_blend = float(rng.uniform(0.0, 0.5))
    elif kind == "SUN":
        data.angle = float(rng.choice([0.0, rng.uniform(0.01, 0.1)]))
    else:
        data.shape = str(rng.choice(["SQUARE", "RECTANGLE", "DISK", "ELLIPSE"]))
        data.size = float(rng.uniform(0.2, 1.5))
        data.size_y = float(rng.uniform(0.2, 1.5))
    return obj


def random_scene(seed: int):
    """(scene, camera, material names in sphere order then the ground's)."""
    rng = np.random.default_rng(seed)
    scene = scenes.reset(size=SIZE)
    scene.shading_lab.model = "PBR"
    elevation = math.radians(float(rng.choice([rng.uniform(6, 15), rng.uniform(50, 85)])))
    eye = (0.0, -10.0 * math.cos(elevation), 0.45 + 10.0 * math.sin(elevation))
    camera = scenes.ortho_camera(scene, location=eye, rotation=(math.pi / 2 - elevation, 0.0, 0.0),
                                 scale=SCALE)
    names = []
    for i, (x, radius) in enumerate(SPHERES):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=(x, 0.0, radius), segments=64,
                                             ring_count=32)
        sphere = bpy.context.object
        for poly in sphere.data.polygons:
            poly.use_smooth = True
        mat = random_material(rng, f"Sphere {i}")
        sphere.data.materials.append(mat)
        names.append(mat.name)
    ground = random_material(rng, "Ground")
    scenes.plane(scene, size=12.0, material=ground)
    names.append(ground.name)
    for i in range(int(rng.integers(1, 9))):
        random_light(rng, scene, i)
    if rng.random() < 0.5:
        background = next(n for n in scenes.node_tree(scene.world).nodes
                          if n.bl_idname == "ShaderNodeBackground")
        background.inputs["Color"].default_value = (*(float(c) for c in rng.uniform(0.3, 1.0, 3)), 1.0)
        background.inputs["Strength"].default_value = float(rng.uniform(0.05, 0.4))
    bpy.context.view_layer.update()
    return scene, camera, names


#: Blender's bundled worlds the image-world scenes take turns with (by seed).
WORLDS = ("forest", "city", "studio", "sunset")


def world_scene(seed: int, specular: str = "SAMPLED", samples: int = 16):
    """``random_scene(seed)`` under one of Blender's bundled worlds (WORLDS, by seed), turned about
    the vertical and scaled (strength 0.3-1.5) at random, with World Specular ``specular``
    (SAMPLED at ``samples`` a pixel, or SPLIT_SUM)."""
    from test_world_light import _hdri, _world

    scene, camera, names = random_scene(seed)
    rng = np.random.default_rng(seed + 7)
    _world(scene, image=_hdri(WORLDS[seed % len(WORLDS)]), strength=float(rng.uniform(0.3, 1.5)))
    tree = scene.world.node_tree
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value[2] = float(rng.uniform(0.0, 2.0 * math.pi))
    coords = tree.nodes.new("ShaderNodeTexCoord")
    tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], tree.nodes["Environment Texture"].inputs["Vector"])
    props = scene.shading_lab
    props.world_specular, props.world_samples = specular, samples
    bpy.context.view_layer.update()
    return scene, camera, names


def sphere_hits(origins, direction, centre, radius: float) -> np.ndarray:
    """Distance along each ray (unit ``direction``) to the sphere's near side; inf where it misses."""
    oc = origins - np.asarray(centre, np.float64)
    b = oc @ direction
    disc = b * b - (np.sum(oc * oc, axis=-1) - radius * radius)
    return np.where(disc > 0.0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)


def interior(ids: np.ndarray) -> np.ndarray:
    """Pixels whose whole 3x3 neighbourhood has their own value (pixels beyond the edge: none)."""
    h, w = ids.shape
    padded = np.pad(ids, 1, constant_values=-1)
    same = np.ones((h, w), bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            same &= padded[dy:dy + h, dx:dx + w] == ids
    return same


#: Pixels whose centre lies within this many pixels of a sphere's silhouette belong to no
#: material: there the drawn mesh (64 x 32 segments, its outline up to 0.005 radii = 0.04 px
#: inside the sphere's) and the analytic sphere may disagree.
SILHOUETTE_MARGIN = 0.05


def material_masks(camera, names) -> dict[str, np.ndarray]:
    """Per material, the pixels (top row first) whose centre's ray meets it first, but for those
    within SILHOUETTE_MARGIN of a sphere's outline: every pixel the material shows, its grazing rim
    and the creases at its contacts included (a 3x3 erosion dropped the outer pixel ring, where
    n.v < 0.47 on these spheres, 22 % of their pixels and the ones where the terms differ most)."""
    origins, direction = scenes.ortho_pixel_rays(SIZE, SCALE, np.array(camera.matrix_world))
    depth = np.full((SIZE, SIZE), np.inf)
    ids = np.full((SIZE, SIZE), -1)
    margin = SILHOUETTE_MARGIN * SCALE / SIZE
    near_outline = np.zeros((SIZE, SIZE), bool)
    for i, (x, radius) in enumerate(SPHERES):
        t = sphere_hits(origins, direction, (x, 0.0, radius), radius)
        nearer = (t > 0.0) & (t < depth)
        depth, ids = np.where(nearer, t, depth), np.where(nearer, i, ids)
        inner = np.isfinite(sphere_hits(origins, direction, (x, 0.0, radius), radius - margin))
        outer = np.isfinite(sphere_hits(origins, direction, (x, 0.0, radius), radius + margin))
        near_outline |= outer & ~inner
    t = -origins[..., 2] / direction[2] if direction[2] != 0.0 else np.full((SIZE, SIZE), np.inf)
    hit = (t > 0.0) & (t < depth) & (np.abs(origins[..., 0] + t * direction[0]) < 6.0)
    ids = np.where(hit, len(SPHERES), ids)
    return {name: ~near_outline & (ids == i) for i, name in enumerate(names)}


def measured_errors(image, reference, masks, quantile: float, min_pixels: int = 20) -> dict[str, float]:
    """Per material, Delta E_ITP of ``image`` against ``reference`` at ``quantile`` of its pixels."""
    from addon.plan import auto_terms

    error = auto_terms.delta_e_itp(image[..., :3], reference[..., :3])
    return {name: float(np.quantile(error[mask], quantile)) for name, mask in masks.items()
            if mask.sum() >= min_pixels}


def render_pairs(scene, camera, names, seed: int, bounds, folder: Path) -> dict[float, list]:
    """{bound: [(seed, material, Choice, measured error)]}: ``scene`` rendered with the Principled
    set once and with Auto at each of ``bounds``, the error measured per material on its pixels
    (``material_masks``) at the scene's Auto quantile."""
    from addon.blender import engine

    props = scene.shading_lab
    props.term_set = "PRINCIPLED"
    reference = scenes.render(scene, folder / f"{seed}_principled.exr")
    masks = material_masks(camera, names)
    out = {}
    for bound in bounds:
        props.term_set, props.auto_error_bound = "AUTO", bound
        auto = scenes.render(scene, folder / f"{seed}_auto_{bound}.exr")
        choices = dict(engine.last_term_choices)
        measured = measured_errors(auto, reference, masks, props.auto_quantile / 100.0)
        out[bound] = [(seed, name, choices[name], measured[name]) for name in names if name in measured]
    return out


def tally(rows, bound: float) -> tuple[float, dict[str, int], list]:
    """Of ``render_pairs`` rows at ``bound``: the share of materials measured within it, how many
    took each set, and those over it (seed, material, set, predicted, measured)."""
    measured = np.array([m for *_, m in rows])
    within = float(np.mean(measured <= bound)) if len(measured) else float("nan")
    chosen: dict[str, int] = {}
    for *_, choice, _m in rows:
        chosen[choice.name] = chosen.get(choice.name, 0) + 1
    over = [(seed, name, c.name, round(c.predicted, 2), round(m, 2))
            for seed, name, c, m in rows if m > bound]
    return within, chosen, over
