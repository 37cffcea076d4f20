"""The procedural texture nodes' emitters (issue #52), registered in ``codegen.EMITTERS``: each
``(writer, node) -> {output socket: GLSL expression}`` or None where the node cannot compile, as
codegen's own. Their GLSL lives in ``glsl/node_hash.glsl`` and ``glsl/node_tex_*.glsl``, files
of ``codegen.OPTIONAL_LIBRARY``: compiled into a program only where its graph calls them. Each
follows Cycles' SVM node of the same texture (kernel/svm/), and has a numpy twin in
``addon/reference/`` (hashing.py ...)."""

from __future__ import annotations

from .graph import FlatNode, Ref

#: The dimension settings of the noise-like textures, each its GLSL functions' suffix.
DIMENSIONS = {"1D": "1d", "2D": "2d", "3D": "3d", "4D": "4d"}


def vector(w, node: FlatNode) -> str | None:
    """A texture node's Vector: what is linked to it, else the object's Generated coordinates
    (Cycles' LINK_TEXTURE_GENERATED). None where the node's own Texture Mapping (the node's
    sidebar) is not the identity: the reader marks it, and such a node does not compile."""
    if node.props.get("texture_mapping"):
        return None
    spec = node.inputs.get("Vector")
    if spec is not None and isinstance(spec.source, Ref):
        return w.arg(node, "Vector")
    return "g.generated"


def scalar(w, node: FlatNode, socket: str) -> str:
    """An input that the node's settings may hide (Blender then leaves it out): its value, or 0."""
    return w.arg(node, socket) if socket in node.inputs else "0.0"


def _white_noise(w, node: FlatNode) -> dict | None:
    """White Noise Texture (Cycles' svm_node_tex_white_noise): the hash of the coordinate."""
    dims = DIMENSIONS.get(node.props.get("noise_dimensions", "3D"))
    co = vector(w, node)
    if dims is None or co is None:
        return None
    args = f"{co}, {scalar(w, node, 'W')}"
    return {"Value": f"node_white_noise_value_{dims}({args})",
            "Color": f"node_white_noise_color_{dims}({args})"}


# --- Noise and Wave (glsl/node_tex_noise.glsl, node_tex_wave.glsl; twins reference/noise.py, wave.py)

#: The Noise Texture's types, each its GLSL constant (node_tex_noise.glsl).
NOISE_TYPES = {"FBM": "NOISE_FBM", "MULTIFRACTAL": "NOISE_MULTIFRACTAL",
               "HYBRID_MULTIFRACTAL": "NOISE_HYBRID_MULTIFRACTAL",
               "RIDGED_MULTIFRACTAL": "NOISE_RIDGED_MULTIFRACTAL", "HETERO_TERRAIN": "NOISE_HETERO_TERRAIN"}
#: The Wave Texture's settings, each its GLSL constant (node_tex_wave.glsl).
WAVE_TYPES = {"BANDS": "WAVE_BANDS", "RINGS": "WAVE_RINGS"}
WAVE_BANDS_DIRECTIONS = {"X": "WAVE_X", "Y": "WAVE_Y", "Z": "WAVE_Z", "DIAGONAL": "WAVE_DIAGONAL"}
WAVE_RINGS_DIRECTIONS = {"X": "WAVE_X", "Y": "WAVE_Y", "Z": "WAVE_Z", "SPHERICAL": "WAVE_SPHERICAL"}
WAVE_PROFILES = {"SIN": "WAVE_SIN", "SAW": "WAVE_SAW", "TRI": "WAVE_TRI"}


def _noise(w, node: FlatNode) -> dict | None:
    """Noise Texture (Cycles' svm_node_tex_noise): 1D to 4D, every type (an old file's Musgrave
    Texture arrives as one of them). The coordinates (scaled, distorted) once; Fac the fractal
    there; Color Fac and the fractal at two seeded offsets (computed only where Color is read:
    an unused output's code is dropped by the shader compiler)."""
    props = node.props
    dims = DIMENSIONS.get(props.get("noise_dimensions", "3D"))
    kind = NOISE_TYPES.get(props.get("noise_type", "FBM"))
    co = vector(w, node) if dims != "1d" else "vec3(0.0)"  # (1D reads W alone)
    if dims is None or kind is None or co is None:
        return None
    d = dims[0]
    p = w.once("vec4", f"node_noise_coordinates({co}, {scalar(w, node, 'W')}, {w.arg(node, 'Scale')}, "
                       f"{w.arg(node, 'Distortion')}, {d})")
    normalize = w.constant(1.0 if props.get("normalize", True) else 0.0, "VALUE")
    args = (f"{d}, {kind}, {w.arg(node, 'Detail')}, {w.arg(node, 'Roughness')}, {w.arg(node, 'Lacunarity')}, "
            f"{scalar(w, node, 'Offset')}, {scalar(w, node, 'Gain')}, {normalize}")
    value = w.once("float", f"node_noise_value({p}, {args})")
    return {"Fac": value, "Color": f"node_noise_color({p}, {value}, {args})"}


def _wave(w, node: FlatNode) -> dict | None:
    """Wave Texture (Cycles' svm_node_tex_wave): bands or rings in every direction and profile,
    distorted by fBM noise; Color is Fac in each channel."""
    props = node.props
    kind = props.get("wave_type", "BANDS")
    directions = WAVE_BANDS_DIRECTIONS if kind == "BANDS" else WAVE_RINGS_DIRECTIONS
    direction = directions.get(props.get("bands_direction" if kind == "BANDS" else "rings_direction", "X"))
    profile = WAVE_PROFILES.get(props.get("wave_profile", "SIN"))
    co = vector(w, node)
    if kind not in WAVE_TYPES or direction is None or profile is None or co is None:
        return None
    args = ", ".join(w.arg(node, socket) for socket in ("Scale", "Distortion", "Detail", "Detail Scale",
                                                          "Detail Roughness", "Phase Offset"))
    fac = w.once("float", f"node_tex_wave({co}, {args}, {WAVE_TYPES[kind]}, {direction}, {profile})")
    return {"Fac": fac, "Color": f"vec4(vec3({fac}), 1.0)"}


EMITTERS = {
    "ShaderNodeTexWhiteNoise": _white_noise,
    "ShaderNodeTexNoise": _noise,
    "ShaderNodeTexWave": _wave,
}
