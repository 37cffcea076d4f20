"""Fit the sheen's linearly transformed cosines (``addon/reference/sheen_ltc.npz``) to Cycles' Sheen BSDF.

    .venv/bin/python scripts/fit_sheen.py [--out addon/reference/sheen_ltc.npz] [--size 256]

Cycles' microfiber sheen (kernel/closure/bsdf_sheen.h; Zeltner, Burley & Chiang 2022) reflects,
towards a light of direction l = (x, y, z) in the frame (the tangent towards v, n x it, n),

    f (n.l) = R a^2 z / (pi ((a x + b z)^2 + (a y)^2 + z^2)^2)

with a, b and the albedo R looked up at (n.v, roughness) bilinearly on a grid. Cycles renders a
plane filling an orthographic view whose Sheen BSDF's normal leans so that n.v runs from 0 to 1
across it, its roughness from 0 to 1 up it (both written to AOVs), under a sun of irradiance 1 from
each of SUNS in turn (direct light only, one sample at each pixel's centre: exact). At a pixel, with
c = sqrt(R) a and each lit measurement F_k = f (n.l):

    c sqrt(z_k / (pi F_k)) - a^2 (x_k^2 + y_k^2) - 2 a b x_k z_k - b^2 z_k^2 = z_k^2

is linear in (c, a^2, a b, b^2): least squares over the suns gives the pixel's (a, b, R) (a pixel
the sheen leaves black has R = 0). The grid's nodes follow by least squares over the pixels, each
the bilinear mix of its cell's four nodes (the lookup Cycles and glsl/principled.glsl's
sheen_lookup make), with a small pull towards the neighbours' mean where pixels leave a node
undetermined. Prints how well the fitted table reproduces every rendered pixel. Needs Blender as a
module (bpy); a few minutes on two cores.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from addon.reference import sheen  # noqa: E402

#: The suns' directions towards the light, (elevation above the plane, azimuth from +x), degrees:
#: the plane's normals lean towards +x, so the suns ring the view's axis at three heights.
SUNS = [(elevation, azimuth) for elevation in (20.0, 45.0, 70.0) for azimuth in range(0, 360, 60)]


def _leaning_plane(columns: int):
    """A 2 m square plane (UVs 0..1 across it) in ``columns`` strips whose smooth normals lean from
    +x at its left edge (n.v = 0 for a view down -z) to +z at its right (n.v = 1): its shading
    normal is its own (a Normal input would be a bent normal, which Cycles' bump shadowing term
    darkens)."""
    import bpy

    xs = np.linspace(-1.0, 1.0, columns + 1)
    verts = [(x, y, 0.0) for x in xs for y in (-1.0, 1.0)]
    faces = [(2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1) for i in range(columns)]
    mesh = bpy.data.meshes.new("Leaning")
    mesh.from_pydata(verts, [], faces)
    uv = mesh.uv_layers.new(name="UVMap")
    for poly in mesh.polygons:
        for loop in poly.loop_indices:
            x, y, _ = verts[mesh.loops[loop].vertex_index]
            uv.data[loop].uv = ((x + 1.0) / 2.0, (y + 1.0) / 2.0)
    mu = (xs + 1.0) / 2.0
    normals = [(math.sqrt(max(1.0 - m * m, 0.0)), 0.0, m) for m in mu for _ in (0, 1)]
    mesh.shade_smooth()
    mesh.normals_split_custom_set_from_vertices(normals)
    return bpy.data.objects.new("Leaning", mesh)


def _scene(size: int, sun: tuple[float, float]):
    """A plane filling an orthographic view (``_leaning_plane``) with a white Sheen BSDF of roughness
    v, its normal and roughness written to AOVs, under one sun."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    world = bpy.data.worlds.new("Black")
    world.use_nodes = True
    for node in world.node_tree.nodes:
        if node.bl_idname == "ShaderNodeBackground":
            node.inputs["Strength"].default_value = 0.0
    scene.world = world
    scene.view_settings.view_transform = "Standard"
    c = scene.cycles
    c.device, c.samples, c.use_adaptive_sampling, c.use_denoising = "CPU", 1, False, False
    c.max_bounces, c.use_light_tree, c.seed = 0, False, 1
    c.pixel_filter_type, c.filter_width = "GAUSSIAN", 0.01  # each pixel's centre
    c.light_sampling_threshold = 0.0  # no light sample dropped at random where it contributes little
    camera = bpy.data.cameras.new("Camera")
    camera.type, camera.ortho_scale = "ORTHO", 2.0
    cam = bpy.data.objects.new("Camera", camera)
    cam.location = (0.0, 0.0, 5.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    plane = _leaning_plane(size)
    scene.collection.objects.link(plane)
    mat = bpy.data.materials.new("Sheen")
    mat.use_nodes = True
    tree = mat.node_tree
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    bsdf = tree.nodes.new("ShaderNodeBsdfSheen")
    bsdf.distribution = "MICROFIBER"
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    coord = tree.nodes.new("ShaderNodeTexCoord")
    sep = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coord.outputs["UV"], sep.inputs["Vector"])
    tree.links.new(sep.outputs["Y"], bsdf.inputs["Roughness"])
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    for name, socket, kind in (("normal", geometry.outputs["Normal"], "COLOR"),
                               ("roughness", sep.outputs["Y"], "VALUE")):
        aov = scene.view_layers[0].aovs.add()
        aov.name, aov.type = name, kind
        node = tree.nodes.new("ShaderNodeOutputAOV")
        node.aov_name = name
        tree.links.new(socket, node.inputs["Color" if kind == "COLOR" else "Value"])
    plane.data.materials.append(mat)
    data = bpy.data.lights.new("Sun", "SUN")
    data.energy, data.angle, data.use_shadow = 1.0, 0.0, False
    sun_object = bpy.data.objects.new("Sun", data)
    elevation, azimuth = (math.radians(x) for x in sun)
    towards = np.array([math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                        math.sin(elevation)])
    from mathutils import Vector

    sun_object.rotation_euler = Vector(tuple(-towards)).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(sun_object)
    return scene, towards


