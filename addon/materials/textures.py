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


EMITTERS = {
    "ShaderNodeTexWhiteNoise": _white_noise,
    "ShaderNodeTexVoronoi": _voronoi,
}
