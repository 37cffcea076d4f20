"""The world's light, precomputed on the GPU once per world content (``EnvironmentPass``).

From the lighting field of ``snapshot.World`` (constant terms and up to four environment images):
1. bake: one equirectangular image of the field (``env_bake``), as wide as the widest image
   (a power of two, 64 to 4096; a mirror ball counts twice its width), straight into the chain
   texture's widest rectangle when it fits (``environment.MIRROR_WIDTH``);
2. downsample: halve it down to ``environment.CHAIN_NARROWEST`` texels wide, each level
   solid-angle weighted (``env_downsample``), and copy the halved levels into the chain texture;
3. spherical harmonics: the level 256 texels wide (or the bake, if narrower) read back and
   projected in numpy (``environment.sh9_project``): nine coefficients for the irradiance;
4. prefiltered levels: an atlas (``environment.atlas_layout``) of the environment seen through
   GGX lobes of roughness k / 6: level 0 a copy of the level as wide as the mirror level, the
   others ``PREFILTER_SAMPLES`` lobe samples each from the level whose texels match a sample's
   share of the lobe (``env_prefilter``).
A world without images needs none of this: its SH are those of a constant and its prefiltered
radiance the constant itself. The result (``EnvironmentMaps``) is kept in the program library by
a key of the field's content, so renders and the viewport share it and an object edit recomputes
nothing. The chains (the whole world's and, with suns split off, the clamped one's) are kept with
it only once a surface samples the world per pixel (``samples_per_pixel``): the split sum reads
the atlas alone, and without them the clamped chain is drawn over the whole one in one texture
(25 MB less for a 1K world with suns, on the GPU and in ``world_cache``'s file).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import gpu
import numpy as np

from ..plan import programs, world_cache
from ..reference import environment as env
from ..scene.snapshot import MAX_ENVIRONMENT_IMAGES, Snapshot, World
from . import gpu_library
from .passes import Frame, Pass, Target

#: Environments precomputed since start (tests count them: an object edit must add none), and
#: those read from the disk cache instead (``world_cache``).
BUILDS = 0
LOADS = 0


@dataclass
class EnvironmentMaps:
    """What the shading programs bind: the EnvironmentData block and, for images, the atlas."""

    block: gpu.types.GPUUniformBuf
    atlas: gpu.types.GPUTexture | None
    chain: gpu.types.GPUTexture | None  # the downsampled levels, for per-pixel sampling
    clamped_chain: gpu.types.GPUTexture | None  # the same with the suns split off
    chain_block: gpu.types.GPUUniformBuf | None
    sh: np.ndarray  # (9, 3) radiance coefficients L_lm (not premultiplied)
    rects: tuple
    build_ms: float  # the precomputation's, or (``loaded``) reading it from the disk cache
    loaded: bool = False


def _packed(sh: np.ndarray, rects, uniform, first_clamped: int = 0) -> gpu.types.GPUUniformBuf:
    premultiplied = sh * np.array(env.SH_COSINE)[:, None]
    roughness = env.PREFILTER_ROUGHNESS if rects else ()
    size = env.atlas_size(rects) if rects else (0, 0)
    return gpu.types.GPUUniformBuf(programs.pack_environment(premultiplied, rects, uniform, roughness,
                                                             first_clamped, size))


def _uniform(terms) -> EnvironmentMaps:
    radiance = np.array(World.constant(terms))
    sh = np.zeros((9, 3))
    sh[0] = radiance * env.SH_CONSTANTS[0] * 4.0 * np.pi  # L00 of a constant: L Y00 4 pi
    return EnvironmentMaps(_packed(sh, (), radiance), None, None, None, None, sh, (), 0.0)


def _draw(frame: Frame, shader, bind, target: Target, rect=None) -> None:
    with target.bind():
        gpu.state.depth_test_set("NONE")
        gpu.state.blend_set("NONE")
        if rect is not None:
            gpu.state.viewport_set(*rect)
        shader.bind()
        bind(shader)
        frame.full_screen.draw(shader)
        if rect is not None:
            gpu.state.viewport_set(0, 0, target.width, target.height)


def _bordered(rect) -> tuple[int, int, int, int]:
    """A level's rectangle with its border (``environment.chain_layout``): the viewport it is
    drawn with."""
    return rect[0] - 1, rect[1] - 1, rect[2] + 2, rect[3] + 2


def _chain(frame: Frame, terms, clamp: bool, reuse: list[Target] | None = None, into: Target | None = None
           ) -> tuple[list[Target], Target, tuple]:
    """Bake the field (with its brightest texels clamped, if ``clamp``) and halve it down to
    ``environment.CHAIN_NARROWEST``, the levels from the mirror level's width down in one texture
    for the prefilter (``environment.chain_layout``). The bake goes straight into that texture's
    widest rectangle, with its border (env_bake; the means of its edge rows from a pass of their
    own); each halved level is drawn on its own and copied into its rectangle. A field wider than
    the mirror level is baked on its own and halved down to it first. Returns the levels drawn on
    their own, that texture and its rectangles. ``reuse``: the levels drawn on their own of a
    chain of the same field, already copied into its texture, drawn again instead of new ones (on a
    software rasteriser a new texture's first writes cost about as much as the drawing: ~1.7 ms
    per MB here); ``into``: a chain texture of the same field to draw over, likewise."""
    width = env.bake_width(terms)
    images = min(len(World.images(terms)), MAX_ENVIRONMENT_IMAGES)
    spare = iter(reuse or ())
    rects = env.chain_layout(min(width, env.MIRROR_WIDTH))
    chain = into or Target(*env.atlas_size(rects), depth=False)
    params = (1.0 if clamp else 0.0, 0.0, 0.0, 0.0)

    def bake(rect, poles=None):
        def bind(shader):
            frame.scene.bind_world(shader, terms, lighting=True)
            shader.uniform_float("rect", tuple(float(x) for x in rect))
            shader.uniform_float("params", params)
            if poles is not None:
                gpu_library.bind_sampler(shader, "poles", poles)
        return bind

    levels = []
    if width > env.MIRROR_WIDTH:  # baked on its own (no border rows: the chain texture stands in)
        levels.append(next(spare, None) or Target(width, width // 2, depth=False))
        source, source_rect = levels[0].texture_color, (0, 0, width, width // 2)
        _draw(frame, gpu_library.env_bake_program(images), bake(source_rect, chain.texture_color), levels[0])
    else:
        poles = Target(2, 1, depth=False)
        _draw(frame, gpu_library.env_bake_program(images, poles=True), bake(rects[0]), poles)
        _draw(frame, gpu_library.env_bake_program(images), bake(rects[0], poles.texture_color), chain,
              _bordered(rects[0]))
        source, source_rect = chain.texture_color, rects[0]
    downsample = gpu_library.env_downsample_program()
    while source_rect[2] > env.CHAIN_NARROWEST:
        w, h = source_rect[2] // 2, source_rect[3] // 2
        levels.append(next(spare, None) or Target(w, h, depth=False))

        def bind(shader, texture=source, rect=source_rect):
            gpu_library.bind_sampler(shader, "source", texture)
            shader.uniform_float("offset", tuple(float(x) for x in rect))

        _draw(frame, downsample, bind, levels[-1])
        source, source_rect = levels[-1].texture_color, (0, 0, w, h)
    copy = gpu_library.env_downsample_program(copy=True)
    by_width = {t.width: t for t in levels}
    for rect in rects:
        if rect[2] not in by_width:
            continue  # baked in place

        def bind(shader, level=by_width[rect[2]], rect=rect):
            gpu_library.bind_sampler(shader, "source", level.texture_color)
            shader.uniform_float("offset", (float(rect[0]), float(rect[1]), 0.0, 0.0))

        _draw(frame, copy, bind, chain, _bordered(rect))
    return levels, chain, rects


def _sh_level(levels: list[Target], chain: Target, rects) -> np.ndarray:
    """The level the spherical harmonics are projected from (``environment.SH_WIDTH`` wide, or the
    widest if narrower), read back."""
    level = next((t for t in levels if t.width == env.SH_WIDTH), None)
    return level.read() if level is not None else chain.read(rects[0])  # narrower: baked in place


def _chain_block(chain_rects) -> gpu.types.GPUUniformBuf:
    """The ChainData block (glsl/chain_data.glsl): the levels' rectangles, their count and the
    texture's size."""
    rows = np.zeros((13, 4), np.float32)
    rows[:len(chain_rects)] = chain_rects
    rows[12, :3] = (len(chain_rects), *env.atlas_size(chain_rects))
    return gpu.types.GPUUniformBuf(rows.tobytes())


