"""Reads a Blender material into ``MaterialParams``: its surface shader's values (Principled BSDF,
Diffuse, Glossy, Glass, Refraction, Emission), its node graph compiled, the Shading Lab panel's
explicit values, and what of the graph is not drawn (``GRAPH_REPORTS``, for the Material panel).
"""

from __future__ import annotations

import dataclasses

import bpy

from ..materials import codegen, surface
from ..scene import snapshot as S
from . import nodes


def _linked_surface_node(material: bpy.types.Material):
    tree = material.node_tree
    if tree is None:
        return None
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    active = [n for n in outputs if n.is_active_output] or outputs
    for out in active:
        surface = out.inputs.get("Surface")
        if surface is not None and surface.is_linked:
            return surface.links[0].from_node
    return None


def rgb(value) -> tuple[float, float, float]:
    """A colour socket's or property's first three channels as floats."""
    return (float(value[0]), float(value[1]), float(value[2]))


def _input(node, name, default):
    socket = node.inputs.get(name)
    return default if socket is None else socket.default_value


def material_params(material: bpy.types.Material | None, images: dict | None = None,
                    warnings: list[str] | None = None) -> S.MaterialParams:
    """Explicit Shading Lab values where the user set them, else the surface shader's values
    (Principled, Diffuse or Glossy BSDF), else the material's viewport display values; a surface
    with nodes linked into it is compiled (``MaterialParams.graph``: its values per fragment). Images
    the graph samples are added to ``images`` (key -> ``bpy.types.Image``); what of it is not
    compiled is said in ``warnings``."""
    if material is None:
        return S.DEFAULT_MATERIAL
    maps: dict = _thin_film_version()
    base = rgb(material.diffuse_color)
    metal = float(material.metallic)
    rough = float(material.roughness)
    f0 = S.DEFAULT_F0
    node = _linked_surface_node(material)
    kind = node.bl_idname if node is not None else ""
    if kind == "ShaderNodeBsdfPrincipled":
        base = rgb(_input(node, "Base Color", base))
        metal = float(_input(node, "Metallic", metal))
        rough = float(_input(node, "Roughness", rough))
        level = float(_input(node, "Specular IOR Level", 0.5))
        f0 = min(S.f0_from_ior(float(_input(node, "IOR", 1.5))) * 2.0 * level, 1.0)
        maps["alpha"] = float(_input(node, "Alpha", 1.0))
        strength = float(_input(node, "Emission Strength", 0.0))
        maps["emission"] = tuple(c * strength for c in rgb(_input(node, "Emission Color", (0, 0, 0))))
        maps.update(_principled_lobes(node))
    elif kind == "ShaderNodeEmission":  # a pure emitter: no reflection
        base, metal, f0 = (0.0, 0.0, 0.0), 0.0, 0.0
        strength = float(_input(node, "Strength", 1.0))
        maps["emission"] = tuple(c * strength for c in rgb(_input(node, "Color", (1, 1, 1))))
    elif kind == "ShaderNodeBsdfDiffuse":
        base, metal, f0 = rgb(_input(node, "Color", base)), 0.0, 0.0
    elif kind in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"):
        base, metal = rgb(_input(node, "Color", base)), 1.0
        rough = float(_input(node, "Roughness", rough))
    elif kind in GLASS_NODES:
        base, metal, rough, f0 = _glass(node, maps)
    graph, aovs = _material_graph(material, images, warnings)
    if graph is not None:  # its closures' inputs, per fragment
        maps["graph"] = graph
    if aovs:
        maps["aovs"] = tuple(sorted(aovs.items()))
    props = getattr(material, "shading_lab", None)
    if props is not None:  # explicit values win over the shader's, textures included
        base = rgb(props.base_color) if props.use_base_color else base
        metal = float(props.metalness) if props.use_metalness else metal
        rough = float(props.roughness) if props.use_roughness else rough
        f0 = float(props.f0) if props.use_f0 else f0
    metal = min(max(metal, 0.0), 1.0)
    rough = min(max(rough, 0.0), 1.0)
    # Blinn-Phong/Phong fallbacks from the physically based values: a metal's colour goes to its
    # highlight and none to its diffuse term; a dielectric keeps a white highlight; the ambient
    # colour is the diffuse colour (the seed's "typically"); shininess from roughness. A surface
    # with no specular lobe (F0 0: Diffuse BSDF, Emission, Specular IOR Level 0) has no highlight.
    diffuse = tuple(c * (1.0 - metal) for c in base)
    dielectric_spec = 1.0 if f0 > 0.0 else 0.0
    spec = tuple((1.0 - metal) * dielectric_spec + metal * c for c in base)
    shininess = S.shininess_from_roughness(rough)
    ambient = diffuse
    if props is not None:
        spec = rgb(props.specular_color) if props.use_specular_color else spec
        shininess = float(props.shininess) if props.use_shininess else shininess
        ambient = rgb(props.ambient_color) if props.use_ambient_color else ambient
    if graph is not None and props is not None:
        maps["graph_keep"] = frozenset(name for name, flag in GRAPH_KEEP.items() if getattr(props, flag))
    return S.MaterialParams(
        name=material.name,
        pass_index=int(getattr(material, "pass_index", 0)),
        base_color=base,
        diffuse_color=diffuse,
        specular_color=spec,
        ambient_color=ambient,
        roughness=rough,
        metalness=metal,
        shininess=max(shininess, 0.0),
        f0=min(max(f0, 0.0), 1.0),
        **{k: v for k, v in maps.items() if v is not None},
        **_material_extras(props),
    )


