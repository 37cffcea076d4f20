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


# --- Gabor ---------------------------------------------------------------------------------------

#: The Gabor Texture's types, each its GLSL function, and the orientation socket each reads.
GABOR_TYPES = {"2D": ("node_tex_gabor_2d", "Orientation 2D"), "3D": ("node_tex_gabor_3d", "Orientation 3D")}


def _gabor(w, node: FlatNode) -> dict | None:
    """Gabor Texture (Cycles' svm_node_tex_gabor): the phasor summed once, its three outputs."""
    kind = GABOR_TYPES.get(node.props.get("gabor_type", "2D"))
    co = vector(w, node)
    if kind is None or co is None or kind[1] not in node.inputs:
        return None
    fn, orientation = kind
    args = ", ".join([co] + [w.arg(node, s) for s in ("Scale", "Frequency", "Anisotropy", orientation)])
    result = w.once("vec3", f"{fn}({args})")
    return {"Value": f"{result}.x", "Phase": f"{result}.y", "Intensity": f"{result}.z"}


# --- Gradient, Checker, Magic, Brick, Radial Tiling (glsl/node_tex_gradient.glsl ...) ----------

#: The Gradient Texture's types, each its GLSL function's suffix.
GRADIENT_TYPES = {"LINEAR": "linear", "QUADRATIC": "quadratic", "EASING": "easing", "DIAGONAL": "diagonal",
                  "SPHERICAL": "spherical", "QUADRATIC_SPHERE": "quadratic_sphere", "RADIAL": "radial"}


def _setting(w, node: FlatNode, name: str, default: float) -> str:
    """A node setting that is a number (Brick's frequencies, Magic's depth), as a constant."""
    return w.constant(float(node.props.get(name, default)), "VALUE")


def _gradient(w, node: FlatNode) -> dict | None:
    """Gradient Texture (Cycles' svm_node_tex_gradient): the type chooses the function."""
    kind = GRADIENT_TYPES.get(node.props.get("gradient_type", "LINEAR"))
    co = vector(w, node)
    if kind is None or co is None:
        return None
    fac = w.once("float", f"node_tex_gradient_{kind}({co})")
    return {"Fac": fac, "Color": f"vec4(vec3({fac}), 1.0)"}


def _checker(w, node: FlatNode) -> dict | None:
    """Checker Texture (Cycles' svm_node_tex_checker)."""
    co = vector(w, node)
    if co is None:
        return None
    fac = w.once("float", f"node_tex_checker({co}, {w.arg(node, 'Scale')})")
    colors = ", ".join(w.arg(node, s) for s in ("Color1", "Color2"))
    return {"Fac": fac, "Color": f"node_tex_checker_color({fac}, {colors})"}


def _magic(w, node: FlatNode) -> dict | None:
    """Magic Texture (Cycles' svm_node_tex_magic): Depth a constant, as its other values."""
    co = vector(w, node)
    if co is None:
        return None
    depth = _setting(w, node, "turbulence_depth", 2)
    args = ", ".join([co, w.arg(node, "Scale"), w.arg(node, "Distortion"), depth])
    result = w.once("vec4", f"node_tex_magic({args})")
    return {"Color": f"vec4({result}.rgb, 1.0)", "Fac": f"{result}.w"}


#: The Brick Texture's inputs, in its GLSL function's order (after the coordinate).
BRICK_INPUTS = ("Color1", "Color2", "Mortar", "Scale", "Mortar Size", "Mortar Smooth", "Bias", "Brick Width",
                "Row Height")


def _brick(w, node: FlatNode) -> dict | None:
    """Brick Texture (Cycles' svm_node_tex_brick): its offset and squash settings constants."""
    co = vector(w, node)
    if co is None:
        return None
    settings = (("offset", 0.5), ("offset_frequency", 2), ("squash", 1.0), ("squash_frequency", 2))
    args = [co, *(w.arg(node, s) for s in BRICK_INPUTS), *(_setting(w, node, *s) for s in settings)]
    result = w.once("vec4", f"node_tex_brick({', '.join(args)})")
    return {"Color": f"vec4({result}.rgb, 1.0)", "Fac": f"{result}.w"}


def _radial_tiling(w, node: FlatNode) -> dict:
    """Radial Tiling (Blender 5; Cycles' svm_node_radial_tiling): Normalize chooses the function.
    Not a texture node: its Vector unlinked is the socket's value."""
    co, sides, roundness = (w.arg(node, s) for s in ("Vector", "Sides", "Roundness"))
    fn = "node_radial_tiling_normalized" if node.props.get("normalize") else "node_radial_tiling"
    result = w.once("vec4", f"{fn}({co}, {sides}, {roundness})")
    return {"Segment Coordinates": f"vec3({result}.xy, 0.0)", "Segment Width": f"{result}.z",
            "Segment Rotation": f"{result}.w", "Segment ID": f"node_radial_tiling_id({co}, {sides})"}