def render(size: int, sun: tuple[float, float], folder: Path) -> dict[str, np.ndarray]:
    """One sun's render: f (n.l) per pixel (red), the normal and the roughness Cycles shaded with,
    and the sun's direction towards the light."""
    import bpy
    import OpenEXR

    scene, towards = _scene(size, sun)
    bpy.ops.render.render()
    path = folder / "sheen.exr"
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    bpy.data.images["Render Result"].save_render(str(path), scene=scene)
    with OpenEXR.File(str(path)) as f:
        channels = {name: np.asarray(ch.pixels, np.float64)
                    for part in f.parts for name, ch in part.channels.items()}
    return {"value": channels["ViewLayer.Combined"][..., 0], "normal": channels["ViewLayer.normal"][..., :3],
            "roughness": channels["ViewLayer.roughness.X"], "towards": towards}


def _frames(renders: list[dict]):
    """Per pixel: the unit normal, n.v, the roughness and the sheen's frame (the tangent towards v,
    n x it), v the orthographic view's (0, 0, 1)."""
    n = renders[0]["normal"].reshape(-1, 3)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    v = np.array([0.0, 0.0, 1.0])
    mu = n @ v
    x_axis = v - n * mu[:, None]
    x_axis /= np.linalg.norm(x_axis, axis=-1, keepdims=True)
    return n, mu, renders[0]["roughness"].reshape(-1), x_axis, np.cross(n, x_axis)


