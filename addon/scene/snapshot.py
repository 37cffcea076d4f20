"""The scene snapshot: plain data (numpy arrays and dataclasses) that the renderer draws.

Nothing here imports ``bpy`` or ``gpu``: ``extract.py`` fills these types from a depsgraph, the
renderer and the numpy reference read them, and tests can build them by hand.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from .exposure import AutoExposure
from .matrices import invert


@dataclass(frozen=True)
class Choice:
    """One value of an enumerated setting: its identifier (Blender enum item, ``#define`` suffix),
    label, command-line and preset spelling, and description."""

    id: str
    label: str
    cli: str
    description: str


def enum_items(choices: tuple[Choice, ...]) -> tuple[tuple[str, str, str], ...]:
    """``choices`` as Blender enum items."""
    return tuple((c.id, c.label, c.description) for c in choices)


def cli_names(choices: tuple[Choice, ...]) -> dict[str, str]:
    """Command-line (and preset) name -> identifier."""
    return {c.cli: c.id for c in choices}


#: The shading models, in the order panels, tables and the command line list them.
MODEL_CHOICES = (
    Choice("BLINN_PHONG", "Blinn-Phong", "blinn-phong",
           "Empirical Blinn-Phong model (eq. 1.7), LDR, clamped to [0, 1]"),
    Choice("PHONG", "Phong", "phong", "Original Phong model (eqs. 1.2-1.3), LDR, clamped to [0, 1]"),
    Choice("PBR", "Physically Based", "pbr", "Cook-Torrance GGX specular + Lambert diffuse, HDR"),
)
MODELS = tuple(c.id for c in MODEL_CHOICES)

#: The physically based model's term variants (glsl/pbr_terms.glsl), the first of each the default.
TERM_CHOICES = {
    "fresnel": ("SCHLICK", "SCHLICK_SG", "SCHLICK_GENERAL", "EXACT"),
    "ndf": ("GGX", "BECKMANN"),
    "visibility": ("SMITH_CORRELATED", "SMITH_SEPARABLE", "VCAVITY", "APPROX"),
    "diffuse": ("LAMBERT", "BURLEY", "BURLEY_RENORMALIZED", "OREN_NAYAR", "GGX_HAMMON", "LAYERED"),
}


@dataclass(frozen=True)
class Terms:
    """Which variant of each term the shading programs use."""

    fresnel: str = "SCHLICK"
    ndf: str = "GGX"
    visibility: str = "SMITH_CORRELATED"
    diffuse: str = "LAMBERT"
    multiscatter: bool = False  # specular energy compensation
    normalized_blinn_phong: bool = False
    principled: bool = False  # Blender's Principled BSDF as Cycles evaluates it (overrides the rest)

    def __post_init__(self):
        for family, choices in TERM_CHOICES.items():
            if getattr(self, family) not in choices:
                raise ValueError(f"unknown {family} term {getattr(self, family)!r}; "
                                 f"expected one of {choices}")

    @property
    def lobe(self) -> tuple[str, str]:
        """(distribution, masking-shadowing) of the specular lobe the program evaluates (the
        Principled set: GGX with Smith height-correlated): its tables are looked up by these."""
        return ("GGX", "SMITH_CORRELATED") if self.principled else (self.ndf, self.visibility)

    @property
    def layered(self) -> bool:
        """The program computes the layering estimate of principled.glsl (``SL_LAYERS``): the
        Principled set, and the LAYERED diffuse."""
        return self.principled or self.diffuse == "LAYERED"

    def override(self, **families: str) -> Terms:
        """These terms with the non-empty entries of ``families`` replaced (per-material choices)."""
        changes = {k: v for k, v in families.items() if v}
        return replace(self, **changes) if changes else self
LIGHT_KINDS = ("POINT", "SPOT", "SUN", "AREA")
#: Lights one frame draws (up to 512 in a uniform block, more as rows of the light texture:
#: GPUs hold 16,384 rows at least); further ones are left out with a warning.
MAX_LIGHTS = 16384

#: Fresnel reflectance at normal incidence of a dielectric with IOR 1.5 (most plastics, glass).
DEFAULT_F0 = 0.04


def f0_from_ior(ior):
    """Normal-incidence Fresnel reflectance from air into a medium of index ``ior`` (>= 1; a
    float, or an array of them)."""
    ior = np.maximum(ior, 1.0)
    f0 = ((ior - 1.0) / (ior + 1.0)) ** 2
    return float(f0) if np.ndim(f0) == 0 else f0


def shininess_from_roughness(roughness: float) -> float:
    """Blinn-Phong exponent matching a Beckmann/GGX surface of perceptual roughness ``r``.

    Walter et al. 2007, section 5.2: alpha_p = 2 / alpha_b^2 - 2, with alpha_b = r^2. Clamped to
    [1, 1e4]: below 1 the lobe is wider than a hemisphere cosine, above 1e4 it is a mirror.
    """
    alpha = max(float(roughness), 0.045) ** 2
    return float(min(max(2.0 / (alpha * alpha) - 2.0, 1.0), 1e4))


def roughness_from_shininess(shininess: float) -> float:
    """The inverse of ``shininess_from_roughness``: alpha = sqrt(2 / (s + 2)), r = sqrt(alpha)."""
    alpha = math.sqrt(2.0 / (max(float(shininess), 0.0) + 2.0))
    return float(min(max(math.sqrt(alpha), 0.0), 1.0))


@dataclass(frozen=True)
class MaterialParams:
    """Resolved shading inputs of one material (explicit values or the Principled fallback)."""

    name: str = "Default"
    base_color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    diffuse_color: tuple[float, float, float] = (0.8, 0.8, 0.8)  # Blinn-Phong/Phong c_surface_diff
    specular_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    ambient_color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    roughness: float = 0.5
    metalness: float = 0.0
    shininess: float = 30.0
    f0: float = DEFAULT_F0
    emission: tuple[float, float, float] = (0.0, 0.0, 0.0)  # emitted radiance, W/(m^2 sr)
    alpha: float = 1.0  # coverage: Principled Alpha (1 opaque); drawn blended, sorted, when < 1
    model: str = ""  # a shading model for this material only; "" follows the scene
    f90: float = -1.0  # Schlick's grazing reflectance; < 0: saturate(50 F0)
    fresnel_p: float = 0.2  # eq. 1.13's p; 1/5 is Schlick's fifth power
    ior_n: tuple[float, float, float] | None = None  # conductor complex IOR n + ik (exact Fresnel)
    ior_k: tuple[float, float, float] | None = None
    fresnel: str = ""  # per-material term choices; "" follows the scene
    ndf: str = ""
    visibility: str = ""
    diffuse: str = ""
    terms: Terms | None = None  # the whole term set, fixed for this material (the Auto term set's choice)
    # the world's specular for this material: -1 follows the scene, 0 the split sum, n > 0 the lobe
    # sampled n times per pixel (physically based model, image worlds)
    environment_samples: int = -1
    #: the material's node graph compiled (``materials.surface.MaterialGraph``): its closures'
    #: inputs per fragment replace the values above, but those the user set in the Material panel
    #: (``graph_keep``: "base_color", "metalness", "roughness", "f0", "specular_color", "shininess",
    #: "ambient_color"); None: the values above are the material
    graph: object | None = None
    graph_keep: frozenset[str] = frozenset()
    #: the material's AOV Outputs compiled, by AOV name (``materials.surface.compile_aovs``)
    aovs: tuple[tuple[str, object], ...] = ()
    pass_index: int = 0  # the material's pass index (Object Info's Material Index)
    #: the Principled BSDF's lobes beyond its base (glsl/principled.glsl), drawn by the physically
    #: based model's Principled set, each only in the programs of materials that use it (``lobes``)
    specular_tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    coat_weight: float = 0.0
    coat_roughness: float = 0.03
    coat_ior: float = 1.5
    coat_tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    sheen_weight: float = 0.0
    sheen_roughness: float = 0.5
    sheen_tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    #: the Thin Film (glsl/thin_film.glsl): thickness in nm (0.1 or less: none) and IOR; the Cycles
    #: rule it follows (``THIN_FILM_RULES``: the reader's Blender's)
    thin_film_thickness: float = 0.0
    thin_film_ior: float = 1.33
    thin_film_rule: str = "CYCLES_5"
    #: the subsurface (glsl/subsurface.glsl): Subsurface Weight, Radius, Scale, IOR, Anisotropy and the
    #: method (reference/subsurface.py's METHODS)
    subsurface_weight: float = 0.0
    subsurface_radius: tuple[float, float, float] = (1.0, 0.2, 0.1)
    subsurface_scale: float = 0.05
    subsurface_ior: float = 1.4
    subsurface_anisotropy: float = 0.0
    subsurface_method: str = "RANDOM_WALK"
    #: transmission (glsl/transmission.glsl): the share of the non-metallic part that is glass
    #: (the Principled BSDF's Transmission Weight; 1 for a Glass or Refraction BSDF), its IOR, the
    #: tint of each crossing of the surface (the Principled BSDF's sqrt(Base Color), the Glass and
    #: Refraction BSDFs' Color), the dielectric reflection's tint (the Glass BSDF's Color; 0: the
    #: Refraction BSDF reflects nothing) and whether the Fresnel splits the light between reflection
    #: and transmission (off: the Refraction BSDF transmits all of it)
    transmission_weight: float = 0.0
    transmission_ior: float = 1.5
    transmission_tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    reflection_tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    transmission_fresnel: bool = True
    #: the Principled BSDF's Diffuse Roughness (Blender 4.3 and later): its diffuse base drawn as the
    #: Diffuse BSDF's Oren-Nayar of that roughness (glsl/closures.glsl, DIFFUSE_ROUGHNESS; Lambert
    #: below 1e-5)
    diffuse_roughness: float = 0.0
    #: the Principled BSDF's IOR and Specular IOR Level as set (Cycles' Random Walk subsurface enters
    #: through the dielectric of that IOR as the level adjusts it: reference/subsurface.py's walk_row)
    ior: float = 1.5
    specular_ior_level: float = 0.5

    @property
    def lobes(self) -> frozenset[str]:
        """The lobes of ``LOBES`` the material draws: its compiled graph's (``MaterialGraph.lobes``),
        else those its values turn on (a tint other than white, a weight above 0)."""
        if self.graph is not None:
            return self.graph.lobes
        return lobes_of(self.specular_tint, self.coat_weight, self.sheen_weight, self.sheen_tint,
                        self.thin_film_thickness, subsurface_weight=self.subsurface_weight,
                        transmission_weight=self.transmission_weight,
                        diffuse_roughness=self.diffuse_roughness)


#: Cycles' rules for the Principled BSDF's Thin Film, by the Blender that reads the material (its
#: kernels read side by side: addon/reference/thin_film.py says where they differ): "CYCLES_4", 4.2 to
#: 4.5's (Belcour & Barla's Gaussian fit of the colour matching functions in XYZ, the metal bare, the
#: film's IOR blended to the air's below 30 nm; 4.3 and 4.4, not measured, taken as 4.5), "CYCLES_5"
#: (the CIE 1931 functions' table, the metal under the film too, a 1 nm blend). A program draws one:
#: the define SL_THIN_FILM_CYCLES_4 (plan/programs.py), none for 5.0's.
THIN_FILM_RULES = ("CYCLES_4", "CYCLES_5")
#: The first Blender (major, minor) of each rule but the first
_THIN_FILM_RULE_FROM = ((5, 0),)


def version_rule(rules: tuple[str, ...], starts: tuple[tuple[int, int], ...], version) -> str:
    """The rule of ``rules`` Blender ``version`` (major, minor, ...) follows, ``starts`` the first
    version (major, minor) of each rule but the first."""
    return rules[sum(tuple(version[:2]) >= start for start in starts)]


def thin_film_rule(version) -> str:
    """The rule of ``THIN_FILM_RULES`` the Cycles of Blender ``version`` (major, minor, ...) follows."""
    return version_rule(THIN_FILM_RULES, _THIN_FILM_RULE_FROM, version)


#: The Principled BSDF's lobes beyond its base the programs draw, as their defines name them
#: (SL_<LOBE>).
#: ANISOTROPY: the anisotropic GGX lobe (glsl/anisotropy.glsl) of a Principled, Glossy or Metallic BSDF:
#: only a compiled graph has one (its tangent is per fragment: ``materials.surface._lobes``).
LOBES = ("SPECULAR_TINT", "COAT", "SHEEN", "THIN_FILM", "ANISOTROPY", "TRANSLUCENT", "SUBSURFACE",
         "TRANSMISSION")
#: The closure nodes' lobes beside the Principled BSDF's (glsl/closures.glsl): the Diffuse BSDF's
#: Oren-Nayar roughness (also the Principled BSDF's Diffuse Roughness), the Sheen BSDF's Ashikhmin
#: velvet, the Toon BSDF; a node graph's alone but that roughness.
CLOSURE_LOBES = frozenset({"DIFFUSE_ROUGHNESS", "VELVET", "TOON"})
#: The Glossy BSDF's own Fresnel (its colour) and distributions in the Principled set's specular lobe
#: (glsl/closures.glsl's SL_GLOSSY; a node graph's alone; other sets draw a metal of its colour).
GLOSSY_LOBE = "GLOSSY"
LOBES += tuple(sorted(CLOSURE_LOBES)) + (GLOSSY_LOBE,)
#: The closure nodes' lobes (tests sweep them through node graphs; of them, a Principled BSDF's
#: Diffuse Roughness turns DIFFUSE_ROUGHNESS on too).
NODE_LOBES = CLOSURE_LOBES | {GLOSSY_LOBE}


def lobes_of(specular_tint, coat_weight, sheen_weight, sheen_tint,
             thin_film_thickness=0.0, subsurface_weight=0.0,
             transmission_weight=0.0, diffuse_roughness=0.0) -> frozenset[str]:
    """The lobes a Principled BSDF of these inputs draws: a Specular Tint other than white, a Coat
    Weight above 0, a Sheen Weight and Tint above 0, a Subsurface or Transmission Weight above 0
    (Cycles adds no lobe of weight 0: its CLOSURE_WEIGHT_CUTOFF is 1e-5), a Thin Film Thickness above
    0, a Diffuse Roughness of at least 1e-5 (Cycles' Oren-Nayar; below it Lambert). Scalars here;
    per-point arrays (the twin's) are any of them. (The translucent lobe is a node graph's: its
    Translucent BSDF; the anisotropic lobe too.)"""
    tint = np.asarray(specular_tint, np.float64)
    sheen = np.asarray(sheen_weight, np.float64)[..., None] * np.asarray(sheen_tint, np.float64)
    used = {"SPECULAR_TINT": bool(np.any(tint != 1.0)),
            "COAT": bool(np.any(np.asarray(coat_weight, np.float64) > 1e-5)),
            "SHEEN": bool(np.any(sheen > 1e-5)),
            "THIN_FILM": bool(np.any(np.asarray(thin_film_thickness, np.float64) > 0.0)),
            "SUBSURFACE": bool(np.any(np.asarray(subsurface_weight, np.float64) > 1e-5)),
            "TRANSMISSION": bool(np.any(np.asarray(transmission_weight, np.float64) > 1e-5)),
            "DIFFUSE_ROUGHNESS": bool(np.any(np.asarray(diffuse_roughness, np.float64) >= 1e-5))}
    return frozenset(name for name in LOBES if used.get(name))


#: Objects without a material render with this: Blender's default surface (grey 0.8,
#: roughness 0.5, dielectric F0 0.04), white Blinn-Phong highlights of shininess 30.
DEFAULT_MATERIAL = MaterialParams()


@dataclass
class MeshGeometry:
    """Triangles of one evaluated mesh, object space: per-corner rows (a mesh's face corners,
    Blender's loops) and the triangles as ``indices`` into them, three per triangle.

    ``ranges`` lists ``(material_slot, first_index, index_count)``, sorted by slot.
    """

    key: str
    positions: np.ndarray  # (N, 3) float32
    normals: np.ndarray  # (N, 3) float32, corner normals
    ranges: list[tuple[int, int, int]]
    uvs: np.ndarray | None = None  # (N, 2) float32, the active UV map (None: the mesh has none)
    tangents: np.ndarray | None = None  # (N, 4) float32: tangent xyz, bitangent sign (normal maps)
    indices: np.ndarray | None = None  # (3T,) int32 rows of the triangles' corners; None: 0, 1, 2, ...
    #: the attributes its materials' graphs read, per corner row ((N, 4) float32), by (kind, name)
    #: (``materials.codegen.ATTRIBUTE_KINDS``; an empty name: the mesh's default of that kind)
    attributes: dict[tuple[str, str], np.ndarray] = field(default_factory=dict)
    #: whether its undeformed positions were looked for (a material's graph reads Generated): they
    #: are then ``attributes[materials.surface.ORCO]`` where a deformation moved its vertices
    orco_read: bool = False
    #: +1: a closed surface facing out (every edge between two faces that run along it in opposite
    #: directions, positive volume), -1: closed facing in, 0: open or not known. Seen from outside,
    #: a closed surface's nearest face faces the viewer: shadow maps need draw only such faces.
    winding: int = 0

    def __post_init__(self):
        if self.indices is None:
            self.indices = np.arange(len(self.positions), dtype=np.int32)

    @property
    def triangle_count(self) -> int:
        return len(self.indices) // 3

    @cached_property
    def bounds(self) -> np.ndarray:
        """(2, 3) float32: the object-space box (min, max) of the positions, zeros when empty; once
        per geometry (extraction and the GPU scene both ask, and the geometry memo reuses it)."""
        positions = np.asarray(self.positions, np.float32)
        if not len(positions):
            return np.zeros((2, 3), np.float32)
        # a column at a time: numpy reduces an (n, 3) array over its rows 7-18x slower
        # (2,400 corners 163 -> 23 us, 30,000 1.9 -> 0.1 ms)
        return np.array([[positions[:, i].min() for i in range(3)],
                         [positions[:, i].max() for i in range(3)]], np.float32)

    def per_corner(self, values: np.ndarray) -> np.ndarray:
        """``values`` (one row per corner row) for each triangle's corners in order: (3T, ...)."""
        return values[self.indices]


#: How an image's pixels are stored and sampled (``ImageData.storage``): sRGB-encoded bytes (decoded
#: to linear by the sampler, before filtering), plain bytes, half or full floats.
IMAGE_STORAGE = ("SRGB8", "UNORM8", "HALF", "FLOAT")


@dataclass(eq=False)
class ImageData:
    """An image's pixels as the shaders sample them, read on the thread that reads the scene.

    ``pixels`` is (height, width, 4), bottom row first, alpha as the image stores it: uint8 for
    the byte storages (the image's own bytes, sRGB-encoded for ``SRGB8``), float16 for ``HALF``,
    float32 for ``FLOAT`` (scene-linear).
    """

    key: str
    pixels: np.ndarray
    storage: str = "FLOAT"
    revision: int = 0  # a new number each time the pixels are read (precomputation keys use it)
    # the pixels are a file's (or a packed file's), unedited: what is computed from them may be
    # kept on disk between sessions (addon/plan/world_cache.py); an image being painted is not
    saved: bool = False

    def __post_init__(self):
        if self.storage not in IMAGE_STORAGE:
            raise ValueError(f"unknown image storage {self.storage!r}; expected one of {IMAGE_STORAGE}")

    @property
    def size(self) -> tuple[int, int]:
        return self.pixels.shape[1], self.pixels.shape[0]


#: How an environment image maps directions to texels (Cycles' Environment Texture projections).
ENVIRONMENT_PROJECTIONS = ("EQUIRECTANGULAR", "MIRROR_BALL")
#: Image terms of one radiance field a program evaluates in one pass (more are a warning).
MAX_ENVIRONMENT_IMAGES = 4


@dataclass(eq=False)
class EnvironmentTerm:
    """One Background shader of the world: radiance ``weight`` (colour x strength x the mix
    weights above it) from every direction, or, with an ``image``, ``weight`` times the image
    looked up in direction ``d`` through ``lookup`` (4x4: the Mapping node, the texture-space
    vector is ``lookup @ (d, 1)``) and the image's ``projection``."""

    weight: tuple[float, float, float]
    image: ImageData | None = None
    projection: str = "EQUIRECTANGULAR"
    closest: bool = False
    lookup: np.ndarray = field(default_factory=lambda: np.eye(4, dtype=np.float32))

    def __post_init__(self):
        if self.projection not in ENVIRONMENT_PROJECTIONS:
            raise ValueError(f"unknown environment projection {self.projection!r}")


@dataclass(eq=False)
class World:
    """The world as two radiance fields, each a sum of terms: what camera rays see and what lights
    the scene (different when a Light Path "Is Camera Ray" mix says so)."""

    camera: tuple[EnvironmentTerm, ...] = ()
    lighting: tuple[EnvironmentTerm, ...] = ()
    #: the lighting field's texels are clamped to this luminance (0: not at all); what lies above
    #: it lights the scene as ``suns`` instead (Blender's World > Sun > Threshold)
    threshold: float = 0.0
    suns: tuple[Light, ...] = ()

    @staticmethod
    def constant(terms) -> tuple[float, float, float]:
        """The summed radiance of ``terms``' constant (imageless) terms."""
        rgb = np.zeros(3)
        for term in terms:
            if term.image is None:
                rgb += term.weight
        return tuple(float(c) for c in rgb)

    @staticmethod
    def images(terms) -> tuple[EnvironmentTerm, ...]:
        return tuple(term for term in terms if term.image is not None)

    @property
    def lights(self) -> bool:
        """Whether the world sends any light (a black world computes nothing)."""
        return any(term.image is not None or any(term.weight) for term in self.lighting)


@dataclass
class DrawItem:
    """One instance of a geometry: its world matrix and a material per slot."""

    geometry: str
    matrix: np.ndarray  # (4, 4) float32, object -> world
    materials: list[str]  # material key per slot
    casts_shadow: bool = True  # the object's shadow ray visibility
    # what node graphs read of the object: its mesh's texture space (location, size: Generated
    # coordinates), its colour (Object Info's Color and Alpha), pass index and random number
    texspace: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    color: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    pass_index: int = 0
    random: float = 0.0
    #: the object's, its instancer's and the view layer's attributes its materials' graphs read:
    #: (kind, name) -> RGBA (Cycles' lookup_instance_property: a float as (x, x, x, 1))
    attributes: dict = field(default_factory=dict)

    @property
    def normal_matrix(self) -> np.ndarray:
        return normal_matrices(self.matrix[None])[0]


def normal_matrices(matrices: np.ndarray) -> np.ndarray:
    """(n, 4, 4) float32: the inverse transpose of each (4, 4) matrix's upper 3x3, embedded in a
    4x4 (zero for a degenerate scale, whose normals then fall back to the face normal)."""
    m3 = np.asarray(matrices, np.float64)[:, :3, :3]
    out = np.zeros((len(m3), 4, 4), np.float32)
    invertible = np.abs(np.linalg.det(m3)) > 1e-30
    if invertible.any():
        out[invertible, :3, :3] = invert(m3[invertible]).transpose(0, 2, 1)
    out[:, 3, 3] = 1.0
    return out



#: The narrowest half spread shaded (radians): narrower, the cone's normalisation (~3 / h^3) and the
#: light it lets through (~z h) leave float32's range.
MIN_HALF_SPREAD = 5e-4

@dataclass(frozen=True)
class Light:
    """A light in Blender's units, reduced to what the shaders need.

    ``intensity`` is rgb radiant intensity in W/sr for point, spot and area lights (I = P / 4 pi
    for point and spot, P / pi along the normal for area) and irradiance in W/m^2 for a sun.
    """

    kind: str
    position: tuple[float, float, float]
    direction: tuple[float, float, float]  # unit vector the light faces (its -Z axis)
    intensity: tuple[float, float, float]
    spot_cos_half: float = -1.0
    spot_smooth: float = 1e20
    diffuse_factor: float = 1.0
    specular_factor: float = 1.0
    angle: float = 0.0  # a sun's angular diameter (radians)
    world: bool = False  # split off the world's brightest texels: it lights what the world lights
    shadow: bool = False  # casts shadows (Blender's Cast Shadow, and the scene's Shadows setting)
    shadow_filter: float = 1.0  # Blender's shadow Filter: the hard shadow's blur radius in map texels
    shadow_resolution_limit: float = 0.001  # Blender's Resolution Limit: the smallest texel (m)
    shadow_jitter: bool = False  # Blender's Jitter: soft shadows at higher precision (more filter taps)
    radius: float = 0.0  # the emitter's size for soft shadows: a sphere's radius (point, spot),
    #                     an area light's equal-area disc radius (m); a sun uses ``angle``
    soft_falloff: bool = False  # a point or spot of radius r: Cycles' disc facing the point,
    #                             E = I / (d^2 + r^2); off: a sphere, E = I / d^2
    axis_x: tuple[float, float, float] = (1.0, 0.0, 0.0)  # an area light's local X axis (unit)
    half_size: tuple[float, float] = (0.0, 0.0)  # an area light's half width and height (m, scaled)
    ellipse: bool = False  # an area light's shape: disk or ellipse (else square or rectangle)
    spread: float = math.pi  # an area light's Spread (radians): the cone its radiance is limited to
    influence: float = math.inf  # how far it reaches (m; light_tiles.influence_radius): windowed
    #                              to nothing there, and culled from the screen tiles beyond it
    cutoff: float = math.inf  # Blender's Custom Distance (m), inf where unset: the reach a light
    #                           keeps where the Light Threshold gives none (programs.light_reaches)

    @property
    def spread_terms(self) -> tuple[float, float]:
        """(tan h, 1 / (tan h - h)) of an area light's spread, h its half angle (glsl/lights.glsl's
        spread_weight), (0, 0) for none (180 degrees, or not an area light); below 0.05 rad the
        denominator by its Taylor series h^3 / 3 + 2 h^5 / 15 (tan h - h cancels in float64 too);
        h at least MIN_HALF_SPREAD."""
        if self.kind != "AREA" or self.spread >= math.pi * (1.0 - 1e-7):
            return 0.0, 0.0
        h = max(0.5 * self.spread, MIN_HALF_SPREAD)
        gap = h ** 3 / 3.0 + 2.0 * h ** 5 / 15.0 if h < 0.05 else math.tan(h) - h
        return math.tan(h), 1.0 / gap

    @property
    def sphere_radius(self) -> float:
        """The radius a point or spot light is shaded with (0 for the other kinds)."""
        return self.radius if self.kind in ("POINT", "SPOT") else 0.0


@dataclass
class Camera:
    view: np.ndarray  # (4, 4) world -> camera
    projection: np.ndarray  # (4, 4) camera -> clip
    is_perspective: bool
    position: tuple[float, float, float]
    forward: tuple[float, float, float]
    clip_start: float = 0.0  # the near clip distance (a camera ray starts on that plane)

    @classmethod
    def from_matrices(cls, view, projection, is_perspective: bool) -> Camera:
        """A camera from a view matrix and a projection (what a 3D viewport region passes)."""
        view = np.asarray(view, np.float64)
        world = invert(view)
        axis = world[:3, 2]
        forward = -axis / max(np.linalg.norm(axis), 1e-30)
        p = np.asarray(projection, np.float64)
        # the near plane from the projection (OpenGL's: perspective P22 = -(f + n)/(f - n),
        # P23 = -2 f n/(f - n); orthographic P22 = -2/(f - n), P23 = -(f + n)/(f - n))
        if is_perspective:
            near = p[2, 3] / (p[2, 2] - 1.0) if p[2, 2] != 1.0 else 0.0
        else:
            near = (p[2, 3] + 1.0) / p[2, 2] if p[2, 2] != 0.0 else 0.0
        return cls(view.astype(np.float32), np.asarray(projection, np.float32), bool(is_perspective),
                   tuple(float(x) for x in world[:3, 3]), tuple(float(x) for x in forward),
                   float(near) if np.isfinite(near) else 0.0)

    @property
    def view_projection(self) -> np.ndarray:
        return (self.projection.astype(np.float64) @ self.view.astype(np.float64)).astype(np.float32)


@dataclass
class Settings:
    model: str = "PBR"
    terms: Terms = field(default_factory=Terms)
    ambient: float = 0.2  # the seed's "commonly used" ambient constant x (eq. 1.4)
    tone_mapper: str = "BLENDER"  # BLENDER: Combined is scene-linear, Blender's view transform displays
    exposure: float = 0.0  # EV: the exposure (manual) or its compensation (automatic)
    auto_exposure: AutoExposure | None = None  # None: manual exposure
    transfer: str = "SRGB"  # SRGB (exact) or GAMMA22, for the engine's own tone mappers
    samples: int = 1  # supersampling grid per axis for final renders (1 = pixel centres)
    compare_mode: str = "OFF"  # OFF, SPLIT or DIFFERENCE
    compare_models: tuple[str, str] = ("BLINN_PHONG", "PBR")
    compare_split: float = 0.5
    compare_range: float = 1.0
    transparency_layers: int = 4  # depth-peeling layers of partly transparent surfaces per pixel
    environment_diffuse: str = "MAP"  # the world's irradiance: "MAP" (exact convolution) or "SH9"
    environment_samples: int = 0  # the world's specular: split sum (0) or this many samples per pixel
    ambient_world: bool = False  # Blinn-Phong/Phong ambient: the world's irradiance, not the constant
    world_occlusion: bool = True  # screen-space ambient occlusion of the world's light
    occlusion_distance: float = 2.0  # how far (m) geometry occludes the world's light
    occlusion_resolution: str = "HALF"  # the occlusion trace's pixels: "FULL" or "HALF" (a quarter)
    shadows: bool = True  # lights whose Cast Shadow is on cast shadows (shadow maps)
    shadow_map_size: int = 1024  # texels per side of each shadow map (a point light has six)
    soft_shadows: bool = True  # penumbrae from the lights' sizes (else hard, filtered over a texel)
    light_threshold: float = 0.01  # W/m^2: a light reaches where its irradiance is above this
    light_culling: bool = True  # each screen tile shades only the lights that reach it
    #: Blender's Persistent Data (Render > Performance), final renders only
    #: (extract.final_render_settings): a final render may keep what the last final render of the
    #: same content drew (its shadow maps) instead of drawing it again
    persistent_data: bool = False
    #: the Auto term set: per material the cheapest terms whose predicted Delta E_ITP against the
    #: Principled set (at ``auto_quantile`` of its pixels) is within this bound; None: off
    auto_error_bound: float | None = None
    auto_quantile: float = 0.99


@dataclass
class Snapshot:
    camera: Camera
    width: int
    height: int
    settings: Settings = field(default_factory=Settings)
    geometries: dict[str, MeshGeometry] = field(default_factory=dict)
    items: list[DrawItem] = field(default_factory=list)
    materials: dict[str, MaterialParams] = field(default_factory=dict)
    lights: list[Light] = field(default_factory=list)
    world_color: tuple[float, float, float] = (0.0, 0.0, 0.0)  # the camera's constant terms
    world: World = field(default_factory=World)
    images: dict[str, ImageData] = field(default_factory=dict)  # by the key materials refer to
    warnings: list[str] = field(default_factory=list)
    fresh: set[str] = field(default_factory=set)  # geometry keys read anew (not reused)
    term_choices: dict = field(default_factory=dict)  # material key -> auto_terms.Choice (Auto)
    #: what ``warnings`` says of each material (a material taken from the last snapshot says it again)
    material_warnings: dict[str, list[str]] = field(default_factory=dict)
    #: the view layer's AOVs a final render writes: (name, "COLOR" or "VALUE")
    aovs: list[tuple[str, str]] = field(default_factory=list)
    #: fallback bakes the draw items wait for (``blender.bake.Request``): their slots draw the
    #: socket values until the bakes are made
    bake_requests: list = field(default_factory=list)

    @property
    def triangle_count(self) -> int:
        return sum(self.geometries[i.geometry].triangle_count for i in self.items)


def spot_smooth(spot_size: float, spot_blend: float) -> float:
    """Cycles' spot smoothstep scale 1 / ((1 - cos(size / 2)) * blend); 1e20 for a hard edge."""
    one_minus_cos = 1.0 - math.cos(0.5 * spot_size)
    denom = one_minus_cos * spot_blend
    return 1.0 / denom if denom > 1e-20 else 1e20