def _principled_lobes(node) -> dict:
    """The Principled BSDF's lobes beyond its base (MaterialParams' fields), clamped as Cycles'
    svm_node_closure_bsdf clamps them: tints and weights at least 0, roughnesses within [0, 1], the
    coat's IOR at least 1, the Transmission Weight within [0, 1]."""
    def colour(name):
        return tuple(max(c, 0.0) for c in rgb(_input(node, name, (1.0, 1.0, 1.0))))

    def unit(name, default):
        return min(max(float(_input(node, name, default)), 0.0), 1.0)

    return {"specular_tint": colour("Specular Tint"),
            "coat_weight": max(float(_input(node, "Coat Weight", 0.0)), 0.0),
            "coat_roughness": unit("Coat Roughness", 0.03),
            "coat_ior": max(float(_input(node, "Coat IOR", 1.5)), 1.0), "coat_tint": colour("Coat Tint"),
            "sheen_weight": max(float(_input(node, "Sheen Weight", 0.0)), 0.0),
            "sheen_roughness": unit("Sheen Roughness", 0.5), "sheen_tint": colour("Sheen Tint"),
            "subsurface_weight": unit("Subsurface Weight", 0.0),
            "subsurface_radius": tuple(float(c) for c in
                                       _input(node, "Subsurface Radius", (1.0, 0.2, 0.1))[:3]),
            "subsurface_scale": float(_input(node, "Subsurface Scale", 0.05)),
            "subsurface_ior": float(_input(node, "Subsurface IOR", 1.4)),
            "subsurface_anisotropy": float(_input(node, "Subsurface Anisotropy", 0.0)),
            "subsurface_method": getattr(node, "subsurface_method", "RANDOM_WALK"),
            # the glass part (Cycles' Transmission component): each crossing tinted by sqrt(Base
            # Color), the base colour clamped to [0, 1] first; its IOR the Principled BSDF's
            "transmission_weight": unit("Transmission Weight", 0.0),
            "transmission_ior": max(float(_input(node, "IOR", 1.5)), 1e-5),
            "transmission_tint": tuple(min(max(c, 0.0), 1.0) ** 0.5 for c in rgb(_input(node, "Base Color",
                                                                                           (0.8, 0.8, 0.8)))),
            # the diffuse base's Oren-Nayar roughness (Blender 4.3 and later; 4.2's: Lambert)
            "diffuse_roughness": unit("Diffuse Roughness", 0.0),
            # what the random walk's entry refracts through (reference/subsurface.py's walk_row)
            "ior": float(_input(node, "IOR", 1.5)),
            "specular_ior_level": float(_input(node, "Specular IOR Level", 0.5)),
            **_thin_film(node)}


