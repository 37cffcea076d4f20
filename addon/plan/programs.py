"""Shader programs specialised to a scene: feature set -> defines -> GLSL source, and the
uniform-buffer packers. Pure Python (no ``bpy``/``gpu``): the renderer feeds the results to
``gpu.types.GPUShaderCreateInfo``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from ..materials import codegen
from ..materials.codegen import glsl_dir
from ..materials.surface import GraphProgram
from ..reference import closures, subsurface, thin_film
from ..reference.multiscatter import MS_SIZE, S_SIZE
from ..reference.sheen import SIZE as SHEEN_SIZE
from ..scene.matrices import invert
from ..scene.snapshot import (
    CLOSURE_LOBES,
    LIGHT_KINDS,
    LOBES,
    MAX_ENVIRONMENT_IMAGES,
    MODELS,
    THIN_FILM_RULES,
    MaterialParams,
    Snapshot,
    Terms,
    World,
    normal_matrices,
)
from . import light_tiles, shadows

#: Sides of the linearly transformed cosines' table and of its horizon-clipping sphere table
#: (addon/reference/ltc.py, glsl/ltc.glsl), in texels.
LTC_SIZE = 64
LTC_SPHERE_SIZE = 32
#: Objects per uniform block of object data (128 bytes each: 32 KiB, within every GPU's limit);
#: a scene with more objects uses several blocks, a draw names its object by block and index.
OBJECT_BLOCK = 256
#: Shade the lights in groups, one loop per kind with and without a shadow map (``Features.
#: light_groups``; the same image as one loop over them all; tests turn it off to compare).
LIGHT_GROUPS = True
#: A scene of at most this many lights, without light culling, shades each by its own call with
#: its kind and index constants (``Features.light_sequence``): on the CPU rasteriser a loop's
#: light index differs per pixel for all the compiler knows, so each read of the light's data is
#: a gather, one per pixel; a constant index reads once for every pixel. Measured against the
#: loops, neither with light culling (640 x 360, fenced minima in one process): the shading
#: passes of long_tail, softbox, roughness_sweep, material_grid and fresnel 0.96-0.98x; the
#: frames within noise (docs/bench/light_sequence.md). Each light holds its kind's code, and the
#: CPU rasteriser's compiler takes superlinearly longer: softbox's area lights unrolled, its
#: first render without the shader cache +70 ms for two, +480 ms for three, +19 s for four
#: (four point lights: no longer, but 0.92-0.96x; four spots +180-240 ms for 0.98x).
UNROLLED_LIGHTS = 2

MODEL_FILES = {
    "BLINN_PHONG": "model_blinn_phong.glsl",
    "PHONG": "model_phong.glsl",
    "PBR": "model_pbr.glsl",
}
FRAGMENT_LIBRARY = ("common.glsl", "surface.glsl", "brdf.glsl", "lights.glsl", "environment.glsl", "ibl.glsl")
PBR_LIBRARY = ("anisotropy.glsl", "multiscatter.glsl", "pbr_terms.glsl", "thin_film.glsl", "principled.glsl",
               "ltc.glsl", "subsurface.glsl",
               "transmission.glsl", "closures.glsl")
#: The screen-space refraction (glsl/transmission.glsl, passes.RefractionPass): the most levels of
#: the blurred copy of what is behind the glass (each half the last's size), the most steps a
#: refracted ray is marched in across the screen and the pixels of its way across per step (a ray
#: along the view takes one: on a glass plane filling the view 48 steps made the pass 40x the frame,
#: 2 pixels per step measure the same errors), the bisections refining where it meets a surface
#: and the steps settling it onto that surface (the depth at the texel it reached), and the blur's
#: scale: a level's texels per pixel of the refracted lobe's radius.
REFRACTION_LEVELS = 7
REFRACTION_STEPS = 48
REFRACTION_STRIDE = 2.0
REFRACTION_BISECTIONS = 6
REFRACTION_SETTLE = 3
REFRACTION_BLUR = 1.0
#: The roughness (alpha) a light seen through a closed object's far face is taken at, over the
#: surface's: the two rough crossings' spreads together (two GGX slopes summed peak as one of
#: sqrt(3) alpha: glsl/transmission.glsl's transmission_exit_light).
REFRACTION_EXIT_ALPHA = 1.7320508
#: The spread of the incidence angles at which rough glass's far face is crossed from inside, radians
#: per unit of alpha and of the turn a microfacet's tilt gives the refracted ray
#: (glsl/transmission.glsl's transmission_inner_spread; fitted to a Monte-Carlo integration of Cycles'
#: two compensated rough crossings of a slab, tests/test_transmission_paths.py).
REFRACTION_EXIT_SPREAD = 1.25
#: The Roughness up to which a glass is smooth: the refraction reads what is behind it unblurred
#: (the shading's roughness floor, glsl/common.glsl's MIN_PERCEPTUAL_ROUGHNESS), and a frame whose
#: glass is all smooth makes no blurred levels.
REFRACTION_SMOOTH = 0.045
#: How far (m, along the view) behind an opaque surface a refracted ray may pass at a step and
#: still meet it (farther, it passed behind a nearer object and goes on), beyond two steps' length.
REFRACTION_THICKNESS = 0.1


def refraction_layout(width: int, height: int,
                      levels: int = REFRACTION_LEVELS) -> tuple[list, list, tuple[int, int]]:
    """The copy of what is behind the glass (passes.RefractionPass) for a ``width`` x ``height``
    target: its levels' sizes (level 0 the target's, each next half the last's, rounded up, at most
    ``levels``), their rectangles (x, y, width, height) in one texture (level 0 at the origin, the
    others stacked to its right) and that texture's size."""
    sizes = [(width, height)]
    while len(sizes) < min(levels, REFRACTION_LEVELS) and max(sizes[-1]) > 1:
        w, h = sizes[-1]
        sizes.append((-(-w // 2), -(-h // 2)))
    rects, y = [(0, 0, width, height)], 0
    for w, h in sizes[1:]:
        rects.append((width, y, w, h))
        y += h
    return sizes, rects, (width + (sizes[1][0] if len(sizes) > 1 else 0), max(height, y))


def pack_refraction(inverse_view_projection: np.ndarray, rects, size: tuple[int, int],
                    world_alpha: float = 1.0) -> bytes:
    """The RefractionData block (glsl/uniforms.glsl) of ``refraction_layout``'s rectangles and size,
    and the alpha the world leaves where it is behind the glass."""
    rows = np.zeros((REFRACTION_LEVELS, 4), np.float32)
    rows[:len(rects)] = rects
    info = np.array([len(rects), *size, REFRACTION_THICKNESS], np.float32)
    world = np.array([world_alpha, 0.0, 0.0, 0.0], np.float32)
    return np.concatenate([_mat(inverse_view_projection), rows.ravel(), info, world]).tobytes()


#: How the world lights a program: "" not at all (a black world), "UNIFORM" a constant radiance,
#: "MAP" environment images (glsl/ibl.glsl).
ENVIRONMENTS = ("", "UNIFORM", "MAP")


@lru_cache(maxsize=None)
def read_glsl(name: str) -> str:
    return (glsl_dir() / name).read_text(encoding="utf-8")


def light_slots(count: int) -> int:
    """Round a light count up to a power of two so adding one light rarely recompiles."""
    size = 1
    while size < count:
        size *= 2
    return size


@dataclass(frozen=True)
class Features:
    """What a scene (or one material in it) needs from the shading program; its defines key the
    program cache. Only the terms the model uses are kept, so equivalent choices share a program."""

    model: str = "PBR"
    max_lights: int = 1
    light_kinds: frozenset[str] = frozenset()
    terms: Terms = Terms()
    half_target: bool = False  # drawing into RGBA16F: cap radiance at 65504
    peel: bool = False  # a depth-peeling pass over the partly transparent surfaces
    environment: str = ""  # the world's light: one of ENVIRONMENTS (the physically based model)
    env_diffuse: str = "MAP"  # its irradiance: "MAP" (exactly convolved) or "SH9"
    env_samples: int = 0  # > 0: specular sampled per pixel with this many samples, not split sum
    ambient_world: bool = False  # the empirical models' ambient term is the world's irradiance
    occlusion: bool = False  # the world's light occluded by screen-space ambient occlusion
    shadow_layers: int = 0  # shadow-map layers the uniform block holds (0: no shadows)
    shadow_size: int = 0  # their texels per side
    soft_shadows: bool = False  # penumbrae from the lights' sizes
    light_tiles: bool = False  # loop over the fragment's screen tile's lights (light_tiles.py)
    light_block: bool = False  # the lights read from a uniform block (``light_block_fits``), not a texture
    sphere_lights: bool = False  # a point or spot light has a radius (the physically based model)
    #: a point or spot light may have a radius (its falloff 1 / (d^2 + r^2) in every model); off,
    #: the program reads no light's shape (True unless the scene says otherwise)
    light_radii: bool = True
    #: an area light may have a Spread under 180 degrees; off, the program holds no spread code
    area_spread: bool = True
    #: an area light may be a disk or an ellipse (a 16-gon); off, the program's area lights are
    #: rectangles, whose corners need no sine and cosine (softbox's shading 0.93x)
    area_ellipse: bool = True
    #: the groups of lights the program loops over, one loop each (``light_order`` lists the
    #: lights by group): a kind, "_SHADOWED" where those lights have a shadow map. A loop holds
    #: its kind's code alone, and the shadow lookup only with "_SHADOWED": both sides of an ``if``
    #: run on this machine's rasteriser (glsl/README.md), so a point light among area lights would
    #: pay the area light's code, and a light without a map the lookup. None: every kind of
    #: ``light_kinds``, with and (with shadows) without maps. Empty: one loop over every light
    #: (``LIGHT_GROUPS`` off)
    light_groups: frozenset[str] | None = None
    #: each light's group (its index in ``LIGHT_GROUP_ORDER``), in ``light_order``: where not
    #: empty, the program shades exactly these lights, each by its own call (``UNROLLED_LIGHTS``),
    #: and no loop; empty: the loops of ``light_groups``
    light_sequence: tuple[int, ...] = ()
    #: shaded deferred: a full-screen pass over the G-buffer's pixels of this group (passes.OpaquePass),
    #: not the surfaces' own fragments; opaque surfaces without image maps or node graphs only
    deferred: bool = False
    #: the material's compiled node graph (``materials.surface.GraphProgram``: one program per
    #: structure), evaluated per fragment; ``graph_keep``: the inputs the material's own values
    #: keep (``MaterialParams.graph_keep``)
    graph: GraphProgram | None = None
    graph_keep: frozenset[str] = frozenset()
    #: the Principled BSDF's lobes beyond its base the material draws (``snapshot.LOBES``: each a
    #: define, SL_<LOBE>); the physically based model's Principled set alone draws them
    lobes: frozenset[str] = frozenset()
    #: the Cycles rule a Thin Film follows (``snapshot.THIN_FILM_RULES``: the reader's Blender's);
    #: 5.0's where the program draws no film (programs of other rules are the same program)
    thin_film_rule: str = "CYCLES_5"

    def __post_init__(self):
        if self.model not in MODELS:
            raise ValueError(f"unknown shading model {self.model!r}; expected one of {MODELS}")
        unknown = set(self.light_kinds) - set(LIGHT_KINDS)
        if unknown:
            raise ValueError(f"unknown light kinds {sorted(unknown)}")
        if self.environment not in ENVIRONMENTS:
            raise ValueError(f"unknown environment {self.environment!r}; expected one of {ENVIRONMENTS}")
        if self.model == "PBR":
            object.__setattr__(self, "ambient_world", False)
        elif not self.ambient_world:  # the empirical models see the world only through their ambient term
            object.__setattr__(self, "environment", "")
        if not {"POINT", "SPOT"} & set(self.light_kinds):
            object.__setattr__(self, "light_radii", False)  # no light that could have one
        if "AREA" not in self.light_kinds:
            object.__setattr__(self, "area_spread", False)
            object.__setattr__(self, "area_ellipse", False)
        if self.model != "PBR" or not {"POINT", "SPOT"} & set(self.light_kinds):
            object.__setattr__(self, "sphere_lights", False)  # shaded by their irradiance alone
        if self.peel or not self.environment:  # a transparent surface lies in front of what the
            object.__setattr__(self, "occlusion", False)  # occlusion pass saw
        if self.peel or self.graph is not None:
            object.__setattr__(self, "deferred", False)
        if self.graph is None:
            object.__setattr__(self, "graph_keep", frozenset())
        if not self.shadow_layers:
            object.__setattr__(self, "shadow_size", 0)
            object.__setattr__(self, "soft_shadows", False)
        if self.light_groups is None:
            groups = set(self.light_kinds)
            if self.shadow_layers:
                groups |= {kind + "_SHADOWED" for kind in self.light_kinds}
            object.__setattr__(self, "light_groups", frozenset(groups))
        elif not self.shadow_layers:  # no light has a map
            object.__setattr__(self, "light_groups", frozenset(
                group.removesuffix("_SHADOWED") for group in self.light_groups))
        if self.light_tiles:  # a tile's own list of lights: loops
            object.__setattr__(self, "light_sequence", ())
        elif not self.shadow_layers:
            object.__setattr__(self, "light_sequence", tuple(
                LIGHT_GROUP_ORDER.index(LIGHT_GROUP_ORDER[g].removesuffix("_SHADOWED"))
                for g in self.light_sequence))
        if self.model == "PBR" and self.terms.principled:
            canonical = Terms(principled=True)  # one fixed set: exact Fresnel, GGX, Smith, layered
        elif self.model == "PBR":
            canonical = replace(self.terms, normalized_blinn_phong=False)
        elif self.model == "BLINN_PHONG":
            canonical = Terms(normalized_blinn_phong=self.terms.normalized_blinn_phong)
        else:
            canonical = Terms()
        object.__setattr__(self, "terms", canonical)
        unknown = set(self.lobes) - set(LOBES)
        if unknown:
            raise ValueError(f"unknown lobes {sorted(unknown)}; expected some of {LOBES}")
        if not (self.model == "PBR" and self.terms.principled):  # the other sets have none of them
            object.__setattr__(self, "lobes", frozenset())
        if {"TRANSLUCENT", "SUBSURFACE"} & set(self.lobes):  # the subsurface measures the surface's
            object.__setattr__(self, "deferred", False)  # curvature from screen derivatives
        if self.peel and "TRANSMISSION" in self.lobes:  # a peeling pass draws no glass (a partly
            object.__setattr__(self, "lobes", self.lobes - {"TRANSMISSION"})  # transparent one: refracted)
        if "TRANSMISSION" in self.lobes:  # drawn over the opaque scene (passes.RefractionPass), which
            object.__setattr__(self, "deferred", False)  # the occlusion pass saw without it
            object.__setattr__(self, "occlusion", False)
        if self.thin_film_rule not in THIN_FILM_RULES:
            raise ValueError(f"unknown thin film rule {self.thin_film_rule!r}; "
                             f"expected one of {THIN_FILM_RULES}")
        if "THIN_FILM" not in self.lobes:
            object.__setattr__(self, "thin_film_rule", "CYCLES_5")

    @classmethod
    def from_snapshot(cls, snapshot: Snapshot, model: str | None = None,
                      material: MaterialParams | None = None, half_target: bool = False,
                      shadow_layers: int | None = None,
                      first_layer: tuple[int, ...] | None = None,
                      light_culling: bool | None = None) -> Features:
        """The scene's features, for ``model`` or for ``material`` (its model and term overrides).
        ``shadow_layers`` and ``first_layer``: the frame's shadow-map layers and each light's
        first when the caller planned them (else given by ``shadows.assign``); ``light_culling``:
        whether light culling pays, as the caller found it (else ``uses_light_tiles`` without
        the scene's bounds)."""
        terms = snapshot.settings.terms
        if shadow_layers is None:
            first_layer, shadow_layers = shadows.assign(snapshot)[:2]
        elif first_layer is None:
            first_layer = shadows.assign(snapshot)[0] if shadow_layers else (-1,) * len(snapshot.lights)
        env_samples = snapshot.settings.environment_samples
        if material is not None:
            model = material.model or model
            if material.environment_samples >= 0:  # the material's own World Specular
                env_samples = material.environment_samples
            terms = material.terms or terms.override(fresnel=material.fresnel, ndf=material.ndf,
                                                     visibility=material.visibility,
                                                     diffuse=material.diffuse)
        tiles = uses_light_tiles(snapshot) if light_culling is None else light_culling
        sequence = () if tiles else light_sequence(snapshot.lights, first_layer)
        return cls(
            model=model or snapshot.settings.model,
            max_lights=light_slots(len(snapshot.lights)),
            light_kinds=frozenset(light.kind for light in snapshot.lights),
            sphere_lights=any(light.kind in ("POINT", "SPOT") and light.sphere_radius > 0.0
                              for light in snapshot.lights),
            light_radii=any(light.kind in ("POINT", "SPOT") and light.sphere_radius > 0.0
                            for light in snapshot.lights),
            area_spread=any(light.kind == "AREA" and light.spread_terms[1] > 0.0
                            for light in snapshot.lights),
            area_ellipse=any(light.kind == "AREA" and light.ellipse for light in snapshot.lights),
            terms=terms,
            half_target=half_target,
            graph=material.graph.program if material is not None and material.graph is not None else None,
            graph_keep=material.graph_keep if material is not None else frozenset(),
            lobes=material.lobes if material is not None else frozenset(),
            thin_film_rule=material.thin_film_rule if material is not None else "CYCLES_5",
            environment=environment_kind(snapshot.world),
            env_diffuse=snapshot.settings.environment_diffuse,
            env_samples=env_samples,
            ambient_world=snapshot.settings.ambient_world,
            occlusion=snapshot.settings.world_occlusion,
            shadow_layers=light_slots(shadow_layers) if shadow_layers else 0,
            shadow_size=int(snapshot.settings.shadow_map_size),
            # the penumbrae's code only where a light with a map has a size (a test costs its body)
            soft_shadows=snapshot.settings.soft_shadows and any(
                shadows.penumbra_size(light) > 0.0 for light, first in zip(snapshot.lights, first_layer)
                if first >= 0),
            light_tiles=tiles,
            light_block=light_block_fits(light_slots(len(snapshot.lights))),
            light_groups=frozenset(map(light_group, snapshot.lights, first_layer) if LIGHT_GROUPS else ()),
            light_sequence=sequence,
        )

    @property
    def holdout(self) -> bool:
        """A node graph holding a Holdout (codegen's closure_holdout): its surface cuts the render's
        alpha by the Holdout's weight; peeled, its layers carry that share apart (``SL_PEEL``'s
        second output, composited by ``under_source(holdout=True)``)."""
        return self.graph is not None and "closure_holdout(" in self.graph.source

    @property
    def uses_ltc(self) -> bool:
        """The program shades area and sphere lights' specular lobe by linearly transformed
        cosines (glsl/ltc.glsl): it samples ``ltc_table``, and ``ms_table`` for the lobe's
        magnitude."""
        return self.model == "PBR" and ("AREA" in self.light_kinds or self.sphere_lights)

    @property
    def uses_albedo_table(self) -> bool:
        """The program samples ``ms_table`` (multiple-scattering compensation, Principled set, the
        magnitude of area lights' specular lobe)."""
        return self.model == "PBR" and (self.terms.multiscatter or self.terms.layered or self.uses_ltc)

    @property
    def uses_env_chain(self) -> bool:
        """The program samples ``env_chain`` (the world's specular sampled per pixel)."""
        return self.environment == "MAP" and self.env_samples > 0 and self.model == "PBR"

    @property
    def uses_split_table(self) -> bool:
        """The program samples ``split_table`` (the world's split-sum specular)."""
        return self.environment != "" and self.model == "PBR"

    @property
    def uses_sheen_table(self) -> bool:
        """The program samples ``sheen_table`` (the Principled BSDF's sheen, addon/reference/sheen.py)."""
        return "SHEEN" in self.lobes

    @property
    def uses_thin_film_table(self) -> bool:
        """The program samples ``thin_film_table`` (the Principled BSDF's Thin Film by Cycles 5.0's
        rule, addon/reference/thin_film.py; 4.x's evaluates its Gaussian fit instead)."""
        return "THIN_FILM" in self.lobes and self.thin_film_rule == "CYCLES_5"

    @property
    def uses_subsurface_table(self) -> bool:
        """The program samples ``subsurface_table`` (the subsurface's random walk,
        addon/reference/subsurface.py's walk_table)."""
        return "SUBSURFACE" in self.lobes

    @property
    def uses_s_table(self) -> bool:
        """The program samples ``s_table`` (the layering estimate: the Principled set, the LAYERED
        diffuse)."""
        return self.model == "PBR" and self.terms.layered

    def defines(self) -> tuple[tuple[str, str], ...]:
        out = [("SL_MAX_LIGHTS", str(self.max_lights)), ("SL_MODEL_" + self.model, "1")]
        out += [("SL_HAS_" + kind, "1") for kind in sorted(self.light_kinds)]
        t = self.terms
        if self.model == "PBR" and t.principled:
            out += [("SL_PRINCIPLED", "1"), ("SL_LAYERS", "1"), ("SL_MS_SIZE", str(MS_SIZE)),
                    ("SL_S_SIZE", str(S_SIZE))]
            out += [("SL_" + lobe, "1") for lobe in sorted(self.lobes)]
            if self.lobes & CLOSURE_LOBES:  # glsl/closures.glsl's lobes
                out.append(("SL_CLOSURE_BSDFS", "1"))
            if self.uses_sheen_table:
                out.append(("SL_SHEEN_SIZE", str(SHEEN_SIZE)))
            if "THIN_FILM" in self.lobes and self.thin_film_rule == "CYCLES_4":
                out += [("SL_THIN_FILM_CYCLES_4", "1"), ("SL_THIN_FILM_RGB", thin_film_rgb_source())]
            if self.uses_subsurface_table:  # the walk table's nodes and the entry's quadrature
                out += [("SL_WALK_ALBEDOS", str(subsurface.WALK_ALBEDO_NODES)),
                        ("SL_WALK_GS", str(subsurface.WALK_G_NODES)),
                        ("SL_WALK_MUS", str(subsurface.WALK_MU_NODES)),
                        ("SL_WALK_RINGS", str(subsurface.WALK_ENTRY_RINGS)),
                        ("SL_WALK_SPOKES", str(subsurface.WALK_ENTRY_SPOKES))]
        elif self.model == "PBR":
            out += [("SL_FRESNEL_" + t.fresnel, "1"), ("SL_NDF_" + t.ndf, "1"),
                    ("SL_VISIBILITY_" + t.visibility, "1"), ("SL_DIFFUSE_" + t.diffuse, "1")]
            if t.multiscatter:
                out += [("SL_MULTISCATTER", "1"), ("SL_MS_SIZE", str(MS_SIZE))]
            if t.diffuse == "LAYERED":  # the layering estimate of principled.glsl
                out += [("SL_LAYERS", "1"), ("SL_S_SIZE", str(S_SIZE))]
                if not t.multiscatter:
                    out.append(("SL_MS_SIZE", str(MS_SIZE)))
        if self.sphere_lights:
            out.append(("SL_SPHERE_LIGHTS", "1"))
        if self.light_radii:
            out.append(("SL_LIGHT_RADII", "1"))
        if self.area_spread:
            out.append(("SL_AREA_SPREAD", "1"))
        if self.area_ellipse:
            out.append(("SL_AREA_ELLIPSE", "1"))
        if self.uses_ltc:
            out += [("SL_LTC", "1"), ("SL_LTC_SIZE", str(LTC_SIZE)),
                    ("SL_LTC_SPHERE_SIZE", str(LTC_SPHERE_SIZE))]
            if ("SL_MS_SIZE", str(MS_SIZE)) not in out:
                out.append(("SL_MS_SIZE", str(MS_SIZE)))
        if t.normalized_blinn_phong:
            out.append(("SL_BLINN_PHONG_NORMALIZED", "1"))
        if self.half_target:
            out.append(("SL_HALF_TARGET", "1"))
        if self.peel:
            out.append(("SL_PEEL", "1"))
        if self.deferred:
            out.append(("SL_DEFERRED", "1"))
        if self.ambient_world and self.environment:
            out.append(("SL_AMBIENT_WORLD", "1"))
        if self.occlusion:
            out.append(("SL_ENV_OCCLUSION", "1"))
        if self.light_tiles:
            out += [("SL_LIGHT_TILES", "1"), ("SL_LIGHT_LIST_WIDTH", str(light_tiles.LIST_WIDTH))]
        if self.light_block:
            out.append(("SL_LIGHT_BLOCK", "1"))
        if self.shadow_layers:
            out += [("SL_SHADOWS", "1"), ("SL_SHADOW_LAYERS", str(self.shadow_layers)),
                    ("SL_SHADOW_SIZE", str(self.shadow_size))]
            if self.soft_shadows:
                out.append(("SL_SOFT_SHADOWS", "1"))
        if self.light_sequence:
            out.append(("SL_LIGHT_SEQUENCE", sequence_source(self.light_sequence)))
        else:
            out += [("SL_LIGHTS_" + group, "1") for group in sorted(self.light_groups)]
            if not self.light_groups:
                out.append(("SL_ONE_LIGHT_LOOP", "1"))
        if self.environment:
            out.append(("SL_ENV_" + self.environment, "1"))
            if self.environment == "MAP" and self.env_diffuse == "SH9":
                out.append(("SL_ENV_DIFFUSE_SH9", "1"))
            if self.uses_env_chain:
                out += [("SL_ENV_SAMPLES", str(self.env_samples)), ("SL_CHAIN", "1")]
            if ("SL_MS_SIZE", str(MS_SIZE)) not in out:
                out.append(("SL_MS_SIZE", str(MS_SIZE)))
        if self.graph is not None:
            out += graph_defines(self.graph)
            out += [("SL_KEEP_" + name.upper(), "1") for name in sorted(self.graph_keep)]
        return tuple(sorted(out))


@lru_cache(maxsize=1)
def thin_film_rgb_source() -> str:
    """SL_THIN_FILM_RGB: Cycles 4.2 and 4.5's XYZ -> RGB of the thin film's sum (reference/thin_film.py's
    gaussian_rgb of Blender 4.x's XYZ_TO_RGB_4), a GLSL mat3 (by columns)."""
    m = thin_film.engine_sensitivity("CYCLES_4")
    return "mat3(" + ", ".join(f"{float(x):.9g}" for x in np.asarray(m).T.ravel()) + ")"


def mesh_vertex() -> str:
    """The mesh programs' vertex stage: glsl/mesh.vert.glsl after the varyings it writes."""
    return read_glsl("mesh_varyings.glsl") + "\n" + read_glsl("mesh.vert.glsl")


#: Triangles per row of a mesh's triangle texture (``gpu_scene.triangle_texture``: three texels each,
#: its corners), for graphs reading the fragment's triangle (Parametric, Wireframe).
TRIANGLE_ROW = 1024


def graph_defines(g: GraphProgram) -> list[tuple[str, str]]:
    """What a program holding compiled graph ``g`` defines: its key, its constants' count, the
    optional GraphInputs fields it reads, and how its attributes reach the fragment stage."""
    out = [("SL_GRAPH", g.key), ("SL_GRAPH_CONSTANTS", str(g.constants)),
           ("GRAPH_ATTRIBUTES", str(max(g.attributes, 1)))]
    out += [("SL_GRAPH_" + field.upper(), "1") for field in sorted(g.uses)]
    if g.uniform_attributes:
        out.append(("SL_GRAPH_UNIFORM_ATTRIBUTE_COUNT", str(g.uniform_attributes)))
    if g.bump_shadowing:
        out.append(("SL_BUMP_SHADOWING_" + g.bump_shadowing, "1"))
    if g.oren_nayar:
        out.append(("SL_OREN_NAYAR_" + g.oren_nayar, "1"))
    if "triangle" in g.uses:  # the fragment's triangle's corners, from the draw's triangle texture
        out.append(("SL_GRAPH_TRIANGLE_ROW", str(TRIANGLE_ROW)))
    if g.attributes:
        passes = " ".join(f"graph_attribute{k} = attr{k};" for k in range(g.attributes))
        out.append(("SL_PASS_ATTRIBUTES", passes))
        reads = [f"graph_tangent_to_world(graph_attribute{k})" if kind == "TANGENT" else f"graph_attribute{k}"
                 for k, kind in enumerate(g.attribute_kinds)]
        # a deformed mesh's undeformed positions (surface.with_orco) give Generated
        orco = [f" g.generated = graph_generated(graph_attribute{k}.xyz);" if kind == "ORCO" else ""
                for k, kind in enumerate(g.attribute_kinds)]
        out.append(("SL_GRAPH_ATTRIBUTE_READS", " ".join(f"g.attributes[{k}] = {read};{orco[k]}"
                                                         for k, read in enumerate(reads))))
    return out


#: The AOV program of a material without that AOV: zeros (Cycles writes nothing there).
ZERO_AOV = GraphProgram("zero-aov", "vec4 graph_table(int i) { return GRAPH_CONST(i); }\n"  # (the library's)
                        "void material_aov(GraphInputs g, out vec4 color, out float value)\n"
                        "{\n  color = vec4(0.0);\n  value = 0.0;\n}\n", 1, 0, 0, frozenset())


@lru_cache(maxsize=64)
def aov_source(graph: GraphProgram, value: bool) -> ProgramSource:
    """The program writing a material's AOV Output (glsl/aov.frag.glsl): its compiled graph
    (``materials.surface.compile_aovs``), a Value AOV's value or a Color AOV's colour."""
    fragment = [read_glsl(name) for name in ("common.glsl", "facing.glsl", "view.glsl",
                                             *codegen.library(graph.source))]
    fragment += ["#define GRAPH_CONST(i) graph.constants[i]", graph.source, read_glsl("graph_surface.glsl"),
                 read_glsl("aov.frag.glsl")]
    defines = graph_defines(graph) + [("SL_OBJECT_BLOCK", str(OBJECT_BLOCK)), ("SL_MAX_LIGHTS", "1")]
    if value:
        defines.append(("SL_AOV_VALUE", "1"))
    return ProgramSource(typedefs=read_glsl("uniforms.glsl"), vertex=mesh_vertex(),
                         fragment="\n".join(fragment), defines=tuple(sorted(defines)))


def environment_kind(world: World) -> str:
    """How ``world`` lights the scene (see ``ENVIRONMENTS``)."""
    if not world.lights:
        return ""
    return "MAP" if World.images(world.lighting) else "UNIFORM"


@dataclass(frozen=True)
class ProgramSource:
    typedefs: str
    vertex: str
    fragment: str
    defines: tuple[tuple[str, str], ...]


@lru_cache(maxsize=64)
def program_source(features: Features) -> ProgramSource:
    fragment = [read_glsl(name) for name in FRAGMENT_LIBRARY]
    if features.model == "PBR":
        fragment += [read_glsl(name) for name in PBR_LIBRARY]
    fragment.append(read_glsl(MODEL_FILES[features.model]))
    fragment.append(read_glsl("view.glsl"))
    fragment.append(read_glsl("light_shading.glsl"))  # after the model: it calls shade_direct
    if not features.deferred:  # reads the object block and the mesh's varyings
        fragment.append(read_glsl("facing.glsl"))
    fragment.append(read_glsl("shadows.glsl"))  # reads the shadow block (SL_SHADOWS)
    if features.graph is not None:  # the node library, then the graph's function
        fragment += [read_glsl(name) for name in codegen.library(features.graph.source)]
        fragment += ["#define GRAPH_CONST(i) graph.constants[i]", features.graph.source,
                     read_glsl("graph_surface.glsl"), read_glsl("bent_normal.glsl")]
    fragment.append(read_glsl("mesh.frag.glsl"))
    return ProgramSource(
        typedefs=read_glsl("uniforms.glsl") + "\n" + read_glsl("chain_data.glsl"),
        vertex=(read_glsl("deferred_depth.glsl") + "\n" + read_glsl("deferred.vert.glsl")
                if features.deferred else mesh_vertex()),
        fragment="\n".join(fragment),
        defines=tuple(sorted(features.defines() + (("SL_OBJECT_BLOCK", str(OBJECT_BLOCK)),)
                             + refraction_defines(features))),
    )


def refraction_defines(features: Features) -> tuple[tuple[str, str], ...]:
    """The screen-space refraction's constants (glsl/transmission.glsl's, under REFRACTION_LEVELS) for
    a program drawing transmission: those drawn by passes.RefractionPass, which binds what they read."""
    if "TRANSMISSION" not in features.lobes:
        return ()
    return (("REFRACTION_LEVELS", str(REFRACTION_LEVELS)), ("REFRACTION_STEPS", str(REFRACTION_STEPS)),
            ("REFRACTION_STRIDE", repr(float(REFRACTION_STRIDE))),
            ("REFRACTION_BISECTIONS", str(REFRACTION_BISECTIONS)),
            ("REFRACTION_SETTLE", str(REFRACTION_SETTLE)),
            ("REFRACTION_BLUR", repr(float(REFRACTION_BLUR))),
            ("REFRACTION_EXIT_ALPHA", repr(float(REFRACTION_EXIT_ALPHA))),
            ("REFRACTION_EXIT_SPREAD", repr(float(REFRACTION_EXIT_SPREAD))))


@dataclass(frozen=True)
class PostFeatures:
    """The resolve/display pass: supersampling grid, and the tone curve when it displays."""

    samples: int = 1
    tone_mapper: str | None = None  # None: resolve radiance only
    transfer: str = "SRGB"

    def defines(self) -> tuple[tuple[str, str], ...]:
        out = [("SL_SAMPLES", str(self.samples))]
        if self.tone_mapper is not None:  # BLENDER: exposure only, Blender's view transform follows
            out += [("SL_DISPLAY", "1"), ("SL_TONEMAP_" + self.tone_mapper, "1")]
            if self.transfer == "GAMMA22" and self.tone_mapper != "BLENDER":
                out.append(("SL_TRANSFER_GAMMA22", "1"))
        return tuple(sorted(out))


@lru_cache(maxsize=64)
def post_source(features: PostFeatures) -> ProgramSource:
    return ProgramSource(
        typedefs="",
        vertex=read_glsl("post.vert.glsl"),
        fragment="\n".join([read_glsl("tonemap.glsl"), read_glsl("post.frag.glsl")]),
        defines=features.defines(),
    )


@dataclass(frozen=True)
class CompareFeatures:
    """The A|B composite: split view or difference heat map."""

    mode: str = "SPLIT"  # SPLIT or DIFFERENCE
    legend_rows: int = 8

    def defines(self) -> tuple[tuple[str, str], ...]:
        return tuple(sorted([("SL_COMPARE_" + self.mode, "1"), ("SL_LEGEND_ROWS", str(self.legend_rows))]))


@lru_cache(maxsize=8)
def compare_source(features: CompareFeatures) -> ProgramSource:
    return ProgramSource(typedefs="", vertex=read_glsl("post.vert.glsl"),
                         fragment=read_glsl("tonemap.glsl") + "\n" + read_glsl("compare.frag.glsl"),
                         defines=features.defines())


def clear_source_caches() -> None:
    """Forget generated sources (and the GLSL files they were read from)."""
    for cached in (read_glsl, program_source, post_source, compare_source, occupancy_source, under_source,
                   background_source, env_bake_source, env_downsample_source, env_prefilter_source,
                   env_irradiance_source, prepass_source, gtao_source, occlusion_resolve_source,
                   occlusion_depths_source, shadow_source, exposure_source, gbuffer_source,
                   refraction_copy_source):
        cached.cache_clear()


@dataclass(frozen=True)
class BackgroundFeatures:
    """The background pass: how many environment images the camera sees, clamped to [0, 1] for
    the empirical models, capped for half-float targets."""

    images: int = 0
    clamp: bool = False
    half_target: bool = False

    def defines(self) -> tuple[tuple[str, str], ...]:
        out = [("SL_ENV_IMAGES", str(self.images))]
        if self.clamp:
            out.append(("SL_CLAMP", "1"))
        if self.half_target:
            out.append(("SL_HALF_TARGET", "1"))
        return tuple(sorted(out))


@lru_cache(maxsize=16)
def background_source(features: BackgroundFeatures) -> ProgramSource:
    return ProgramSource(typedefs=read_glsl("world_data.glsl"), vertex=read_glsl("background.vert.glsl"),
                         fragment="\n".join(read_glsl(name) for name in
                                            ("common.glsl", "environment.glsl", "background.frag.glsl")),
                         defines=features.defines())


def _full_screen_source(*files: str, defines=(), typedefs: str = "") -> ProgramSource:
    return ProgramSource(typedefs=typedefs, vertex=read_glsl("post.vert.glsl"),
                         fragment="\n".join(read_glsl(name) for name in files),
                         defines=tuple(sorted(defines)))


@lru_cache(maxsize=16)
def env_bake_source(images: int, poles: bool = False) -> ProgramSource:
    """The world's lighting field baked into an equirectangular level; or (``poles``) the means of
    its edge rows."""
    defines = (("SL_ENV_IMAGES", str(images)),) + ((("SL_POLES", "1"),) if poles else ())
    return _full_screen_source("common.glsl", "environment.glsl", "env_bake.frag.glsl", defines=defines,
                               typedefs=read_glsl("world_data.glsl"))


@lru_cache(maxsize=2)
def env_downsample_source(copy: bool = False) -> ProgramSource:
    return _full_screen_source("common.glsl", "env_downsample.frag.glsl",
                               defines=(("SL_COPY", "1"),) if copy else ())


@lru_cache(maxsize=1)
def env_irradiance_source() -> ProgramSource:
    return _full_screen_source("common.glsl", "environment.glsl", "env_irradiance.frag.glsl",
                               typedefs=read_glsl("chain_data.glsl"))


@lru_cache(maxsize=1)
def env_prefilter_source() -> ProgramSource:
    """Every prefiltered level's program (its sample count a uniform: one compile, not one per
    level, most of a first world's set-up on a software rasteriser)."""
    return _full_screen_source("common.glsl", "environment.glsl", "env_prefilter.frag.glsl",
                               defines=(("SL_CHAIN", "1"),), typedefs=read_glsl("chain_data.glsl"))


@lru_cache(maxsize=4)
def prepass_source(back_faces: bool = False, depth_only: bool = False) -> ProgramSource:
    """Depth and normals of the opaque surfaces, their depth alone (``depth_only``), or
    (``back_faces``) the depth of the faces turned away from the viewer (the occlusion pass's
    input)."""
    return ProgramSource(
        typedefs=read_glsl("uniforms.glsl") + "\n" + read_glsl("chain_data.glsl"),
        vertex=mesh_vertex(),
        fragment=read_glsl("facing.glsl") + "\n" + read_glsl("prepass.frag.glsl"),
        defines=(("SL_MAX_LIGHTS", "1"), ("SL_OBJECT_BLOCK", str(OBJECT_BLOCK)))
        + ((("SL_BACK_FACES", "1"),) if back_faces else ())
        + ((("SL_DEPTH_ONLY", "1"),) if depth_only else ()),
    )


@lru_cache(maxsize=1)
def gbuffer_source() -> ProgramSource:
    """The G-buffer of the opaque surfaces shaded deferred (glsl/gbuffer.frag.glsl)."""
    return ProgramSource(
        typedefs=read_glsl("uniforms.glsl") + "\n" + read_glsl("chain_data.glsl"),
        vertex=mesh_vertex(),
        fragment=read_glsl("facing.glsl") + "\n" + read_glsl("gbuffer.frag.glsl"),
        defines=(("SL_MAX_LIGHTS", "1"), ("SL_OBJECT_BLOCK", str(OBJECT_BLOCK))),
    )


#: Slices and steps per horizon of the ambient occlusion pass (glsl/gtao.frag.glsl); the slices
#: are interleaved over 2 x 2 pixels (a multiple of 4).
OCCLUSION_DIRECTIONS, OCCLUSION_STEPS = 8, 12


#: Automatic exposure's reduction stages (glsl/exposure.frag.glsl).
EXPOSURE_STAGES = ("BLOCKS", "ROWS", "COLUMNS")


@lru_cache(maxsize=4)
def exposure_source(stage: str) -> ProgramSource:
    from ..scene import exposure

    return _full_screen_source("exposure.frag.glsl", defines=(
        ("SL_EXPOSURE_" + stage, "1"), ("SL_EXPOSURE_BINS", str(exposure.BINS)),
        ("SL_LOG_MIN", f"{exposure.LOG_MIN:.1f}"), ("SL_LOG_MAX", f"{exposure.LOG_MAX:.1f}")))


#: The occlusion trace's resolution divisor per Settings.occlusion_resolution.
OCCLUSION_SCALES = {"FULL": 1, "HALF": 2}


@lru_cache(maxsize=2)
def gtao_source(scale: int = 1) -> ProgramSource:
    return _full_screen_source("common.glsl", "occlusion.glsl", "gtao.frag.glsl",
                               typedefs=read_glsl("chain_data.glsl"),
                               defines=(("SL_DIRECTIONS", str(OCCLUSION_DIRECTIONS)),
                                        ("SL_STEPS", str(OCCLUSION_STEPS)),
                                        ("SL_OCCLUSION_SCALE", str(scale))))


@lru_cache(maxsize=2)
def occlusion_resolve_source(scale: int = 1) -> ProgramSource:
    return _full_screen_source("occlusion.glsl", "occlusion_resolve.frag.glsl",
                               typedefs=read_glsl("chain_data.glsl"),
                               defines=(("SL_OCCLUSION_SCALE", str(scale)),))


@lru_cache(maxsize=1)
def occlusion_depths_source() -> ProgramSource:
    return _full_screen_source("occlusion.glsl", "occlusion_depths.frag.glsl",
                               typedefs=read_glsl("chain_data.glsl"))


#: Texels per side of a block summarised by one texel of a peeling layer's occupancy map.
OCCUPANCY_BLOCK = 16


@lru_cache(maxsize=1)
def occupancy_source() -> ProgramSource:
    return ProgramSource(typedefs="", vertex=read_glsl("post.vert.glsl"),
                         fragment=read_glsl("occupancy.frag.glsl"),
                         defines=(("SL_BLOCK", str(OCCUPANCY_BLOCK)),))


@lru_cache(maxsize=1)
def group_depth_source() -> ProgramSource:
    fragment = read_glsl("deferred_depth.glsl") + "\n" + read_glsl("group_depth.frag.glsl")
    return ProgramSource(typedefs="", vertex=read_glsl("post.vert.glsl"), fragment=fragment, defines=())


#: The screen-space refraction's copy stages (glsl/refraction_copy.frag.glsl).
REFRACTION_COPY_STAGES = ("COPY", "DOWN", "PACK")


@lru_cache(maxsize=3)
def refraction_copy_source(stage: str) -> ProgramSource:
    return _full_screen_source("refraction_copy.frag.glsl", defines=(("SL_REFRACTION_" + stage, "1"),))


#: The transparency composite's programs (glsl/under.frag.glsl): the layers' radiance and coverage
#: ("UNDER"), also their Holdout share ("UNDER_HOLDOUT").
UNDER_VARIANTS = {"UNDER": (), "UNDER_HOLDOUT": (("SL_HOLDOUT", "1"),)}


@lru_cache(maxsize=None)
def under_source(variant: str = "UNDER") -> ProgramSource:
    return ProgramSource(typedefs="", vertex=read_glsl("post.vert.glsl"),
                         fragment=read_glsl("under.frag.glsl"), defines=UNDER_VARIANTS[variant])


# --- uniform-buffer packing (std140, vec4/mat4 members only; matrices column-major) ---------

LIGHT_KIND_IDS = {kind: float(i) for i, kind in enumerate(LIGHT_KINDS)}


def _mat(m: np.ndarray) -> np.ndarray:
    return np.asarray(m, np.float32).T.reshape(-1)


#: Lobe weights of a normal draw (the ``lobes`` push constant): everything, through the model's
#: final clamp. A light pass draws the same frame with other weights.
ALL_LOBES = (1.0, 1.0, 1.0, 1.0)


def pack_frame(snapshot: Snapshot, view_projection: np.ndarray | None = None,
               tiles: light_tiles.TileLists | None = None,
               group_ends: tuple[int, ...] | None = None, size: tuple[int, int] | None = None,
               samples: int = 1) -> bytes:
    """The FrameData block; ``tiles``: the view's light tiles (light culling); ``group_ends``:
    where each group of ``light_order`` ends (default: each after the last light); ``size``: the
    target's pixels (default: the snapshot's); ``samples``: the target's pixels per image pixel
    along an axis (supersampling: screen-space sizes, a Wireframe's Pixel Size and a Bump's step,
    are the image's pixels)."""
    cam = snapshot.camera
    vp = cam.view_projection if view_projection is None else view_projection
    ambient = snapshot.settings.ambient
    rows = [
        _mat(vp),
        [*cam.position, 1.0 if cam.is_perspective else 0.0],
        [*cam.forward, 0.0],
        [ambient, ambient, ambient, 0.0],
        [float(len(snapshot.lights)), *((float(tiles.tile), float(tiles.columns), float(tiles.header_texels))
                                         if tiles is not None else (0.0, 0.0, 0.0))],
        *np.reshape(group_ends if group_ends is not None else [len(snapshot.lights)] * len(LIGHT_GROUP_ORDER),
                    (2, 4)),
        _mat(cam.view),
        [*(size or (snapshot.width, snapshot.height)), cam.clip_start, float(samples)],
    ]
    return np.concatenate([np.asarray(r, np.float32) for r in rows]).tobytes()


#: Floats per light: LightData's seven vec4 (glsl/uniforms.glsl, LIGHT_TEXELS), one row of the
#: light texture (or one light's span of the lights' uniform block).
LIGHT_FLOATS = 28

#: The bytes a uniform block holds (OpenGL's GL_MAX_UNIFORM_BLOCK_SIZE on the platforms Blender
#: runs on) and whether the lights go in one where they fit (tests turn it off to compare).
UNIFORM_BLOCK_BYTES = 65536
LIGHT_BLOCK = True


def light_block_fits(max_lights: int) -> bool:
    """Whether ``max_lights`` lights (slots) are read from a uniform block (LightBlock,
    glsl/uniforms.glsl) rather than the light texture: up to 512 lights, where the block holds
    them. On the CPU rasteriser a block's load costs less than a texel fetch (no texture
    addressing or format conversion): measured at 1280 x 720, 64 point lights over a plane, each
    evaluated at every pixel 377 -> 253 ms a frame; beyond, the texture holds any number."""
    return LIGHT_BLOCK and max_lights * LIGHT_FLOATS * 4 <= UNIFORM_BLOCK_BYTES


#: The irradiance (W/m^2) of a scene exposed for exposure 0: a grey surface of albedo 0.18 under it
#: shows middle grey, 0.18 (L = rho E / pi).
EXPOSED_IRRADIANCE = math.pi


def scene_irradiance(lights, box) -> float:
    """How bright a scene's lights make it: the irradiance they give together at the centre of
    the drawn scene's box (min, max), each light taken at least half the box's diagonal from it (a
    light inside the scene lights most of it from about that far), a sun by its strength. 0
    without a box."""
    if box is None:
        return 0.0
    lo, hi = (np.asarray(b, np.float64) for b in box)
    centre, half = 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))
    total = 0.0
    for light in lights:
        peak = float(max(light.intensity)) * max(1.0, light.diffuse_factor, light.specular_factor)
        if light.kind == "SUN":
            total += peak
            continue
        total += peak / max(float(np.sum((np.asarray(light.position) - centre) ** 2)), half * half, 1e-12)
    return total


def light_reaches(lights: list, threshold: float, box) -> list:
    """The lights with the reach the Light Threshold gives them: where a light's irradiance falls to
    the threshold, scaled down in a scene dimmer than one exposed for exposure 0 (by its
    ``scene_irradiance`` over EXPOSED_IRRADIANCE; never up), so that what the window drops stays a
    small share of the scene's light however dim its lights are; its Custom Distance where nearer.
    Only in a scene of more than UNROLLED_LIGHTS lights, where light culling can repay the window:
    one or two lights are each shaded by their own call, where culling saves little (hdr's two
    point lights: 1.06x with the lists) and the window costs accuracy (a 1 W lamp 2 m from a wall
    lost half its light there at 0.01 W/m^2); they reach as far as their Custom Distance.
    ``box``: the drawn scene's box (min, max), or a function giving it, called only where a reach
    is set (extraction's box reads every geometry's bounds)."""
    if threshold <= 0.0 or len(lights) <= UNROLLED_LIGHTS:
        return [light if light.influence == light.cutoff else replace(light, influence=light.cutoff)
                for light in lights]
    box = box() if callable(box) else box
    scaled = threshold * min(1.0, scene_irradiance(lights, box) / EXPOSED_IRRADIANCE)
    out = []
    for light in lights:
        factor = max(1.0, light.diffuse_factor, light.specular_factor)
        custom = light.cutoff if math.isfinite(light.cutoff) else None
        reach = light_tiles.influence_radius(light.kind, np.asarray(light.intensity) * factor, scaled, custom)
        out.append(replace(light, influence=min(reach, light.cutoff)))
    return out


def uses_light_tiles(snapshot: Snapshot, box: tuple[np.ndarray, np.ndarray] | None = None) -> bool:
    """Light culling pays: it is on and some light reaches less than everywhere -- less than the
    whole of ``box`` (the drawn scene's world bounds, min and max) where given: a light whose
    reach holds every corner of the box is listed by every tile that shows a surface, and its
    window (glsl/lights.glsl's light_window) shades the same without the lists, whose reads cost
    a gather per pixel and light (the presets' point lights reach past their scenes: without the
    lists their shading passes 0.85-0.95x, roughness_sweep's frame 0.87-0.93x;
    docs/bench/light_sequence.md). The scene's condition: each view's tiles are then made, and
    shaded through where they leave out enough lights (``light_tiles.lists_pay``)."""
    lights = snapshot.lights
    if not snapshot.settings.light_culling:
        return False
    finite = [light for light in lights if math.isfinite(light.influence)]
    if not finite or box is None:
        return bool(finite)
    corners = shadows.box_corners(*box)
    positions = np.array([light.position for light in finite], np.float64).reshape(-1, 3)
    farthest = np.linalg.norm(corners[None] - positions[:, None], axis=2).max(axis=1)
    return bool(np.any(farthest >= np.array([light.influence for light in finite], np.float64)))


#: The groups of lights in the order the programs loop over them (``Features.light_groups``):
#: each kind with a shadow map, then each without (FrameData.group_ends, glsl/uniforms.glsl).
LIGHT_GROUP_ORDER = tuple(kind + "_SHADOWED" for kind in LIGHT_KINDS) + LIGHT_KINDS


def light_group(light, first_layer: int) -> str:
    """The group of ``LIGHT_GROUP_ORDER`` a light belongs to (``first_layer``: its first
    shadow-map layer, -1 for none)."""
    return light.kind + ("_SHADOWED" if first_layer >= 0 else "")


def light_order(lights, first_layer) -> tuple[list[int], tuple[int, ...]]:
    """The order the programs loop over ``lights`` in (``first_layer[i]``: light i's first
    shadow-map layer, -1 for none): by group of ``LIGHT_GROUP_ORDER``, each in the scene's order;
    and where each group ends in it."""
    group = [LIGHT_GROUP_ORDER.index(light_group(light, first)) for light, first in zip(lights, first_layer)]
    order = sorted(range(len(group)), key=group.__getitem__)
    ends = tuple(sum(1 for g in group if g <= i) for i in range(len(LIGHT_GROUP_ORDER)))
    return order, ends


def light_sequence(lights, first_layer) -> tuple[int, ...]:
    """``Features.light_sequence`` of a scene's lights (``first_layer[i]``: light i's first
    shadow-map layer, -1 for none): each one's group in ``light_order``, where there are at most
    UNROLLED_LIGHTS (and lights are shaded in groups); else empty."""
    if not (LIGHT_GROUPS and 0 < len(lights) <= UNROLLED_LIGHTS):
        return ()
    return tuple(sorted(LIGHT_GROUP_ORDER.index(light_group(light, first))
                        for light, first in zip(lights, first_layer)))


def sequence_source(sequence: tuple[int, ...]) -> str:
    """The statements (SL_LIGHT_SEQUENCE, glsl/mesh.frag.glsl) that shade ``light_sequence``'s
    lights: the light at each index by its group's kind, its shadow looked up where the group's
    lights have maps."""
    calls = []
    for index, group in enumerate(sequence):
        name = LIGHT_GROUP_ORDER[group]
        shadowed = "true" if name.endswith("_SHADOWED") else "false"
        calls.append(f"shade_light(c, s, ng, {index}, LIGHT_{name.removesuffix('_SHADOWED')}, {shadowed});")
    return " ".join(calls)


def pack_lights(lights, max_lights: int, first_layer) -> np.ndarray:
    """(max_lights, LIGHT_FLOATS) float32: each light's LightData, a row of the light texture;
    ``first_layer[i]``: light i's first shadow-map layer (``shadows.ShadowPlan``), -1 for none."""
    data = np.zeros((max_lights, LIGHT_FLOATS), np.float32)
    for i, light in enumerate(lights[:max_lights]):
        data[i] = [
            *light.position, LIGHT_KIND_IDS[light.kind],
            *light.direction, light.spot_cos_half,
            *light.intensity, light.spot_smooth,
            light.diffuse_factor, light.specular_factor, 1.0 if light.world else 0.0, first_layer[i],
            light.sphere_radius, 1.0 if light.soft_falloff else 0.0, *light.half_size,
            *light.axis_x, 1.0 if light.ellipse else 0.0,
            1.0 / light.influence ** 2 if math.isfinite(light.influence) else 0.0, *light.spread_terms, 0.0,
        ]
    return data



def pack_shadows(plan: shadows.ShadowPlan, slots: int) -> bytes:
    """The ShadowBlock (glsl/uniforms.glsl) of ``plan``'s layers, ``slots`` entries each."""
    matrices = np.tile(np.eye(4, dtype=np.float32), (2, slots, 1, 1))
    matrices[0, :plan.layers] = plan.matrices
    matrices[1, :plan.layers] = invert(plan.views.astype(np.float64))  # view -> world
    rows = np.zeros((4, slots, 4), np.float32)
    rows[0, :plan.layers] = plan.info
    rows[1, :plan.layers] = plan.origins
    rows[2, :plan.layers] = plan.extents
    # the near plane's centre along the view's right, up and forward (the view's rows 0, 1, -2)
    views = np.asarray(plan.views, np.float64)
    centres = np.asarray(plan.origins, np.float64)[:, :3]
    rows[3, :plan.layers, :3] = np.einsum("lij,lj->li", views[:, :3, :3] * [[1.0], [1.0], [-1.0]], centres)
    return np.concatenate([matrices.transpose(0, 1, 3, 2).ravel(), rows.ravel()]).tobytes()


@lru_cache(maxsize=1)
def shadow_source(orthographic: bool = False) -> ProgramSource:
    """A shadow map's layer: the casters' distances from the light (glsl/shadow.frag.glsl); an
    orthographic layer's (a sun's) is the rasteriser's own depth, written without the fragment
    shader (which lets the rasteriser test depth before shading: ~3x faster maps on llvmpipe)."""
    return ProgramSource(typedefs=read_glsl("uniforms.glsl"), vertex=read_glsl("shadow.vert.glsl"),
                         fragment=read_glsl("shadow.frag.glsl"),
                         defines=(("SL_MAX_LIGHTS", "1"), ("SL_OBJECT_BLOCK", str(OBJECT_BLOCK)))
                         + ((("SL_SHADOW_ORTHOGRAPHIC", "1"),) if orthographic else ()))


@lru_cache(maxsize=64)
def shadow_coverage_source(graph: GraphProgram | None, orthographic: bool, dither: bool) -> ProgramSource:
    """A shadow map's layer for casters whose coverage is tested (glsl/shadow_coverage.glsl): the
    fragments a partly covering surface lets the light through discarded, its coverage the
    compiled ``graph``'s (evaluated at the fragment as the shading programs do: graph_inputs) or,
    without one, the material's Alpha; ``dither``: a share of the texels per coverage, else a
    threshold of 1/2."""
    fragment = []
    defines = [("SL_MAX_LIGHTS", "1"), ("SL_OBJECT_BLOCK", str(OBJECT_BLOCK)), ("SL_SHADOW_COVERAGE", "1")]
    if graph is not None:  # (facing.glsl reads the mesh's varyings: a graph's program hands them on)
        library = codegen.library(graph.source)
        fragment += [read_glsl(name) for name in ("common.glsl", "facing.glsl", *library)]
        fragment += ["#define GRAPH_CONST(i) graph.constants[i]", graph.source,
                     read_glsl("graph_surface.glsl")]
        defines += graph_defines(graph) + [("SL_SHADOW_GRAPH", "1")]
    fragment += [read_glsl("shadow_coverage.glsl"), read_glsl("shadow.frag.glsl")]
    if orthographic:
        defines.append(("SL_SHADOW_ORTHOGRAPHIC", "1"))
    if dither:
        defines.append(("SL_SHADOW_DITHER", "1"))
    vertex = read_glsl("shadow.vert.glsl")
    if graph is not None:  # it hands on what the graph reads of the mesh
        vertex = read_glsl("mesh_varyings.glsl") + "\n" + vertex
    return ProgramSource(typedefs=read_glsl("uniforms.glsl"), vertex=vertex,
                         fragment="\n".join(fragment), defines=tuple(sorted(defines)))


def pack_material(m: MaterialParams) -> bytes:
    complex_ior = m.ior_n is not None and m.ior_k is not None
    rows = [
        [*m.base_color, 1.0],
        [*m.diffuse_color, 1.0],
        [*m.specular_color, 1.0],
        [*m.ambient_color, 1.0],
        [m.roughness, m.metalness, max(m.shininess, 1e-4), m.f0],
        [m.f90, max(m.fresnel_p, 1e-3), 1.0 if complex_ior else 0.0, 0.0],
        [*(m.ior_n if complex_ior else (1.0, 1.0, 1.0)), 0.0],
        [*(m.ior_k if complex_ior else (0.0, 0.0, 0.0)), 0.0],
        [*m.emission, min(max(m.alpha, 0.0), 1.0)],
        [*m.specular_tint, 0.0],
        [m.coat_weight, m.coat_roughness, m.coat_ior, 0.0],
        [*m.coat_tint, 0.0],
        [*(m.sheen_weight * c for c in m.sheen_tint), m.sheen_roughness],
        [0.0, 0.0, 0.0, 0.0],  # the coat's normal: the surface's (a node graph's own is per fragment)
        [m.thin_film_thickness, m.thin_film_ior, 0.0, 0.0],  # (its rule: the program's define)
        [0.0, 0.0, 0.0, 1.0],  # anisotropy: none (an anisotropic BSDF compiles a graph)
        [0.0, 0.0, 0.0, 0.0],  # the translucent lobe: a node graph's alone
        [*subsurface.mean_free_path(m.subsurface_radius, m.subsurface_scale, m.subsurface_method,
                                    m.base_color, m.subsurface_ior), m.subsurface_weight],
        [min(max(m.transmission_weight, 0.0), 1.0), 1.0 if m.transmission_fresnel else 0.0,
         max(m.transmission_ior, 1e-5), 0.0],
        [*m.transmission_tint, 0.0],
        [*m.reflection_tint, 0.0],
        # the closure nodes beside the Principled BSDF (a node graph's, per fragment): the sheen layered
        # over the base, the Principled BSDF's Diffuse Roughness (Oren-Nayar), no velvet, no toon
        [1.0, min(max(m.diffuse_roughness, 0.0), 1.0), 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0],
        [*closures.oren_nayar_ms(m.diffuse_roughness, m.base_color), 0.0],  # its multiple scattering
        [0.0, 0.0, 0.0, 0.0],
        # the subsurface's random walk: Anisotropy, the entry's IOR and roughness, the diffuse entry
        [*subsurface.walk_row(m.subsurface_method, m.ior, m.specular_ior_level, m.subsurface_ior,
                              m.subsurface_anisotropy)],
    ]
    return np.asarray(rows, np.float32).tobytes()


def pack_world(terms, threshold: float = 0.0) -> bytes:
    """A radiance field (``snapshot.World.camera`` or ``.lighting``) as the WorldData block: the
    constant terms' sum and the first ``MAX_ENVIRONMENT_IMAGES`` image terms, each clamped to
    luminance ``threshold`` (0: not clamped)."""
    images = World.images(terms)[:MAX_ENVIRONMENT_IMAGES]
    weight = np.zeros((MAX_ENVIRONMENT_IMAGES, 4), np.float32)
    lookup = np.tile(np.eye(4, dtype=np.float32), (MAX_ENVIRONMENT_IMAGES, 1, 1))
    kind = np.zeros((MAX_ENVIRONMENT_IMAGES, 4), np.float32)
    for i, term in enumerate(images):
        weight[i, :3] = term.weight
        lookup[i] = term.lookup
        kind[i, :3] = (1.0 if term.projection == "MIRROR_BALL" else 0.0, 1.0 if term.closest else 0.0,
                       threshold if term.projection == "EQUIRECTANGULAR" else 0.0)
    constant = np.array([*World.constant(terms), 0.0], np.float32)
    columns = lookup.transpose(0, 2, 1).ravel()  # column-major, as GLSL's mat4
    return np.concatenate([constant, weight.ravel(), columns, kind.ravel()]).tobytes()


def pack_environment(sh: np.ndarray, rects, uniform_radiance, roughness=(), first_clamped: int = 0,
                     atlas_size=(0, 0)) -> bytes:
    """The EnvironmentData block: SH coefficients (9, 3) premultiplied by the cosine kernel's
    band factors, the rectangles of the prefiltered levels (one per ``roughness``, which
    glsl/ibl.glsl's env_level_roughness gives in closed form) and of the irradiance map in a
    texture of ``atlas_size``, the radiance of a world without images."""
    rows = np.zeros((9 + 8 + 1 + 1, 4), np.float32)
    rows[:9, :3] = sh
    if len(rects):
        rows[9:9 + len(rects)] = rects
    rows[17] = (len(roughness), first_clamped, *atlas_size)
    rows[18, :3] = uniform_radiance
    return rows.tobytes()


def pack_objects(items) -> np.ndarray:
    """(blocks, OBJECT_BLOCK * 32) float32: each item's model and normal matrices (column-major;
    the normal matrix's [3][3] is the sign of the model's determinant, -1 for a mirrored object),
    item i at block i // OBJECT_BLOCK, index i % OBJECT_BLOCK; unused entries are zero."""
    blocks = max(-(-len(items) // OBJECT_BLOCK), 1)
    data = np.zeros((blocks * OBJECT_BLOCK, 2, 4, 4), np.float32)
    if items:
        matrices = np.stack([item.matrix for item in items])
        data[:len(items), 0] = matrices.transpose(0, 2, 1)
        data[:len(items), 1] = normal_matrices(matrices).transpose(0, 2, 1)
        data[:len(items), 1, 3, 3] = np.where(np.linalg.det(matrices[:, :3, :3]) < 0.0, -1.0, 1.0)
    return data.reshape(blocks, OBJECT_BLOCK * 32)