def _build_maps(frame: Frame, terms, suns: bool, keep=None, chains: bool = True) -> EnvironmentMaps:
    """The maps of an image-lit world. With suns split off, two chains: the whole world for the
    smoother prefiltered levels (which show the brightest texels where they are), the clamped one
    for the rougher levels, the irradiance and the SH (the suns light those as lights).
    ``keep(arrays)``: handed what ``_maps`` makes the same maps from again (read back).
    ``chains``: keep the chains for surfaces that sample the world per pixel; without them the
    clamped chain is drawn over the whole one once the levels that read it are drawn (one texture
    instead of two)."""
    global BUILDS
    BUILDS += 1
    start = time.perf_counter()
    levels, chain, chain_rects = _chain(frame, terms, clamp=False)
    chain_block = _chain_block(chain_rects)
    rects = env.atlas_layout(chain_rects[0][2])
    atlas = Target(*env.atlas_size(rects), depth=False)
    first_clamped = env.FIRST_CLAMPED_LEVEL if suns else env.PREFILTER_LEVELS
    _prefiltered(frame, chain, chain_rects, chain_block, atlas, rects, range(first_clamped))
    clamped_levels, clamped = _clamped_chain(frame, terms, suns, levels, chain,
                                             into=None if chains else chain)
    sh = env.sh9_project(_sh_level(clamped_levels, clamped, chain_rects))
    _prefiltered(frame, clamped, chain_rects, chain_block, atlas, rects, range(first_clamped, len(rects)))
    atlas.fence()  # the time below is the GPU's too
    for target in {*levels, *clamped_levels}:
        target.free()
    if keep is not None:
        keep({"atlas": atlas.read(), "sh": sh})
    return EnvironmentMaps(_packed(sh, rects, (0.0, 0.0, 0.0), first_clamped), atlas.texture_color,
                           chain.texture_color if chains else None,
                           clamped.texture_color if chains else None, chain_block, sh, rects,
                           1e3 * (time.perf_counter() - start))


