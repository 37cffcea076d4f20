"""Scene and material settings (``scene.shading_lab``, ``material.shading_lab``)."""

from __future__ import annotations

import bpy
from bpy.app.handlers import persistent
from bpy.props import (
    BoolProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from ..reference.tonemap import TONE_MAPPER_CHOICES
from ..scene.snapshot import MODEL_CHOICES, enum_items
from . import extract, geometry, images

MODEL_ITEMS = enum_items(MODEL_CHOICES)


TERM_ITEMS = {
    "fresnel": (
        ("SCHLICK", "Schlick", "Schlick 1994, eq. 1.11: F0 + (F90 - F0)(1 - l.h)^5"),
        ("SCHLICK_SG", "Spherical Gaussian", "Lagarde 2012, eq. 1.12: the exponent as a power of 2"),
        ("SCHLICK_GENERAL", "Generalised Schlick", "Eq. 1.13: the material's F90 and exponent 1/p"),
        ("EXACT", "Exact", "Fresnel's equations: dielectric from the IOR, metal from its complex IOR"),
    ),
    "ndf": (
        ("GGX", "GGX", "Walter et al. 2007 / Trowbridge-Reitz, eq. 1.15: long-tailed"),
        ("BECKMANN", "Beckmann", "Beckmann 1963, eq. 1.14: the Cook-Torrance distribution"),
    ),
    "visibility": (
        ("SMITH_CORRELATED", "Smith Height-Correlated", "Heitz 2014, eqs. 1.16-1.17"),
        ("SMITH_SEPARABLE", "Smith Separable", "G1(v) G1(l), Walter et al. 2007"),
        ("VCAVITY", "V-Cavity", "Torrance-Sparrow / Cook-Torrance 1982"),
        ("APPROX", "Fast Approximation", "Hammon 2017 (GGX) or Schlick 1994 (Beckmann)"),
    ),
    "diffuse": (
        ("LAMBERT", "Lambert", "Eq. 1.18: (1 - F) rho / pi"),
        ("BURLEY", "Burley", "Burley 2012, Disney's retro-reflective diffuse (not energy conserving)"),
        ("BURLEY_RENORMALIZED", "Burley Renormalised", "Lagarde & de Rousiers 2014 (Frostbite)"),
        ("OREN_NAYAR", "Oren-Nayar", "Oren & Nayar 1994, the full model, sigma = roughness"),
        ("GGX_HAMMON", "GGX Rough Diffuse", "Hammon 2017: Lambertian microfacets under GGX + Smith"),
        ("LAYERED", "Layered (Principled)", "Lambert under the dielectric specular layer's albedo, as "
                                            "Blender's Principled BSDF weighs its base"),
    ),
}
#: World Specular: how the world lights the physically based specular lobe (the scene's setting,
#: and a material's own).
WORLD_SPECULAR_ITEMS = (
    ("SPLIT_SUM", "Split Sum", "Prefiltered world x directional albedo (Karis 2013): one lookup; "
                               "assumes the view along the normal, so errs at grazing angles"),
    ("SAMPLED", "Sampled", "The BRDF importance-sampled against the world at every pixel: slow, "
                           "converges to the reference as the samples grow"),
)
TERM_LABELS = {"fresnel": "Fresnel", "ndf": "Distribution", "visibility": "Masking-Shadowing",
               "diffuse": "Diffuse"}


def _redraw(self, context):
    """Add-on properties alone do not tag the depsgraph: tag the owner so renders update."""
    owner = self.id_data
    if owner is not None:
        owner.update_tag()
        if isinstance(owner, bpy.types.Scene):
            extract.remember_settings(owner)


class ShadingLabSceneSettings(bpy.types.PropertyGroup):
    model: EnumProperty(name="Model", items=MODEL_ITEMS, default="PBR", update=_redraw,
                        description="Shading model used for the whole scene")
    ambient: FloatProperty(
        name="Ambient", default=0.2, min=0.0, soft_max=1.0, update=_redraw,
        description="Ambient constant x of the Blinn-Phong and Phong models (eq. 1.4); 0.2 is the "
                    "commonly used value")
    ambient_source: EnumProperty(
        name="Ambient", default="CONSTANT", update=_redraw, items=(
            ("CONSTANT", "Constant", "The report's ambient term: ambient colour x the constant x (eq. 1.4)"),
            ("WORLD", "World", "The world's light: ambient colour x the world's irradiance / pi, the "
                               "diffuse light the physically based model receives from the world, and "
                               "the suns split off the world as lights"),
        ),
        description="What the Blinn-Phong and Phong models' ambient term is")
    tone_mapper: EnumProperty(
        name="Tone Mapper", default="BLENDER", update=_redraw, items=enum_items(TONE_MAPPER_CHOICES),
        description="Who turns radiance into display values. The engine's own tone mappers write "
                    "display-linear Combined (and raw radiance to a Radiance pass) and expect the "
                    "Standard view transform")
    light_threshold: FloatProperty(
        name="Light Threshold", default=0.01, min=0.0, soft_max=1.0, precision=4, update=_redraw,
        description="Irradiance (W/m^2) below which a light stops, in scenes of three or more lights: each "
                    "light reaches the distance where its irradiance falls to this (scaled down in a scene "
                    "dimmer than one lit for exposure 0; its Custom Distance where nearer) and is faded to "
                    "nothing there, dropping at most this much irradiance anywhere. 0: every light reaches "
                    "everywhere")
    light_culling: BoolProperty(
        name="Light Culling", default=True, update=_redraw,
        description="Shade each part of the screen with only the lights that reach it (the image is the "
                    "same; off is slower with many lights)")
    exposure_mode: EnumProperty(
        name="Exposure", default="MANUAL", update=_redraw, items=(
            ("MANUAL", "Manual", "The exposure set below"),
            ("AUTO", "Automatic", "Metered from each frame's luminance (and, in animations and the "
                                  "viewport, adapted from frame to frame), plus the compensation below"),
        ),
        description="How the exposure before the tone mapper is chosen. Automatic also scales Combined "
                    "under Blender's view transform (the raw radiance goes to the Radiance pass)")
    exposure: FloatProperty(name="Exposure", default=0.0, soft_min=-10.0, soft_max=10.0, update=_redraw,
                            description="Exposure in stops (radiance x 2^EV) before the tone mapper; "
                                        "with automatic exposure, stops added to the metered value")
    exposure_method: EnumProperty(
        name="Metering", default="HISTOGRAM", update=_redraw, items=(
            ("HISTOGRAM", "Histogram", "Log-average of the pixels between the low and high percentiles "
                                       "(the darkest and brightest ignored)"),
            ("LOG_AVERAGE", "Log Average", "Log-average luminance of every pixel (Reinhard et al. 2002)"),
        ),
        description="How the frame's luminance is measured")
    exposure_key: FloatProperty(
        name="Key", default=0.18, min=1e-4, soft_min=0.01, soft_max=1.0, update=_redraw,
        description="The luminance the frame's measured average is brought to (0.18: middle grey)")
    exposure_low: FloatProperty(
        name="Low", default=10.0, min=0.0, max=100.0, subtype="PERCENTAGE", update=_redraw,
        description="Histogram metering: the darkest pixels up to this percentage are ignored")
    exposure_high: FloatProperty(
        name="High", default=90.0, min=0.0, max=100.0, subtype="PERCENTAGE", update=_redraw,
        description="Histogram metering: the brightest pixels above this percentage are ignored")
    exposure_min: FloatProperty(
        name="Minimum", default=-16.0, soft_min=-16.0, soft_max=16.0, update=_redraw,
        description="Lowest automatic exposure, in stops")
    exposure_max: FloatProperty(
        name="Maximum", default=16.0, soft_min=-16.0, soft_max=16.0, update=_redraw,
        description="Highest automatic exposure, in stops")
    adapt_brighter: FloatProperty(
        name="Adapt to Brighter", default=0.5, min=0.0, soft_max=10.0, unit="TIME_ABSOLUTE", update=_redraw,
        description="Time constant (seconds) of the exposure's approach when the scene gets brighter, in "
                    "animations and the viewport (0: at once)")
    adapt_darker: FloatProperty(
        name="Adapt to Darker", default=2.0, min=0.0, soft_max=10.0, unit="TIME_ABSOLUTE", update=_redraw,
        description="Time constant (seconds) of the exposure's approach when the scene gets darker")
    transfer: EnumProperty(
        name="Transfer", default="SRGB", update=_redraw, items=(
            ("SRGB", "sRGB (exact)", "The exact sRGB transfer function (Blender's Standard view)"),
            ("GAMMA22", "Gamma 2.2", "The power-law approximation: display value = y^(1/2.2)"),
        ),
        description="Transfer function from display-linear to display values")
    term_set: EnumProperty(
        name="Term Set", default="CUSTOM", update=_redraw, items=(
            ("CUSTOM", "Custom", "The Fresnel, distribution, masking-shadowing and diffuse chosen below"),
            ("PRINCIPLED", "Principled BSDF", "Blender's Principled BSDF as Cycles evaluates it: exact "
                                              "Fresnel, GGX, Smith, per-lobe multiple scattering and a "
                                              "diffuse base under the specular layer's albedo"),
            ("AUTO", "Auto", "Per material, the cheapest terms whose predicted error against the "
                             "Principled BSDF set stays within the Error Bound"),
        ),
        description="Which physically based terms the engine evaluates")
    auto_error_bound: FloatProperty(
        name="Error Bound", default=0.5, min=0.01, soft_max=10.0, precision=2, update=_redraw,
        description="The largest difference from the Principled BSDF set Auto allows a material, as "
                    "Delta E_ITP (ITU-R BT.2124; 1 is about one just-noticeable difference) at the "
                    "Quantile of its pixels")
    auto_quantile: FloatProperty(
        name="Quantile", default=99.0, min=50.0, max=100.0, subtype="PERCENTAGE", precision=1,
        update=_redraw,
        description="Which share of a material's pixels must lie within the Error Bound")
    fresnel: EnumProperty(name="Fresnel", items=TERM_ITEMS["fresnel"], default="SCHLICK", update=_redraw)
    ndf: EnumProperty(name="Distribution", items=TERM_ITEMS["ndf"], default="GGX", update=_redraw)
    visibility: EnumProperty(name="Masking-Shadowing", items=TERM_ITEMS["visibility"],
                             default="SMITH_CORRELATED", update=_redraw)
    diffuse: EnumProperty(name="Diffuse", items=TERM_ITEMS["diffuse"], default="LAMBERT", update=_redraw)
    multiscatter: BoolProperty(
        name="Multiple Scattering", default=False, update=_redraw,
        description="Compensate the energy single-scatter microfacet specular loses at high roughness "
                    "(Turquin 2019, with a directional-albedo table built by the engine)")
    normalized_blinn_phong: BoolProperty(
        name="Energy-Normalised Blinn-Phong", default=False, update=_redraw,
        description="Blinn-Phong's specular as the normalised lobe (s + 8) / (8 pi) (n.h)^s")
    compare_mode: EnumProperty(
        name="A|B Compare", default="OFF", update=_redraw, items=(
            ("OFF", "Off", "Render the scene's model"),
            ("SPLIT", "Split", "Model A left of the split, model B right of it"),
            ("DIFFERENCE", "Difference", "The luminance difference |A - B| as a heat map (Turbo colours, "
                                         "0 at the left of the bottom strip, Range at its right)"),
        ))
    compare_a: EnumProperty(name="A", items=MODEL_ITEMS, default="BLINN_PHONG", update=_redraw)
    compare_b: EnumProperty(name="B", items=MODEL_ITEMS, default="PBR", update=_redraw)
    compare_split: FloatProperty(name="Split", default=0.5, min=0.0, max=1.0, subtype="FACTOR",
                                 update=_redraw, description="Position of the divider, from the left")
    compare_range: FloatProperty(name="Range", default=1.0, min=1e-6, soft_max=100.0, update=_redraw,
                                 description="Radiance difference shown at the hot end of the heat map")
    samples: IntProperty(
        name="Anti-Aliasing", default=1, min=1, max=8, update=_redraw,
        description="Supersampling grid per axis for final renders: N x N sub-pixel samples averaged "
                    "with equal weights (a box filter over the pixel). 1 samples pixel centres only, "
                    "as the comparisons against Cycles expect")
    transparency_layers: IntProperty(
        name="Transparency Layers", default=4, min=1, max=16, update=_redraw,
        description="Partly transparent surfaces blended per pixel, nearest first, in depth order "
                    "(depth peeling): surfaces beyond this many behind one another are left out")
    world_diffuse: EnumProperty(
        name="World Diffuse", default="MAP", update=_redraw, items=(
            ("MAP", "Irradiance Map", "The world's light convolved exactly with the cosine, per "
                                      "direction (64 x 32 texels, from a 64 x 32 downsampled world)"),
            ("SH9", "Spherical Harmonics", "Nine coefficients (Ramamoorthi & Hanrahan 2001): cheaper, "
                                           "smooth; wrong where a small bright source dominates"),
        ),
        description="How the world lights the diffuse lobe of the physically based model")
    world_specular: EnumProperty(
        name="World Specular", default="SPLIT_SUM", update=_redraw, items=WORLD_SPECULAR_ITEMS,
        description="How the world lights the specular lobe of the physically based model")
    world_occlusion: BoolProperty(
        name="World Occlusion", default=True, update=_redraw,
        description="Geometry occludes the world's light: screen-space ambient occlusion (ground-truth "
                    "ambient occlusion, Jimenez et al. 2016) of its diffuse and specular parts")
    occlusion_distance: FloatProperty(
        name="Occlusion Distance", default=2.0, min=0.001, soft_max=100.0, subtype="DISTANCE", update=_redraw,
        description="How far geometry occludes the world's light (on screen only: what the camera does not "
                    "see occludes nothing)")
    occlusion_resolution: EnumProperty(
        name="Occlusion Resolution", default="HALF", update=_redraw, items=(
            ("FULL", "Full", "Trace the occlusion at every pixel (slowest; sharpest at thin objects' edges)"),
            ("HALF", "Half", "Trace one pixel of every 2 x 2 block and merge the neighbours on the same "
                             "surface (a quarter of the work; thin objects' occlusion softens)"),
        ),
        description="How many pixels the world's occlusion is traced at")
    shadows: BoolProperty(
        name="Shadows", default=True, update=_redraw,
        description="Lights whose Cast Shadow is on cast shadows (shadow maps); objects whose shadow ray "
                    "visibility is off cast none")
    shadow_map_size: EnumProperty(
        name="Shadow Map Size", default="1024", update=_redraw, items=(
            ("512", "512", "512 x 512 texels per map (a point or area light has six)"),
            ("1024", "1024", "1024 x 1024 texels per map (a point or area light has six)"),
            ("2048", "2048", "2048 x 2048 texels per map (a point or area light has six)"),
            ("4096", "4096", "4096 x 4096 texels per map: sharp, 64 MiB per map"),
        ),
        description="Resolution of each shadow map: larger is sharper and takes more memory and time")
    soft_shadows: BoolProperty(
        name="Soft Shadows", default=True, update=_redraw,
        description="Penumbrae from the lights' sizes (Radius, Angle, area Size); off: hard shadows, "
                    "filtered over one texel")
    world_samples: IntProperty(
        name="World Samples", default=64, min=1, max=1024, update=_redraw,
        description="Samples of the world per pixel for sampled world specular")
    bake_resolution: IntProperty(
        name="Bake Resolution", default=512, min=16, max=8192, soft_max=4096, update=_redraw,
        description="Texels along each side of the images Cycles bakes for the nodes Shading Lab does not "
                    "compile (on the object's UV map; kept in memory, never saved into the file)")


def _override(name: str, description: str):
    return BoolProperty(name=f"Set {name}", default=False, update=_redraw,
                        description=f"Use this {description} instead of the surface shader's value")


class ShadingLabMaterialSettings(bpy.types.PropertyGroup):
    model: EnumProperty(
        name="Model", default="SCENE", update=_redraw,
        items=(("SCENE", "Scene's", "Use the model chosen in the Render properties"), *MODEL_ITEMS),
        description="Shading model for this material, overriding the scene's")
    fresnel: EnumProperty(name="Fresnel", items=(("SCENE", "Scene's", ""), *TERM_ITEMS["fresnel"]),
                          default="SCENE", update=_redraw)
    ndf: EnumProperty(name="Distribution", items=(("SCENE", "Scene's", ""), *TERM_ITEMS["ndf"]),
                      default="SCENE", update=_redraw)
    visibility: EnumProperty(name="Masking-Shadowing", default="SCENE", update=_redraw,
                             items=(("SCENE", "Scene's", ""), *TERM_ITEMS["visibility"]))
    diffuse: EnumProperty(name="Diffuse", items=(("SCENE", "Scene's", ""), *TERM_ITEMS["diffuse"]),
                          default="SCENE", update=_redraw)
    world_specular: EnumProperty(
        name="World Specular", default="SCENE", update=_redraw,
        items=(("SCENE", "Scene's", "The Render properties' World Specular"), *WORLD_SPECULAR_ITEMS),
        description="How the world lights this material's specular lobe (physically based model, "
                    "worlds with images): a hero metal sampled while the rest of the scene uses the "
                    "split sum, or the other way round")
    world_samples: IntProperty(
        name="World Samples", default=64, min=1, max=1024, update=_redraw,
        description="Samples of the world per pixel for this material's sampled world specular")
    use_base_color: _override("Base Color", "base colour")
    base_color: FloatVectorProperty(name="Base Color", subtype="COLOR", size=3, min=0.0, max=1.0,
                                    default=(0.8, 0.8, 0.8), update=_redraw)
    use_metalness: _override("Metalness", "metalness")
    metalness: FloatProperty(name="Metalness", default=0.0, min=0.0, max=1.0, update=_redraw)
    use_roughness: _override("Roughness", "roughness")
    roughness: FloatProperty(name="Roughness", default=0.5, min=0.0, max=1.0, update=_redraw,
                             description="Perceptual roughness r; the GGX width is alpha = r^2")
    use_f0: _override("F0", "dielectric reflectance at normal incidence")
    f0: FloatProperty(name="Dielectric F0", default=0.04, min=0.0, max=1.0, update=_redraw,
                      description="Fresnel reflectance at normal incidence of the dielectric part "
                              "(0.04 for IOR 1.5; 0 removes the specular lobe)")
    use_f90: _override("F90", "grazing reflectance of the generalised Schlick Fresnel")
    f90: FloatProperty(name="F90", default=1.0, min=0.0, max=1.0, update=_redraw,
                       description="Reflectance at grazing incidence (eq. 1.13); otherwise saturate(50 F0)")
    fresnel_p: FloatProperty(name="Fresnel p", default=0.2, min=0.01, max=10.0, update=_redraw,
                             description="Eq. 1.13's p: the Fresnel tail is (1 - l.h)^(1/p); "
                                         "0.2 is Schlick's")
    use_complex_ior: _override("Complex IOR", "conductor's complex index of refraction")
    ior_n: FloatVectorProperty(name="IOR n", size=3, min=0.0, default=(0.18, 0.42, 1.37), update=_redraw,
                               description="Real part of the metal's index of refraction per rgb channel "
                                           "(exact Fresnel); default: gold")
    ior_k: FloatVectorProperty(name="IOR k", size=3, min=0.0, default=(3.42, 2.35, 1.77), update=_redraw,
                               description="Extinction coefficient per rgb channel (exact Fresnel)")
    use_shininess: _override("Shininess", "Blinn-Phong exponent")
    shininess: FloatProperty(name="Shininess", default=30.0, min=0.0, soft_max=1000.0, update=_redraw,
                             description="Blinn-Phong/Phong specular exponent (otherwise derived "
                                     "from roughness: 2 / r^4 - 2)")
    use_specular_color: _override("Specular Color", "Blinn-Phong specular colour")
    specular_color: FloatVectorProperty(name="Specular Color", subtype="COLOR", size=3, min=0.0,
                                        default=(1.0, 1.0, 1.0), update=_redraw)
    use_ambient_color: _override("Ambient Color", "Blinn-Phong ambient colour")
    ambient_color: FloatVectorProperty(name="Ambient Color", subtype="COLOR", size=3, min=0.0,
                                       default=(0.8, 0.8, 0.8), update=_redraw)


class ShadingLabWorldSettings(bpy.types.PropertyGroup):
    """The baked world (World > Shading Lab > Bake World) for worlds Shading Lab cannot read."""

    baked_image: PointerProperty(
        name="Baked World", type=bpy.types.Image, update=_redraw,
        description="The world rendered by Cycles into an equirectangular image; Shading Lab lights "
                    "and shows with it while the world has nodes it cannot read")
    baked_fingerprint: StringProperty(
        name="Baked Fingerprint", default="",
        description="A hash of the world's nodes when it was baked (a different one: out of date)")
    bake_resolution: IntProperty(name="Resolution", default=1024, min=64, max=8192,
                                 description="Width of the baked image in pixels (its height is half)")
    bake_samples: IntProperty(name="Samples", default=16, min=1, max=4096,
                              description="Cycles samples per pixel for the bake")


classes = (ShadingLabSceneSettings, ShadingLabMaterialSettings, ShadingLabWorldSettings)
_OWNERS = ((bpy.types.Scene, ShadingLabSceneSettings), (bpy.types.Material, ShadingLabMaterialSettings),
           (bpy.types.World, ShadingLabWorldSettings))


@persistent
def _remember_scene(*_args):
    """Main-thread handler: the current scene's settings, kept for previews."""
    extract.remember_settings(getattr(bpy.context, "scene", None))


@persistent
def _forget_changed_images(_scene, depsgraph):
    """Main-thread handler: images reloaded, repainted or regenerated are read again."""
    images.IMAGES.forget(images.image_updates(depsgraph))


@persistent
def _forget_all_images(*_args):
    """Main-thread handler: a file load starts with no cached pixels, nor meshes' geometry, nor
    fallback bakes."""
    images.IMAGES.clear()
    geometry.GEOMETRY_MEMO.clear()
    extract.FALLBACK_READS.clear()
    extract.bake.forget()


def _handlers():
    h = bpy.app.handlers
    return ((h.depsgraph_update_post, _remember_scene), (h.load_post, _remember_scene),
            (h.depsgraph_update_post, _forget_changed_images), (h.load_post, _forget_all_images))


def register():
    """Attach the settings as ``scene.shading_lab`` and ``material.shading_lab``."""
    for owner, group in _OWNERS:
        owner.shading_lab = PointerProperty(type=group)
    for handlers, function in _handlers():
        handlers.append(function)
    _remember_scene()


def unregister():
    for handlers, function in _handlers():
        if function in handlers:
            handlers.remove(function)
    for owner, _group in _OWNERS:
        del owner.shading_lab