# --- Voronoi ------------------------------------------------------------------------------------

#: The Voronoi Texture's features, each its GLSL functions' name (glsl/node_tex_voronoi.glsl).
VORONOI_FEATURES = {"F1": "f1", "F2": "f2", "SMOOTH_F1": "smooth_f1", "DISTANCE_TO_EDGE": "distance_to_edge",
                    "N_SPHERE_RADIUS": "n_sphere_radius"}
#: Its distance metrics, each a constant of the GLSL (Blender spells Chebychev so).
VORONOI_METRICS = {m: f"VORONOI_{m}" for m in ("EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI")}
#: How the Blender that read the file hashes a cell (the reader's ``voronoi_cells``): Cycles 5.0
#: its integer index, 4.x its float coordinates; 5.0's where the reader does not say.
VORONOI_CELLS = {"INT": "VORONOI_CELLS_INT", "FLOAT": "VORONOI_CELLS_FLOAT"}


def _voronoi(w, node: FlatNode) -> dict | None:
    """Voronoi Texture (Cycles' svm_node_tex_voronoi): one function per feature and dimension
    count; the metric, the cells' hash and Normalize its constant arguments. Where the metric
    changes nothing (1D; Distance to Edge and N-Sphere Radius are Euclidean) the source names
    Euclidean whatever the setting: one program for every metric."""
    props = node.props
    dims = DIMENSIONS.get(props.get("voronoi_dimensions", "3D"))
    feature = VORONOI_FEATURES.get(props.get("feature", "F1"))
    metric = VORONOI_METRICS.get(props.get("distance", "EUCLIDEAN"))
    cells = VORONOI_CELLS.get(props.get("voronoi_cells", "INT"))
    co = vector(w, node)
    if None in (dims, feature, metric, cells, co):
        return None
    if dims == "1d" or feature in ("distance_to_edge", "n_sphere_radius"):
        metric = VORONOI_METRICS["EUCLIDEAN"]
    fractal = ", ".join(scalar(w, node, s) for s in ("Scale", "Detail", "Roughness", "Lacunarity"))
    shape = ", ".join(scalar(w, node, s) for s in ("Smoothness", "Exponent", "Randomness"))
    normalize = "true" if props.get("normalize") else "false"
    v = w.once("VoronoiTexture", f"node_tex_voronoi_{feature}_{dims}({co}, {scalar(w, node, 'W')}, "
                                 f"vec4({fractal}), vec3({shape}), {metric}, {cells}, {normalize})")
    fields = {"Distance": "distance", "Color": "color", "Position": "position", "W": "w", "Radius": "radius"}
    # the outputs Blender shows for the feature and dimensions (the reader leaves hidden ones out)
    return {socket: f"{v}.{field}" for socket, field in fields.items() if socket in node.outputs}


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
#: How the Blender that read the file takes the phase over 2 pi (the reader's ``wave_phase``): 4.5
#: and 5.0 times the reciprocal, 4.2 divided; 5.0's where the reader does not say.
WAVE_PHASES = {"RECIPROCAL": "WAVE_PHASE_RECIPROCAL", "DIVIDE": "WAVE_PHASE_DIVIDE"}


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
    distorted by fBM noise, the phase over 2 pi as the reading Blender's Cycles takes it; Color is
    Fac in each channel."""
    props = node.props
    kind = props.get("wave_type", "BANDS")
    directions = WAVE_BANDS_DIRECTIONS if kind == "BANDS" else WAVE_RINGS_DIRECTIONS
    direction = directions.get(props.get("bands_direction" if kind == "BANDS" else "rings_direction", "X"))
    profile = WAVE_PROFILES.get(props.get("wave_profile", "SIN"))
    rule = WAVE_PHASES.get(props.get("wave_phase", "RECIPROCAL"))
    co = vector(w, node)
    if kind not in WAVE_TYPES or direction is None or profile is None or rule is None or co is None:
        return None
    args = ", ".join(w.arg(node, socket) for socket in ("Scale", "Distortion", "Detail", "Detail Scale",
                                                          "Detail Roughness", "Phase Offset"))
    fac = w.once("float", f"node_tex_wave({co}, {args}, {WAVE_TYPES[kind]}, {direction}, {profile}, {rule})")
    return {"Fac": fac, "Color": f"vec4(vec3({fac}), 1.0)"}


EMITTERS = {
    "ShaderNodeTexWhiteNoise": _white_noise,
    "ShaderNodeTexNoise": _noise,
    "ShaderNodeTexWave": _wave,
    "ShaderNodeTexGabor": _gabor,
    "ShaderNodeTexGradient": _gradient,
    "ShaderNodeTexChecker": _checker,
    "ShaderNodeTexMagic": _magic,
    "ShaderNodeTexBrick": _brick,
    "ShaderNodeRadialTiling": _radial_tiling,
    "ShaderNodeTexVoronoi": _voronoi,
}