def pixel_fits(renders: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(n.v, roughness, (a, b, R), which pixels have a lobe) of every pixel, from its measurements
    under every sun. With c = sqrt(R) a, each lit measurement F_k gives

        c sqrt(z_k / (pi F_k)) - a^2 (x_k^2 + y_k^2) - 2 a b x_k z_k - (b^2 + 1) z_k^2 = 0,

    homogeneous in (c, a^2, a b, b^2 + 1): the suns' rows' null vector (its least singular vector)
    is that up to a scale, which b^2 + 1 - (a b)^2 / a^2 = 1 fixes."""
    n, mu, rough, x_axis, y_axis = _frames(renders)
    rows, valid = [], []
    for r in renders:
        l = r["towards"]
        x, y, z = x_axis @ l, y_axis @ l, n @ l
        F = r["value"].reshape(-1)
        ok = (z > 1e-3) & (F > 0.0)
        w = np.sqrt(np.where(ok, z, 0.0) / (np.pi * np.where(ok, F, 1.0)))
        rows.append(np.stack([w, -(x * x + y * y), -2.0 * x * z, -z * z], -1) * ok[:, None])
        valid.append(ok)
    M = np.stack(rows, 1)  # (pixels, suns, 4)
    lobe = np.sum(valid, axis=0) >= 5
    scale = np.maximum(np.abs(M).max(axis=1, keepdims=True), 1e-30)  # columns of like size
    q = np.linalg.svd(M / scale)[2][:, -1, :] / scale[:, 0, :]  # (c, a^2, a b, b^2 + 1) up to a scale
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = 1.0 / (q[:, 3] - q[:, 2] ** 2 / q[:, 1])
        c, A, B = q[:, 0] * lam, q[:, 1] * lam, q[:, 2] * lam
        a = np.sqrt(np.maximum(A, 1e-30))
        fit = np.stack([a, B / a, c * c / np.maximum(A, 1e-30)], -1)
    good = lobe & np.isfinite(fit).all(axis=1) & (A > 0.0)
    return mu, rough, np.nan_to_num(fit), good


def node_solve(mu, rough, values, weight, size: int, pull: float = 1e-3) -> np.ndarray:
    """(size, size) nodes whose bilinear mix at each (mu, rough) matches ``values`` in least squares
    (``weight`` per pixel), pulled towards their neighbours' mean by ``pull`` (nodes no pixel
    determines take their neighbours')."""
    from scipy import sparse
    from scipy.sparse.linalg import lsqr

    n = size - 1
    x, y = np.clip(mu, 0.0, 1.0) * n, np.clip(rough, 0.0, 1.0) * n
    i0, j0 = np.minimum(np.floor(x).astype(int), n - 1), np.minimum(np.floor(y).astype(int), n - 1)
    fx, fy = x - i0, y - j0
    cols = np.stack([j0 * size + i0, j0 * size + i0 + 1, (j0 + 1) * size + i0, (j0 + 1) * size + i0 + 1], -1)
    w = np.stack([(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy], -1) * weight[:, None]
    rows = np.repeat(np.arange(len(mu)), 4)
    A = sparse.csr_matrix((w.ravel(), (rows, cols.ravel())), shape=(len(mu), size * size))
    smooth = []
    for j in range(size):
        for i in range(size):
            near = [(j + dj) * size + i + di for dj, di in ((0, 1), (0, -1), (1, 0), (-1, 0))
                    if 0 <= i + di < size and 0 <= j + dj < size]
            row = np.zeros(size * size)
            row[j * size + i] = 1.0
            row[near] = -1.0 / len(near)
            smooth.append(row * pull)
    A = sparse.vstack([A, sparse.csr_matrix(np.array(smooth))])
    b = np.concatenate([values * weight, np.zeros(size * size)])
    return lsqr(A, b, atol=1e-12, btol=1e-12, iter_lim=20000)[0].reshape(size, size)


def fit_table(renders: list[dict], size: int = sheen.SIZE) -> np.ndarray:
    """(size, size, 3) float32: (a, b, albedo) by [roughness, n.v] from the renders."""
    mu, rough, fit, lobe = pixel_fits(renders)
    black = np.max([r["value"].reshape(-1) for r in renders], axis=0) <= 0.0
    table = np.zeros((size, size, 3))
    for k in range(2):  # a and b where the sheen has a lobe
        table[..., k] = node_solve(mu[lobe], rough[lobe], fit[lobe, k], np.ones(lobe.sum()), size)
    keep = lobe | black  # the albedo: 0 where Cycles drew no sheen at all
    albedo = np.where(black, 0.0, fit[:, 2])
    table[..., 2] = node_solve(mu[keep], rough[keep], albedo[keep], np.ones(keep.sum()), size)
    return table.astype(np.float32)


def reproduction_error(renders: list[dict], table: np.ndarray) -> float:
    """The largest |f_table - f_Cycles| over every rendered pixel, relative to the largest f."""
    n, mu, rough, x_axis, y_axis = _frames(renders)
    sheen.table.cache_clear()
    t = table.astype(np.float64)
    x, y = np.clip(mu, 0, 1) * (len(t) - 1), np.clip(rough, 0, 1) * (len(t) - 1)
    i0, j0 = np.floor(x).astype(int), np.floor(y).astype(int)
    i1, j1 = np.minimum(i0 + 1, len(t) - 1), np.minimum(j0 + 1, len(t) - 1)
    fx, fy = (x - i0)[:, None], (y - j0)[:, None]
    top = t[j0, i0] + (t[j0, i1] - t[j0, i0]) * fx
    fit = top + (t[j1, i0] + (t[j1, i1] - t[j1, i0]) * fx - top) * fy
    a, b, R = fit[:, 0], fit[:, 1], fit[:, 2]
    on = (np.abs(a) >= 1e-5) & (R >= 1e-5)
    worst, scale = 0.0, 0.0
    for r in renders:
        l = r["towards"]
        x, y, z = x_axis @ l, y_axis @ l, n @ l
        len2 = (a * x + b * z) ** 2 + (a * y) ** 2 + z * z
        f = np.where(on & (z > 0.0), R * a * a * np.maximum(z, 0.0) / (np.pi * len2 * len2), 0.0)
        F = r["value"].reshape(-1)
        worst = max(worst, float(np.abs(f - F).max()))
        scale = max(scale, float(F.max()))
    return worst / scale


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=sheen.SHIPPED)
    parser.add_argument("--size", type=int, default=256, help="pixels per side of each render")
    args = parser.parse_args()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        renders = [render(args.size, sun, Path(folder)) for sun in SUNS]
    table = fit_table(renders)
    error = reproduction_error(renders, table)
    np.savez_compressed(args.out, sheen_ltc=table)
    print(f"wrote the sheen table {table.shape} to {args.out} in {time.perf_counter() - start:.1f} s; "
          f"it reproduces Cycles' {len(renders)} renders to {error:.2e} of their largest value")
    return 0


if __name__ == "__main__":
    sys.exit(main())