def _thin_film(node) -> dict:
    """The Principled BSDF's Thin Film (Blender 4.2 and later; none before): its thickness (nm, at
    least 0: 0.1 or less is no film, Cycles' THINFILM_THICKNESS_CUTOFF) and IOR (at least 1e-5, as
    Cycles' svm_node_closure_bsdf floors it)."""
    return {"thin_film_thickness": max(float(_input(node, "Thin Film Thickness", 0.0)), 0.0),
            "thin_film_ior": max(float(_input(node, "Thin Film IOR", 1.33)), 1e-5)}


def _thin_film_version() -> dict:
    """The rule this Blender's Cycles draws a Thin Film by (``snapshot.THIN_FILM_RULES``: 4.2 and 4.5
    sum its colour through a Gaussian fit in XYZ, leave the metal bare and blend its IOR to the air's
    below 30 nm; 5.0 reads a table, films the metal, blends below 1 nm)."""
    return {"thin_film_rule": S.thin_film_rule(bpy.app.version)}


#: The closures that transmit alone (glsl/transmission.glsl): the Glass BSDF (reflects and transmits
#: by the Fresnel) and the Refraction BSDF (transmits all, reflects nothing).
GLASS_NODES = ("ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction")


def _glass(node, maps: dict) -> tuple:
    """A Glass or Refraction BSDF as the surface: (base colour, metalness, roughness, F0), its
    transmission into ``maps``, as Cycles' svm_node_closure_bsdf sets its closure up: the Color
    tints each crossing (and the Glass BSDF's reflection), the IOR at least 1e-5, the roughness
    within [0, 1]; the Refraction BSDF has no reflection (F0 0) and no Fresnel."""
    color = tuple(max(c, 0.0) for c in rgb(_input(node, "Color", (1.0, 1.0, 1.0))))
    ior = max(float(_input(node, "IOR", 1.5)), 1e-5)
    rough = min(max(float(_input(node, "Roughness", 0.0)), 0.0), 1.0)
    glass = node.bl_idname == "ShaderNodeBsdfGlass"
    maps.update(transmission_weight=1.0, transmission_ior=ior, transmission_tint=color,
                reflection_tint=color if glass else (0.0, 0.0, 0.0), transmission_fresnel=glass)
    return color, 0.0, rough, S.f0_from_ior(ior) if glass else 0.0


#: The Material panel's explicit values a compiled graph leaves as they are: its input -> the flag.
GRAPH_KEEP = {"base_color": "use_base_color", "metalness": "use_metalness", "roughness": "use_roughness",
              "f0": "use_f0", "specular_color": "use_specular_color", "shininess": "use_shininess",
              "ambient_color": "use_ambient_color"}


@dataclasses.dataclass(frozen=True)
class GraphReport:
    """What the last read of a material made of its node graph, for the Material panel: whether
    it was compiled (else its surface is one shader read as values), how many of its nodes, which
    did not compile and what the models do not read (``MaterialGraph.missing`` / ``unread``),
    whether its Displacement is linked (never drawn), its AOV Outputs, and which of the nodes
    that did not compile are baked (``bake``: per object, ``bake.status``)."""

    compiled: bool
    nodes: int = 0
    missing: tuple[str, ...] = ()
    unread: tuple[str, ...] = ()
    displacement: bool = False
    aovs: tuple[str, ...] = ()
    #: of ``missing``, the nodes Cycles bakes for the objects using the material (flat names)
    baked: tuple[str, ...] = ()


