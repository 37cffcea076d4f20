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


EMITTERS = {
    "ShaderNodeTexWhiteNoise": _white_noise,
    "ShaderNodeTexGabor": _gabor,
}