def _prefiltered(frame: Frame, chain: Target, chain_rects, chain_block, atlas: Target, rects, which) -> None:
    """Draw the atlas's levels ``which`` (indices into ``rects``; the last is the irradiance map)
    from ``chain``."""
    irradiance_source = next(k for k, r in enumerate(chain_rects) if r[2] == env.IRRADIANCE_WIDTH)
    for k in which:
        rect = rects[k]
        last = k == len(rects) - 1  # the irradiance map
        alpha = 0.0 if last else env.level_roughness(k) ** 2
        samples = None
        if not last and alpha > 0.0:
            samples = gpu_library.prefilter_samples(alpha, env.PREFILTER_SAMPLES[k], rect[3],
                                                    chain_rects[0][2], env.PREFILTER_BIAS[k])
        count = float(samples.width // 2) if samples is not None else 0.0  # two texels a sample
        params = (alpha, float(irradiance_source) if last else 0.0, count, 0.0)

        def bind(shader, rect=rect, params=params, samples=samples):
            gpu_library.bind_sampler(shader, "source", chain.texture_color)
            # (the mirror level and the irradiance map read no samples: any texture will do)
            gpu_library.bind_sampler(shader, "samples", chain.texture_color if samples is None else samples)
            shader.uniform_block("chain", chain_block)
            shader.uniform_float("rect", tuple(float(x) for x in rect))
            shader.uniform_float("params", params)

        program = gpu_library.env_irradiance_program() if last else gpu_library.env_prefilter_program()
        _draw(frame, program, bind, atlas, _bordered(rect))


def _add_chains(frame: Frame, terms, suns: bool, maps: EnvironmentMaps) -> None:
    """The chains of maps built or read without them, drawn for surfaces that sample the world per
    pixel (the same textures ``_build_maps`` keeps when asked to)."""
    levels, chain, _ = _chain(frame, terms, clamp=False)
    clamped_levels, clamped = _clamped_chain(frame, terms, suns, levels, chain)
    for target in {*levels, *clamped_levels}:
        target.free()
    maps.chain, maps.clamped_chain = chain.texture_color, clamped.texture_color


def _clamped_chain(frame: Frame, terms, suns: bool, levels: list[Target], chain: Target,
                   into: Target | None = None) -> tuple[list[Target], Target]:
    """The chain with the suns split off (drawn in the whole chain's halved levels again, and
    ``into`` that texture if given), or the whole chain itself when there are none."""
    if not suns:
        return levels, chain
    clamped_levels, clamped, _ = _chain(frame, terms, True, levels, into=into)
    return clamped_levels, clamped


def _layouts(terms) -> tuple[tuple, tuple]:
    """The rectangles of the chain's levels and of the atlas's (as ``_chain`` and ``_build_maps``
    lay them out)."""
    chain_rects = env.chain_layout(min(env.bake_width(terms), env.MIRROR_WIDTH))
    return chain_rects, env.atlas_layout(chain_rects[0][2])


def _shapes(terms) -> dict[str, tuple]:
    """The arrays ``_build_maps`` keeps, by shape (rows first)."""
    _, rects = _layouts(terms)
    atlas = env.atlas_size(rects)
    return {"atlas": (atlas[1], atlas[0], 4), "sh": (9, 3)}


def _maps(terms, suns: bool, arrays) -> EnvironmentMaps:
    """The maps ``_build_maps`` made, from the arrays it kept (without the chains)."""
    global LOADS
    start = time.perf_counter()
    chain_rects, rects = _layouts(terms)
    sh = np.asarray(arrays["sh"], np.float64)
    first_clamped = env.FIRST_CLAMPED_LEVEL if suns else env.PREFILTER_LEVELS
    LOADS += 1
    atlas = gpu_library.rgba32f_texture(arrays["atlas"])
    return EnvironmentMaps(_packed(sh, rects, (0.0, 0.0, 0.0), first_clamped), atlas, None, None,
                           _chain_block(chain_rects), sh, rects, 1e3 * (time.perf_counter() - start),
                           loaded=True)


def _device() -> str:
    return "|".join((gpu.platform.vendor_get(), gpu.platform.renderer_get(), gpu.platform.version_get()))


def _cached_or_built(frame: Frame, terms, threshold: float, suns: bool, chains: bool) -> EnvironmentMaps:
    """The maps from the disk cache (``world_cache``) if an earlier session kept them, else built
    (and kept for the next), with the chains if ``chains``. Not for images being edited (each edit
    would write a file)."""
    saved = all(term.image.saved for term in World.images(terms)[:MAX_ENVIRONMENT_IMAGES])
    key = None
    if saved and world_cache.folder() is not None:
        key = world_cache.content_key(terms, threshold, suns, _device())
    if key is not None:
        arrays = world_cache.load(key, _shapes(terms))
        if arrays is not None:
            return _maps(terms, suns, arrays)
    if key is None:
        return _build_maps(frame, terms, suns, chains=chains)
    return _build_maps(frame, terms, suns, keep=lambda arrays: world_cache.save_later(key, arrays),
                       chains=chains)


def samples_per_pixel(snapshot: Snapshot) -> bool:
    """Whether a surface may sample the world's specular per pixel (World Specular: Sampled, the
    scene's or a material's own): those read the chains. (Any model: a model that does not
    sample only makes the chains a little early.)"""
    return snapshot.settings.environment_samples > 0 or any(
        m.environment_samples > 0 for m in snapshot.materials.values())


class EnvironmentPass(Pass):
    """The world's light for this frame's shading (``frame.scene.environment``): nothing for a
    black world, a constant for a world without images, else the precomputed maps, shared
    through the program library by content."""

    def run(self, frame: Frame, _spec) -> bool:
        world = frame.snapshot.world
        kind = programs.environment_kind(world)
        if not kind:
            frame.scene.environment = None
        elif kind == "UNIFORM":
            frame.scene.environment = gpu_library.LIBRARY.environment(
                env.field_key(world.lighting), lambda: _uniform(world.lighting))
        else:
            chains = samples_per_pixel(frame.snapshot)
            suns = bool(world.suns)
            maps = gpu_library.LIBRARY.environment(
                env.field_key(world.lighting, world.threshold),
                lambda: _cached_or_built(frame, world.lighting, world.threshold, suns, chains))
            if chains and maps.chain is None:  # built or read without them
                _add_chains(frame, world.lighting, suns, maps)
            frame.scene.environment = maps
        return True
