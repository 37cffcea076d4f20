"""The numpy twin of ``glsl/environment.glsl``: the world as a radiance field, looked up in a
direction exactly as Cycles' Environment Texture does (``kernel/camera/projection.h``).

Directions are arrays of shape (..., 3), not necessarily unit; images are ``snapshot.ImageData``.
Pure numpy: no ``bpy``, no ``gpu``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.matrices import invert
from ..scene.snapshot import MAX_ENVIRONMENT_IMAGES, EnvironmentTerm, ImageData, World
from .brdf import MIN_PERCEPTUAL_ROUGHNESS
from .tonemap import srgb_to_linear


def equirect_uv(d) -> np.ndarray:
    """Cycles' equirectangular mapping: u = (pi - atan2(y, x)) / 2pi, v = 1 - acos(z) / pi."""
    d = np.asarray(d, np.float64)
    length = np.linalg.norm(d, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where((d[..., 0] == 0.0) & (d[..., 1] == 0.0), 0.5,
                     0.5 - np.arctan2(d[..., 1], d[..., 0]) / (2.0 * np.pi))
        v = 1.0 - np.arccos(np.clip(d[..., 2] / length, -1.0, 1.0)) / np.pi
    return np.where((length > 0.0)[..., None], np.stack([u, v], -1), 0.0)


def equirect_direction(u, v) -> np.ndarray:
    """The unit direction of equirectangular coordinates (u, v): the inverse of ``equirect_uv``."""
    phi = np.pi - 2.0 * np.pi * np.asarray(u, np.float64)
    theta = np.pi * (1.0 - np.asarray(v, np.float64))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def mirror_ball_uv(d) -> np.ndarray:
    """Cycles' mirror ball: a chrome ball photographed along +Y."""
    d = np.asarray(d, np.float64)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    x, y, z = d[..., 0], d[..., 1] - 1.0, d[..., 2]
    div = 2.0 * np.sqrt(np.maximum(-0.5 * y, 0.0))
    safe = np.where(div > 0.0, div, 1.0)
    return 0.5 * (np.stack([x / safe, z / safe], -1) + 1.0)


def linear_pixels(image: ImageData, where=None) -> np.ndarray:
    """(h, w, 4) float64 as the sampler returns them: sRGB bytes decoded, other bytes / 255; or
    (n, 4), only the texels at ``where`` (rows, columns)."""
    pixels = np.asarray(image.pixels if where is None else image.pixels[where], np.float64)
    if image.pixels.dtype == np.uint8:
        pixels = pixels / 255.0
    if image.storage == "SRGB8":
        pixels = np.concatenate([srgb_to_linear(pixels[..., :3]), pixels[..., 3:]], -1)
    return pixels


def lookup(pixels: np.ndarray, uv, closest: bool = False) -> np.ndarray:
    """Bilinear between texel centres (Cycles' "Linear"), repeating in both directions as Cycles'
    environment images do; or the texel under uv ("Closest"). ``pixels`` (h, w, c), bottom row
    first."""
    h, w = pixels.shape[:2]
    uv = np.asarray(uv, np.float64)
    p = uv * np.array([w, h])

    def texel(x, y):
        return pixels[np.mod(y, h), np.mod(x, w)]

    if closest:
        return texel(np.floor(p[..., 0]).astype(int), np.floor(p[..., 1]).astype(int))
    p = p - 0.5
    i = np.floor(p)
    f = p - i
    x, y = i[..., 0].astype(int), i[..., 1].astype(int)
    fx, fy = f[..., 0:1], f[..., 1:2]
    bottom = texel(x, y) * (1 - fx) + texel(x + 1, y) * fx
    top = texel(x, y + 1) * (1 - fx) + texel(x + 1, y + 1) * fx
    return bottom * (1 - fy) + top * fy


def term_radiance(term: EnvironmentTerm, d, threshold: float = 0.0) -> np.ndarray:
    """(..., 3): one term's radiance in directions ``d``; an equirectangular image's clamped to
    luminance ``threshold`` when it is > 0 (the lighting field, its excess split off as suns)."""
    d = np.asarray(d, np.float64)
    if term.image is None:
        return np.broadcast_to(np.asarray(term.weight, np.float64), d.shape).copy()
    m = np.asarray(term.lookup, np.float64)
    v = d @ m[:3, :3].T + m[:3, 3]
    uv = mirror_ball_uv(v) if term.projection == "MIRROR_BALL" else equirect_uv(v)
    c = np.asarray(term.weight, np.float64) * lookup(linear_pixels(term.image), uv, term.closest)[..., :3]
    if threshold > 0.0 and term.projection == "EQUIRECTANGULAR":
        c = clamp_luminance(c, threshold)
    return c


def world_radiance(terms, d, threshold: float = 0.0) -> np.ndarray:
    """(..., 3): a radiance field (``World.camera`` or ``World.lighting``) in directions ``d``,
    its constant terms and its first ``MAX_ENVIRONMENT_IMAGES`` image terms, as the GPU sums it."""
    d = np.asarray(d, np.float64)
    out = np.broadcast_to(np.asarray(World.constant(terms)), d.shape).copy()
    for term in World.images(terms)[:MAX_ENVIRONMENT_IMAGES]:
        out += term_radiance(term, d, threshold)
    return out


# --- precomputation: spherical harmonics, prefiltered levels ------------------------------------

#: Real spherical harmonics up to band 2 (Ramamoorthi & Hanrahan 2001, eq. 3): constants and
#: the order used everywhere (glsl/ibl.glsl): Y00, Y1-1, Y10, Y11, Y2-2, Y2-1, Y20, Y21, Y22.
SH_CONSTANTS = (0.282095, 0.488603, 0.488603, 0.488603, 1.092548, 1.092548, 0.315392, 1.092548, 0.546274)
#: The clamped-cosine kernel's band factors A_l (Ramamoorthi & Hanrahan 2001, eq. 8): pi, 2pi/3, pi/4.
SH_COSINE = (np.pi, 2.0 * np.pi / 3.0, 2.0 * np.pi / 3.0, 2.0 * np.pi / 3.0) + (np.pi / 4.0,) * 5


def sh9_basis(d) -> np.ndarray:
    """(..., 9): the nine basis functions at unit directions ``d``."""
    d = np.asarray(d, np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    one = np.ones_like(x)
    polys = (one, y, z, x, x * y, y * z, 3.0 * z * z - 1.0, x * z, x * x - y * y)
    return np.stack([c * p for c, p in zip(SH_CONSTANTS, polys)], -1)


def texel_solid_angles(height: int, width: int) -> np.ndarray:
    """(height,) solid angle of one texel in each row of an equirectangular image (bottom row
    first): (2 pi / width) (cos theta_top - cos theta_bottom)."""
    v = np.arange(height + 1) / height
    z = -np.cos(np.pi * v)  # z = cos(theta) with theta = pi (1 - v): -1 at the bottom edge
    return (2.0 * np.pi / width) * np.diff(z)


def texel_directions(height: int, width: int) -> np.ndarray:
    """(height, width, 3) unit directions of an equirectangular image's texel centres."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    return equirect_direction(*np.meshgrid(u, v))


def sh9_project(pixels: np.ndarray) -> np.ndarray:
    """(9, 3): the radiance coefficients L_lm of an equirectangular radiance image (h, w, >= 3),
    each texel taken as constant over its solid angle."""
    h, w = pixels.shape[:2]
    weights = texel_solid_angles(h, w)[:, None, None] * sh9_basis(texel_directions(h, w))
    return np.einsum("hwk,hwc->kc", weights, np.asarray(pixels, np.float64)[..., :3])


def sh9_irradiance(coefficients: np.ndarray, n) -> np.ndarray:
    """(..., 3): irradiance E(n) = sum_lm A_l L_lm Y_lm(n) (Ramamoorthi & Hanrahan 2001, eq. 7),
    floored at 0 (nine bands ring below zero behind a very bright source)."""
    premultiplied = np.asarray(coefficients, np.float64) * np.array(SH_COSINE)[:, None]
    return np.maximum(sh9_basis(n) @ premultiplied, 0.0)


#: Prefiltered specular levels: level k holds the environment seen through a GGX lobe of
#: perceptual roughness PREFILTER_ROUGHNESS[k]; level 0 is the mirror image, which the shading
#: takes for the smallest roughness a surface has (0.045). Closer at the smooth end, where
#: mixing two neighbours would blur a sharp reflection most.
PREFILTER_ROUGHNESS = (0.0, 0.125, 0.25, 0.375, 0.5, 0.75, 1.0)
PREFILTER_LEVELS = len(PREFILTER_ROUGHNESS)
#: With suns split off the world, levels from this one on (roughness 0.375 and up), the
#: irradiance and the SH are made from the clamped world, the smoother levels from the whole.
FIRST_CLAMPED_LEVEL = 2
#: The diffuse irradiance map (exact convolution of a downsampled environment), texels wide.
IRRADIANCE_WIDTH = 64
#: The level the spherical harmonics are projected from (texels wide; the bake, if narrower).
SH_WIDTH = 256
#: Importance samples per texel of each prefiltered level: few for the sharp, large levels, many
#: for the rough, small ones (a wide lobe over an environment with small bright sources needs
#: them), about the same work per level.
PREFILTER_SAMPLES = (0, 64, 256, 512, 1024, 2048, 2048)
#: Levels of detail added to each prefiltered level's filtered reads (``chain_lod``'s bias).
#: Krivanek & Colbert add one (a sample's read also averages its neighbourhood); for the narrow
#: lobes that blurs small bright sources well beyond the lobe. Mean error against quadrature lobe
#: means (numpy twin, 40 directions, the bundled worlds whole), bias 1 -> the one here: roughness
#: 0.125 (bias 0) forest 7.8 -> 1.8 %, sunset 1.6 -> 0.5, city 2.7 -> 0.7, studio 112 -> 23,
#: night 7.2 -> 5.2; 0.25 (bias 0.5) forest 3.1 -> 1.8, sunset 1.4 -> 0.9, city 1.9 -> 1.2, studio
#: 34 -> 21, night 7.4 -> 5.7. From 0.375 up less blur is not better everywhere (city at 0.5-1,
#: and a synthetic world of texel-sized sources at 0.375, lose), so those keep Krivanek & Colbert's
#: one (tests/test_world_light.py holds the 0.125 and 0.25 levels to the forest world's lobe means).
PREFILTER_BIAS = (0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0)
#: Widest mirror level (texels); narrower levels halve down to the narrowest.
MIRROR_WIDTH, NARROWEST = 1024, 32


def level_roughness(k: int) -> float:
    return PREFILTER_ROUGHNESS[k]



def radical_inverse(i) -> np.ndarray:
    """The Van der Corput radical inverse in base 2 of 32-bit integers (Hammersley's second
    coordinate; glsl/environment.glsl's radical_inverse)."""
    bits = np.asarray(i, np.uint64) & 0xFFFFFFFF
    reversed_bits = np.zeros_like(bits)
    for b in range(32):
        reversed_bits |= ((bits >> np.uint64(b)) & np.uint64(1)) << np.uint64(31 - b)
    return reversed_bits.astype(np.float64) * 2.0 ** -32


def _prefilter_lobe(alpha: float, samples: int):
    """The prefilter's lobe samples about n = v = +z: (l_x, l_y, l_z, pdf of l), those with
    n.l > 0 only (``prefilter_samples``)."""
    a2 = alpha * alpha
    i = np.arange(samples)
    phi = 2.0 * np.pi * i / samples
    xi2 = radical_inverse(i)
    cos_t = np.sqrt((1.0 - xi2) / (1.0 + (a2 - 1.0) * xi2))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    n_dot_l = 2.0 * cos_t * cos_t - 1.0  # l = 2 (n.h) h - n
    keep = n_dot_l > 0.0
    t = cos_t * cos_t * (a2 - 1.0) + 1.0
    pdf = (a2 / (np.pi * t * t) * 0.25)[keep]  # of l, with n = v: D(h) / 4
    lx, ly = 2.0 * cos_t * sin_t * np.cos(phi), 2.0 * cos_t * sin_t * np.sin(phi)
    return lx[keep], ly[keep], n_dot_l[keep], pdf


def chain_lod(pdf, samples: int, chain_width: int, bias: float):
    """environment.glsl's chain_lod: the chain level whose texels at the equator cover the solid
    angle 1 / (samples pdf) of a sample (the widest level ``chain_width`` texels wide), plus
    ``bias`` levels, at every latitude."""
    omega_s = 1.0 / (samples * np.asarray(pdf, np.float64))
    omega_p = 2.0 * np.pi * np.pi / (chain_width * (chain_width // 2))
    return 0.5 * np.log2(omega_s / omega_p) + bias


def prefilter_samples(alpha: float, samples: int, height: int, chain_width: int, bias: float) -> np.ndarray:
    """(height + 2, n, 4) float32: the lobe samples of one prefiltered level, per row of the level
    (``height`` rows, equirectangular), then about the north and the south pole (for the level's
    border rows: ``chain_layout``), as ``env_prefilter`` reads them.

    The level is the environment seen through a GGX lobe of ``alpha`` about each texel's
    direction with n = v (the split sum, Karis 2013): ``samples`` Hammersley half vectors
    (Walter et al. 2007, eq. 35-36), reflected to l and weighted by n.l; those with n.l <= 0 weigh
    nothing and are left out (half of them at alpha 1). Each texel of a row sees the same lobe
    turned about the pole by its longitude, and an equirectangular u is the longitude, so each
    sample is stored once per row: (u offset from the texel's u, v, the chain level to read,
    n.l / sum n.l). The level is filtered importance sampling's (Krivanek & Colbert 2008): the
    level whose texels at the equator cover the sample's solid angle 1 / (N pdf), plus ``bias``
    (``PREFILTER_BIAS``; ``chain_lod`` in glsl/environment.glsl; the chain's widest level is
    ``chain_width`` texels wide). What was
    computed per texel and sample on the GPU (the frame, the half vector, atan and acos, the
    level) is computed here once per row."""
    lx, ly, lz, pdf = _prefilter_lobe(alpha, samples)
    # each row's texel at u = 1/2 (longitude 0): n = (sin theta, 0, cos theta), and the shader's
    # frame about it: tx = normalize(cross(z, n)) = +y, ty = cross(n, tx) = (-cos theta, 0, sin theta)
    theta = np.concatenate([np.pi * (1.0 - (np.arange(height) + 0.5) / height), [0.0, np.pi]])[:, None]
    l = np.stack([-np.cos(theta) * ly + np.sin(theta) * lz, np.broadcast_to(lx, (height + 2, lx.size)),
                  np.sin(theta) * ly + np.cos(theta) * lz], -1)
    uv = equirect_uv(l)
    out = np.empty(uv.shape[:-1] + (4,), np.float32)
    out[..., 0] = uv[..., 0] - 0.5
    out[..., 1] = uv[..., 1]
    out[..., 2] = chain_lod(pdf, samples, chain_width, bias)
    out[..., 3] = lz / lz.sum()
    return out


def prefilter_reads(rows: np.ndarray, chain_width: int) -> np.ndarray:
    """(rows, 2 n, 4) float32: ``prefilter_samples``' samples (``rows``: (rows, n, 4)) as the reads
    env_prefilter makes of the chain texture (``chain_layout(chain_width)``), two texels a sample:
    (u offset, x origin and width of level k, y of level k) and (weight on level k, x origin of
    level k + 1, weight on level k + 1, y of level k + 1), in the texture's 0-1 coordinates, k the
    floor of the sample's chain level (clamped to the chain) and the weights its n.l weight split
    between k and k + 1 (level k + 1 is half as wide). A texel at longitude u then reads level k at
    (x origin + fract(u + u offset) width, y): what chain_lookup_uv computes per texel and sample
    from the same numbers, computed once per row here."""
    rects = np.array(chain_layout(chain_width), np.float64)
    size = np.array(atlas_size(rects), np.float64)
    rows = np.asarray(rows, np.float64)
    du, v, lod, weight = np.moveaxis(rows, -1, 0)
    lod = np.clip(lod, 0.0, len(rects) - 1.0)
    k = np.floor(lod).astype(int)
    k1 = np.minimum(k + 1, len(rects) - 1)
    t = lod - k
    v = np.clip(v, 0.0, 1.0)
    out = np.empty(rows.shape[:2] + (2, 4), np.float32)
    out[..., 0, 0] = du
    out[..., 0, 1] = rects[k, 0] / size[0]
    out[..., 0, 2] = rects[k, 2] / size[0]
    out[..., 0, 3] = (rects[k, 1] + v * rects[k, 3]) / size[1]
    out[..., 1, 0] = weight * (1.0 - t)
    out[..., 1, 1] = rects[k1, 0] / size[0]
    out[..., 1, 2] = weight * t
    out[..., 1, 3] = (rects[k1, 1] + v * rects[k1, 3]) / size[1]
    return out.reshape(rows.shape[0], -1, 4)


def _bordered_layout(widths) -> list[tuple[int, int, int, int]]:
    """(x, y, width, height) of equirectangular levels ``widths`` wide in one texture: the first
    on top of a row of the others, each with a border of one texel around it (``chain_layout``)."""
    rects, x, y = [(1, 1, widths[0], widths[0] // 2)], 1, widths[0] // 2 + 3
    for w in widths[1:]:
        rects.append((x, y, w, w // 2))
        x += w + 2
    return rects


def atlas_layout(mirror_width: int) -> tuple[tuple[int, int, int, int], ...]:
    """(x, y, width, height) of each prefiltered level in one texture (``atlas_size``), then of
    the irradiance map: the mirror level on top of a row of the others, each half as wide as the
    one before (never narrower than ``NARROWEST``), the irradiance map below; all
    equirectangular, each with a border of one texel (``chain_layout``)."""
    widths = [mirror_width] + [max(mirror_width >> k, NARROWEST) for k in range(1, PREFILTER_LEVELS)]
    rects = _bordered_layout(widths)
    rects.append((1, rects[1][1] + widths[1] // 2 + 2, IRRADIANCE_WIDTH, IRRADIANCE_WIDTH // 2))
    return tuple(rects)


#: The narrowest downsampled level filtered importance sampling reads (texels).
CHAIN_NARROWEST = 8


def chain_layout(width: int) -> tuple[tuple[int, int, int, int], ...]:
    """(x, y, width, height) of each downsampled level, ``width`` wide down to
    ``CHAIN_NARROWEST``, in one texture (``atlas_size``): the widest on top of a row of the
    others. Each level has a border of one texel around it (its opposite column at the sides,
    its edge row above and below), so that the GPU's bilinear filter reads a level as the
    equirectangular image it is: repeating in longitude, clamped at the poles
    (glsl/environment.glsl chain_level)."""
    widths = [width]
    while widths[-1] // 2 >= CHAIN_NARROWEST:
        widths.append(widths[-1] // 2)
    return tuple(_bordered_layout(widths))


def atlas_size(layout) -> tuple[int, int]:
    """The size of a texture holding ``layout``'s rectangles and their borders."""
    return max(x + w + 1 for x, _, w, _ in layout), max(y + h + 1 for _, y, _, h in layout)


# --- the GPU's world maps, in numpy (gpu_environment, env_*.frag.glsl) ---------------------------

def field_key(terms, threshold: float = 0.0) -> tuple:
    """A lighting field's content within this session (its images by key and revision): what the
    world's precomputation and its twin depend on, with the sun threshold it is clamped at."""
    key = [tuple(round(c, 7) for c in World.constant(terms)), threshold]
    for term in World.images(terms)[:MAX_ENVIRONMENT_IMAGES]:
        key.append((term.image.key, term.image.revision, tuple(term.weight), term.projection, term.closest,
                    np.asarray(term.lookup, np.float32).tobytes()))
    return tuple(key)


def bake_width(terms) -> int:
    """The width the field is baked at: the widest image (a mirror ball counts twice its width)
    rounded up to a power of two, 64 to 4096."""
    widest = max((term.image.size[0] * (2 if term.projection == "MIRROR_BALL" else 1)
                  for term in World.images(terms)[:MAX_ENVIRONMENT_IMAGES]), default=64)
    width = 64
    while width < min(widest, 4096):
        width *= 2
    return width


def halve(level: np.ndarray) -> np.ndarray:
    """env_downsample.frag.glsl: half the size of an equirectangular level (h, w, 3), each texel
    the solid-angle weighted mean of the 2 x 2 it covers (rows weighted by sin theta at their
    centres)."""
    h, w = level.shape[0] // 2, level.shape[1] // 2
    weight = np.sin(np.pi * (1.0 - (np.arange(2 * h) + 0.5) / (2 * h)))[:, None, None]
    summed = (level[..., :3] * weight).reshape(h, 2, w, 2, 3).sum(axis=(1, 3))
    return summed / (2.0 * weight.reshape(h, 2, 1, 1).sum(axis=1))


def chain_levels(terms, threshold: float = 0.0, max_width: int | None = None) -> list[np.ndarray]:
    """The downsampled chain (gpu_environment._chain) of the field ``terms``, its brightest texels
    clamped at ``threshold`` if > 0: the bake halved down to ``CHAIN_NARROWEST``, the levels
    from ``MIRROR_WIDTH`` (or the bake's width) down, widest first. ``max_width``: baked no wider
    (point-sampled there, not halved down to it: a cheaper, slightly sharper chain)."""
    width = bake_width(terms) if max_width is None else min(bake_width(terms), max_width)
    levels = [world_radiance(terms, texel_directions(width // 2, width), threshold)]
    while levels[-1].shape[1] > CHAIN_NARROWEST:
        levels.append(halve(levels[-1]))
    return [level for level in levels if level.shape[1] <= MIRROR_WIDTH]


def pole_borders(level: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(below, above): a level's border rows beyond its poles (``chain_layout``): 2 P - the edge
    row, P the edge row's mean (the pole's value), so that bilinear filtering runs from each edge
    texel to P at the pole itself."""
    bottom, top = level[0, :, :3], level[-1, :, :3]
    return 2.0 * bottom.mean(0) - bottom, 2.0 * top.mean(0) - top


def level_lookup(level: np.ndarray, uv) -> np.ndarray:
    """environment.glsl's bordered_level: bilinear between texel centres, repeating in u; between
    the edge rows and the poles, towards the pole's value (``pole_borders``)."""
    h, w = level.shape[:2]
    uv = np.asarray(uv, np.float64)
    x = np.mod(uv[..., 0], 1.0) * w - 0.5
    y = np.clip(uv[..., 1], 0.0, 1.0) * h - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    xa, xb = np.mod(x0, w).astype(int), np.mod(x0 + 1, w).astype(int)
    below, above = pole_borders(level)

    def texels(yi, xi):  # rows -1 and h: the borders
        inside = level[np.clip(yi, 0, h - 1), xi, :3]
        return np.where((yi >= h)[..., None], above[xi], np.where((yi < 0)[..., None], below[xi], inside))

    ya, yb = y0.astype(int), (y0 + 1).astype(int)
    bottom = texels(ya, xa) * (1.0 - fx) + texels(ya, xb) * fx
    top = texels(yb, xa) * (1.0 - fx) + texels(yb, xb) * fx
    return bottom * (1.0 - fy) + top * fy


def chain_lookup(levels: list[np.ndarray], d, lod) -> np.ndarray:
    """environment.glsl's chain_lookup: the chain in directions ``d`` (..., 3), between levels
    floor(lod) and the next."""
    uv = equirect_uv(d)
    lod = np.clip(np.broadcast_to(np.asarray(lod, np.float64), uv.shape[:-1]), 0.0, len(levels) - 1.0)
    k = np.floor(lod).astype(int)
    t = (lod - k)[..., None]
    out = np.zeros(uv.shape[:-1] + (3,))
    for level in np.unique(k):
        at = k == level
        a = level_lookup(levels[level], uv[at])
        b = level_lookup(levels[min(level + 1, len(levels) - 1)], uv[at])
        out[at] = a + (b - a) * t[at]
    return out


def tangent_frame(n) -> tuple[np.ndarray, np.ndarray]:
    """(tx, ty) about unit normals ``n`` as the world's shaders build them: tx = normalize(up x n),
    up +z unless n is within 0.999 of it (then +x), ty = n x tx."""
    n = np.asarray(n, np.float64)
    up = np.where((np.abs(n[..., 2]) < 0.999)[..., None], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    tx = np.cross(up, n)
    tx /= np.linalg.norm(tx, axis=-1, keepdims=True)
    return tx, np.cross(n, tx)


def prefiltered_level(levels: list[np.ndarray], d, k: int, samples: int | None = None) -> np.ndarray:
    """(N, 3): prefiltered level ``k`` (env_prefilter.frag.glsl) in unit directions ``d`` (N, 3),
    evaluated there rather than read between its texels: the lobe's ``samples``
    (``PREFILTER_SAMPLES[k]``) about each direction, each read from the chain at its filtered
    importance sampling level plus ``PREFILTER_BIAS[k]``, weighted by n.l. Level 0 is the chain's
    widest level."""
    d = np.asarray(d, np.float64)
    alpha = level_roughness(k) ** 2
    if alpha <= 0.0:
        return level_lookup(levels[0], equirect_uv(d))
    count = PREFILTER_SAMPLES[k] if samples is None else samples
    lx, ly, lz, pdf = _prefilter_lobe(alpha, count)
    tx, ty = tangent_frame(d)
    l = tx[:, None] * lx[:, None] + ty[:, None] * ly[:, None] + d[:, None] * lz[:, None]
    lod = np.broadcast_to(chain_lod(pdf, count, levels[0].shape[1], PREFILTER_BIAS[k]), l.shape[:-1])
    return np.einsum("nsc,s->nc", chain_lookup(levels, l, lod), lz / lz.sum())


def prefiltered_radiance(whole: list[np.ndarray], clamped: list[np.ndarray], d, roughness,
                         first_clamped: int = PREFILTER_LEVELS, samples: int | None = None) -> np.ndarray:
    """(N, 3): ibl.glsl's env_prefiltered: the two levels around each point's perceptual
    ``roughness`` (level 0 standing for the roughness floor 0.045), mixed linearly in roughness;
    levels from ``first_clamped`` on made from the ``clamped`` chain."""
    d = np.asarray(d, np.float64)
    rough = np.broadcast_to(np.asarray(roughness, np.float64), d.shape[:-1])
    r = np.array([MIN_PERCEPTUAL_ROUGHNESS] + list(PREFILTER_ROUGHNESS[1:]))
    k = np.clip(np.searchsorted(r, rough, side="left") - 1, 0, PREFILTER_LEVELS - 2)
    t = np.clip((rough - r[k]) / (r[k + 1] - r[k]), 0.0, 1.0)[..., None]
    out = np.zeros(d.shape[:-1] + (3,))
    for level in np.unique(k):
        at = k == level
        a, b = (prefiltered_level(clamped if j >= first_clamped else whole, d[at], j, samples)
                for j in (level, level + 1))
        out[at] = a + (b - a) * t[at]
    return out


def irradiance(level: np.ndarray, n) -> np.ndarray:
    """(N, 3): the irradiance E(n) = sum over texels L max(n.d, 0) dOmega of an equirectangular
    level (env_irradiance.frag.glsl's exact convolution, at ``n`` rather than between the
    irradiance map's texels)."""
    h, w = level.shape[:2]
    d = texel_directions(h, w).reshape(-1, 3)
    radiance = (level[..., :3] * texel_solid_angles(h, w)[:, None, None]).reshape(-1, 3)
    return np.maximum(np.asarray(n, np.float64) @ d.T, 0.0) @ radiance


@dataclass
class WorldMaps:
    """The numpy twin of ``gpu_environment.EnvironmentMaps``: the chains the world's light is read
    from (the whole field's and the clamped one's, the same list without suns), the first level
    made from the clamped chain, and the spherical harmonics."""

    whole: list
    clamped: list
    first_clamped: int
    sh: np.ndarray

    def level(self, width: int) -> np.ndarray:
        """The clamped chain's level ``width`` texels wide (or its widest, if narrower)."""
        return next((level for level in self.clamped if level.shape[1] == width), self.clamped[0])


def world_maps(world: World, max_width: int | None = None) -> WorldMaps:
    """What ``gpu_environment`` computes for ``world``'s lighting field (images or not); baked no
    wider than ``max_width`` if given (``chain_levels``)."""
    whole = chain_levels(world.lighting, max_width=max_width)
    suns = bool(world.suns)
    clamped = chain_levels(world.lighting, world.threshold, max_width) if suns else whole
    maps = WorldMaps(whole, clamped, FIRST_CLAMPED_LEVEL if suns else PREFILTER_LEVELS, np.zeros((9, 3)))
    maps.sh = sh9_project(maps.level(SH_WIDTH))
    return maps


# --- very bright texels: split off as suns ------------------------------------------------------

#: Rec. 709 luminance weights (the clamp keeps each texel's colour, scaling it to the threshold).
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: Suns split off one world at the most; fainter bright spots join the nearest of them.
MAX_SUNS = 4


def clamp_luminance(radiance, threshold: float) -> np.ndarray:
    """``radiance`` (..., 3) scaled down where its luminance exceeds ``threshold`` (> 0)."""
    radiance = np.asarray(radiance, np.float64)
    y = radiance @ LUMINANCE
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(y > threshold, threshold / y, 1.0)
    return radiance * scale[..., None]


#: Bright spots are told apart on a grid this many times coarser than the image (fast enough in
#: Python; two spots closer than that are one sun).
CLUSTER_CELL = 4


def _clusters(mask: np.ndarray, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """Connected components (8 neighbours, repeating in u) of a boolean image, found on cells of
    ``CLUSTER_CELL`` texels: the labels of its texels (ys, xs), those it holds."""
    h, w = mask.shape
    c = CLUSTER_CELL if h % CLUSTER_CELL == 0 and w % CLUSTER_CELL == 0 else 1
    coarse = mask.reshape(h // c, c, w // c, c).any(axis=(1, 3))
    return _cell_clusters(coarse)[ys // c, xs // c]


def _cell_clusters(mask: np.ndarray) -> np.ndarray:
    labels = np.full(mask.shape, -1, np.int64)
    h, w = mask.shape
    current = 0
    for start in zip(*np.nonzero(mask)):
        if labels[start] >= 0:
            continue
        stack = [start]
        labels[start] = current
        while stack:
            y, x = stack.pop()
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    ny, nx = y + dy, (x + dx) % w
                    if 0 <= ny < h and mask[ny, nx] and labels[ny, nx] < 0:
                        labels[ny, nx] = current
                        stack.append((ny, nx))
        current += 1
    return labels


def split_suns(term: EnvironmentTerm, threshold: float, max_suns: int = MAX_SUNS):
    """The light of ``term``'s texels above ``threshold`` (luminance, after the term's weight)
    that the clamped map no longer holds, as up to ``max_suns`` suns: [(unit direction towards
    the sun, irradiance rgb in W/m^2 on a surface facing it, solid angle)], brightest first.
    EEVEE's sun threshold makes one sun of all of it; here each bright cluster is its own, the
    faint ones joining the nearest bright one. An equirectangular image only (none for a
    mirror ball, whose texels this does not map)."""
    if term.image is None or term.projection != "EQUIRECTANGULAR" or threshold <= 0.0:
        return []
    weight = np.asarray(term.weight, np.float64)
    pixels = term.image.pixels
    h, w = pixels.shape[:2]
    # the texels that might be above the threshold, found in float32 over the whole image (with a
    # margin for its rounding; non-finite ones too), then converted and tested in float64: a 4K
    # world has 8 M texels and a few hundred bright ones. Bytes and negative weights: every texel.
    if pixels.dtype == np.uint8 or np.any(weight < 0.0):
        where = np.nonzero(np.ones((h, w), bool))
    else:
        luminance = pixels[..., :3].astype(np.float32, copy=False) @ (LUMINANCE * weight).astype(np.float32)
        where = np.nonzero((luminance > np.float32(threshold * (1.0 - 1e-4))) | ~np.isfinite(luminance))
    radiance = linear_pixels(term.image, where)[:, :3] * weight
    radiance = np.where(np.isfinite(radiance), radiance, 0.0)
    bright_ones = radiance @ LUMINANCE > threshold
    if not bright_ones.any():
        return []
    ys, xs, bright = where[0][bright_ones], where[1][bright_ones], radiance[bright_ones]
    mask = np.zeros((h, w), bool)
    mask[ys, xs] = True
    omega = texel_solid_angles(h, w)[ys]
    excess = (bright - clamp_luminance(bright, threshold)) * omega[:, None]
    # texture-space directions back to the world through the Mapping's rotation and scale
    inverse = invert(np.asarray(term.lookup, np.float64)[:3, :3])
    directions = equirect_direction((xs + 0.5) / w, (ys + 0.5) / h) @ inverse.T
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    labels = _clusters(mask, ys, xs)
    suns = []
    for label in range(labels.max() + 1):
        where = labels == label
        e = excess[where].sum(axis=0)
        d = (directions[where] * (excess[where] @ LUMINANCE)[:, None]).sum(axis=0)
        suns.append([d / max(np.linalg.norm(d), 1e-30), e, float(omega[where].sum())])
    suns.sort(key=lambda s: -float(s[1] @ LUMINANCE))
    brightest = float(suns[0][1] @ LUMINANCE)
    kept = [s for s in suns[:max_suns] if float(s[1] @ LUMINANCE) >= 0.01 * brightest]
    for d, e, omega in suns[len(kept):]:  # fainter spots: their light joins the nearest sun
        nearest = max(kept, key=lambda s: float(s[0] @ d))
        nearest[1] = nearest[1] + e
        nearest[2] += omega
    return [(tuple(d), tuple(float(c) for c in e), omega) for d, e, omega in kept]