#: The last GraphReport of each material (by its full name), as a render or the viewport read it.
GRAPH_REPORTS: dict[str, GraphReport] = {}


def _material_graph(material, images: dict | None, warnings: list[str] | None) -> tuple:
    """(the material's node graph compiled, ``surface.compile_material``: None where its surface is
    one closure with nothing linked into it; its AOV Outputs compiled, by name); the images they
    sample go into ``images``. The nodes the surface could not compile are said in ``warnings``."""
    found: dict = {}
    read = nodes.read_material(material, images=found)
    if read is None:
        return None, {}
    graph = surface.compile_material(*read)
    aovs = surface.compile_aovs(*read)
    displacement = surface.displacement_linked(read[0])
    GRAPH_REPORTS[material.name_full] = GraphReport(
        graph is not None, graph.nodes if graph is not None else 0, tuple(graph.missing) if graph else (),
        tuple(graph.unread) if graph else (), displacement, tuple(sorted(aovs)),
        tuple(_baked_nodes(graph, aovs)))
    if displacement and warnings is not None:
        warnings.append(f"Material '{material.name}': its Displacement is not drawn (the surface is drawn "
                        f"as it is, without displacement or bump from the output)")
    for compiled in ([graph] if graph is not None else []) + list(aovs.values()):
        if images is not None:  # a UDIM tile's key (codegen.tile_key) names its image's
            images.update((key, found.get(key) or found[key.rsplit("#", 1)[0]])
                          for entry in compiled.images for key in codegen.sampler_keys(entry))
        if compiled.notes and warnings is not None:
            warnings.append(f"Material '{material.name}': {'; '.join(compiled.notes)}")
    baked = _baked_nodes(graph, aovs)
    if baked and warnings is not None:
        kinds = {m.rsplit(" (", 1)[0]: m for g in [graph, *aovs.values()] if g is not None for m in g.missing}
        named = ", ".join(kinds.get(n, n) for n in baked)
        of = f" of {graph.nodes}" if graph is not None else ""
        warnings.append(f"Material '{material.name}': {len(baked)}{of} nodes not compiled ({named}): baked "
                        f"by Cycles on each object's UV map")
    if graph is None:
        return None, aovs
    if graph.unread and warnings is not None:
        warnings.append(f"Material '{material.name}': its {', '.join(graph.unread)} not drawn (the shading "
                        f"models have no such input)")
    fallen = [m for m in graph.missing if m.rsplit(" (", 1)[0] not in baked]
    if fallen and warnings is not None:
        warnings.append(f"Material '{material.name}': {len(fallen)} of {graph.nodes} nodes not "
                        f"compiled ({', '.join(fallen)}); what they feed takes its socket's own value")
    return graph, aovs


def _baked_nodes(graph, aovs: dict) -> list[str]:
    """The not-compiled nodes of a material's graphs that its bakes stand in for (flat names)."""
    graphs = ([graph] if graph is not None else []) + list(aovs.values())
    return list(dict.fromkeys(n for g in graphs for t in g.bakes for n in t.nodes))


def _material_extras(props) -> dict:
    """The per-material model and term choices, and the Fresnel inputs beyond F0."""
    if props is None:
        return {}

    def chosen(value):
        return "" if value == "SCENE" else value

    extras = dict(model=chosen(props.model), fresnel=chosen(props.fresnel), ndf=chosen(props.ndf),
                  visibility=chosen(props.visibility), diffuse=chosen(props.diffuse),
                  fresnel_p=float(props.fresnel_p),
                  environment_samples={"SCENE": -1, "SPLIT_SUM": 0}.get(props.world_specular,
                                                                        int(props.world_samples)))
    if props.use_f90:
        extras["f90"] = float(props.f90)
    if props.use_complex_ior:
        extras["ior_n"], extras["ior_k"] = rgb(props.ior_n), rgb(props.ior_k)
    return extras
