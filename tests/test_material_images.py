"""The Image Texture node compiled (materials/codegen.py, glsl/node_texture_image.glsl) against
Cycles evaluating the same node into AOVs.

Images are made here from random texels (7 x 5 and 5 x 7: texel boundaries and wrapping show at
33 x 33 pixels): an 8-bit sRGB PNG with alpha (0, 255 and between), an 8-bit Non-Color PNG, a
float EXR with alpha (values below 0 and above 1), a generated (not a file's) float image. Each is
read into ``ImageData`` by the engine's own reader (image_reader.read_image) and uploaded as the
engine uploads it (gpu_scene.image_texture); Cycles reads the files itself. The Vector comes from
the UV through a Vector Math multiply-add, to cross the image's edges on both sides."""

from __future__ import annotations

import bpy
import numpy as np
import OpenEXR
import pytest
from glsl_harness import evaluate
from test_material_nodes import (
    FRAGMENT_AOVS,
    SIZE,
    _aov,
    _compare,
    _node,
    _plane_scene,
    cycles_aovs_and_graph,
)

from addon.blender import images as image_reader
from addon.blender import nodes as reader
from addon.materials import codegen, graph

INTERPOLATIONS = ("Closest", "Linear", "Cubic", "Smart")
EXTENSIONS = ("REPEAT", "EXTEND", "CLIP", "MIRROR")
IMAGES = ("srgb", "data", "exr", "generated")


def _png(path, texels: np.ndarray, colorspace: str) -> bpy.types.Image:
    """An 8-bit RGBA PNG of ``texels`` (h, w, 4 bytes, bottom row first), loaded as a file."""
    h, w = texels.shape[:2]
    image = bpy.data.images.new(path.stem, w, h, alpha=True)
    image.pixels.foreach_set((texels.astype(np.float32) / 255.0).ravel())
    image.filepath_raw, image.file_format = str(path), "PNG"
    image.save()
    bpy.data.images.remove(image)
    image = bpy.data.images.load(str(path))
    image.colorspace_settings.name = colorspace
    return image


def _exr(path, texels: np.ndarray) -> bpy.types.Image:
    """A 32-bit float RGBA EXR of ``texels`` (h, w, 4; rows top first as EXR stores them)."""
    channels = {c: np.ascontiguousarray(texels[..., i], np.float32) for i, c in enumerate("RGBA")}
    header = {"compression": OpenEXR.NO_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))
    return bpy.data.images.load(str(path))


def _generated(texels: np.ndarray) -> bpy.types.Image:
    """A float image made in Blender (not a file: Cycles reads Blender's own pixels)."""
    h, w = texels.shape[:2]
    image = bpy.data.images.new("generated", w, h, alpha=True, float_buffer=True)
    image.pixels.foreach_set(texels.astype(np.float32).ravel())
    image.use_half_precision = False  # FLOAT storage (the EXR keeps Blender's default: HALF)
    return image


def _make_image(kind: str, tmp) -> bpy.types.Image:
    rng = np.random.default_rng({"srgb": 1, "data": 2, "exr": 3, "generated": 4}[kind])
    if kind in ("srgb", "data"):
        texels = rng.integers(0, 256, (5, 7, 4))
        texels[..., 3] = rng.choice([0, 255, 40, 128, 200, 255], (5, 7))  # alpha 0, 1 and between
        return _png(tmp / f"{kind}.png", texels, "sRGB" if kind == "srgb" else "Non-Color")
    texels = rng.uniform(-0.2, 2.0, (7, 5, 4))
    texels[..., 3] = rng.choice([0.0, 1.0, 0.3, 0.7, 1.0], (7, 5))
    return _exr(tmp / "float.exr", texels) if kind == "exr" else _generated(texels)


def _vector(tree, u, v, scale=(2.6, 2.2, 1.0), offset=(-0.8, -0.6, 0.0)):
    """(u, v, 0) x scale + offset through Vector Math (itself compiled): -0.8 .. 1.8 across."""
    uv = _node(tree, "ShaderNodeCombineXYZ", {"X": u, "Y": v}, "Vector")
    return _node(tree, "ShaderNodeVectorMath", {"Vector": uv, "Vector_001": scale, "Vector_002": offset},
                 "Vector", operation="MULTIPLY_ADD")


def _texture(tree, image, vector, **settings):
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    for key, value in settings.items():
        setattr(node, key, value)
    if vector is not None:
        tree.links.new(vector, node.inputs["Vector"])
    return node


def _outputs(scene, tree, name, node, alpha=True):
    _aov(scene, tree, f"{name}_color", node.outputs["Color"], "COLOR")
    if alpha:
        _aov(scene, tree, f"{name}_alpha", node.outputs["Alpha"])


def _evaluate(compiled: codegen.Compiled, fragment: dict, samplers: dict, object_to_world) -> dict:
    """Every target at every fragment in one pass: the fragments repeated once per target, a
    selector row choosing which target each copy writes."""
    consts = ", ".join(f"vec4({', '.join(repr(float(x)) for x in row)})" for row in compiled.constants)
    m = np.asarray(object_to_world, np.float64)
    mat = "mat4(" + ", ".join(repr(float(x)) for x in m.T.ravel()) + ")"  # GLSL: column by column
    source = (f"const vec4 graph_constants[{len(compiled.constants)}] = vec4[]({consts});\n"
              f"#define GRAPH_CONST(i) graph_constants[i]\n{compiled.source}")
    names = list(compiled.targets)
    decls = " ".join(f"{compiled.targets[n]} {n};" for n in names)
    call = (f"GraphInputs g; g.uv = vec3(uv.xy, 0.0); g.position = g_position.xyz; g.n = g_normal.xyz; "
            f"g.ng = g_normal.xyz; g.i = g_incoming.xyz; g.backfacing = false; g.object_to_world = {mat}; "
            f"g.world_to_object = inverse(g.object_to_world); {decls} "
            f"{compiled.name}(g, {', '.join(names)});")
    select = " ".join(f"if (k == {i}) result = vec4({n}{'.rgb' if compiled.targets[n] == 'vec4' else ''}"
                      f"{', 0.0' if compiled.targets[n] == 'vec4' else ''});" for i, n in enumerate(names))
    rows = len(next(iter(fragment.values())))
    inputs = {name: np.tile(a, (len(names), 1)) for name, a in fragment.items()}
    selector = np.repeat(np.arange(len(names), dtype=np.float32), rows)
    inputs["sel"] = np.stack([selector, *([np.zeros_like(selector)] * 3)], axis=1)
    values = evaluate(f"{call} int k = int(sel.x + 0.5); {select}", inputs, extra=codegen.library(source),
                      source=source, samplers=samplers)
    out = {}
    for i, n in enumerate(names):
        block = values[i * rows:(i + 1) * rows].astype(np.float64)
        out[n] = block[:, :3] if compiled.targets[n] == "vec4" else block[:, :1]
    return out


def _against_cycles(scene, mat, obj, tmp) -> dict:
    """Every AOV but the fragment's: (ours, Cycles') on covered pixels, with the images the
    material reads read by the engine's reader."""
    images: dict = {}
    cycles, compiled = cycles_aovs_and_graph(scene, mat, tmp, images)
    warnings: list[str] = []
    samplers = {f"graph_image_{k}": image_reader.read_image(key, images[key], warnings)
                for k, key in enumerate(compiled.images)}
    assert not warnings, warnings
    fragment = {}
    for name in FRAGMENT_AOVS:
        rows = cycles[f"ViewLayer.{name}"].reshape(SIZE * SIZE, -1)[:, :3]
        fragment[name] = np.concatenate([rows, np.zeros((len(rows), 1))], axis=1)
    ours = _evaluate(compiled, fragment, samplers, obj.matrix_world)
    covered = np.linalg.norm(fragment["g_normal"][:, :3], axis=1) > 0.5
    out = {}
    for target, value in ours.items():
        name = target[2:]
        ref = cycles.get(f"ViewLayer.{name}.X", cycles.get(f"ViewLayer.{name}"))
        out[name] = (value[covered], ref.reshape(SIZE * SIZE, -1)[covered, :value.shape[1]])
    out["_source"] = compiled
    return out


# --- interpolation x extension, per image ---------------------------------------------------------

FILTER_CASES = [f"{i.lower()}_{e.lower()}" for i in INTERPOLATIONS for e in EXTENSIONS]


@pytest.fixture(scope="module", params=IMAGES)
def filter_results(request, tmp_path_factory):
    """One image under every interpolation and extension, Color and Alpha read (the colour then
    divided by alpha), and with Linear and Cubic the Color alone (premultiplied, Cycles' rule)."""
    scene, mat, tree, u, v = _plane_scene()
    tmp = tmp_path_factory.mktemp(f"filter_{request.param}")
    image = _make_image(request.param, tmp)
    vector = _vector(tree, u, v)
    for interpolation in INTERPOLATIONS:
        for extension in EXTENSIONS:
            node = _texture(tree, image, vector, interpolation=interpolation, extension=extension)
            _outputs(scene, tree, f"{interpolation.lower()}_{extension.lower()}", node)
    shifted = _vector(tree, u, v, offset=(-0.7, -0.5, 0.0))  # not a node like one above (Cycles merges those)
    for interpolation in ("Linear", "Cubic"):
        node = _texture(tree, image, shifted, interpolation=interpolation, extension="REPEAT")
        _outputs(scene, tree, f"{interpolation.lower()}_color_only", node, alpha=False)
    obj = next(o for o in scene.objects if o.type == "MESH")
    return request.param, _against_cycles(scene, mat, obj, tmp)


def _compare_texture(results, name, bound, measured):
    """A node's Alpha, and its Color; where the Alpha is read the Color is divided by it, a sum
    divided by a sum that may be near 0 (a texel of alpha 0 weighed against others), its last
    bits magnified by 1 / alpha (measured: 0.018 at alpha 5e-7): that colour is compared times
    its own alpha (ours by ours, Cycles' by Cycles'), the sum each divided: not dividing, or
    dividing by another alpha, still shows."""
    color, alpha = f"{name}_color", f"{name}_alpha"
    if alpha in results:
        _compare(results, alpha, bound, measured)
        ours, ref = results[color]
        print(f"{name}: the colour itself differs by {np.abs(ours - ref).max():.2e} at most")
        results = {color: (ours * results[alpha][0], ref * results[alpha][1])}
    _compare(results, color, bound, measured)


#: The largest difference measured (of the range: 1 or the largest value), per image: the float
#: EXR is stored in half floats (Blender's Half Float Precision, on by default for it: the
#: engine's HALF storage, 11 bits), Cycles reads the file's 32-bit floats.
FILTER_MEASURED = {"srgb": 1.4e-6, "data": 1.4e-6, "exr": 2.5e-4, "generated": 1.4e-6}


@pytest.mark.parametrize("case", FILTER_CASES + ["linear_color_only", "cubic_color_only"])
def test_image_texture_filters_match_cycles(filter_results, case):
    kind, results = filter_results
    measured = FILTER_MEASURED[kind]
    _compare_texture(results, case, 4 * measured, f"{kind}: <= {measured:.1e}")


# --- projections, and a node without an image, on a sphere ---------------------------------------

PROJECTION_CASES = ["flat", "sphere", "tube", "box_0", "box_25", "box_100", "box_closest",
                    "box_unlinked_alpha", "missing"]


@pytest.fixture(scope="module")
def projection_results(tmp_path_factory):
    """The sRGB image with alpha on a sphere turned and stretched (the object-space normal is not
    the world's: Box reads it), at the position mapped into about 0..1: Flat, Sphere, Tube, Box
    with Blend 0, 0.25 and 1 (Linear), Box with Closest, Box with its Alpha unread; an Image
    Texture without an image."""
    scene, mat, tree, u, v = _plane_scene(sphere=True)
    obj = next(o for o in scene.objects if o.type == "MESH")
    obj.rotation_euler = (0.4, -0.3, 0.7)
    obj.scale = (1.0, 0.8, 1.1)
    tmp = tmp_path_factory.mktemp("projection")
    image = _make_image("srgb", tmp)
    position = tree.nodes.new("ShaderNodeNewGeometry").outputs["Position"]
    inputs = {"Vector": position, "Vector_001": (0.6, 0.55, 0.6), "Vector_002": (0.5, 0.45, 0.5)}
    co = _node(tree, "ShaderNodeVectorMath", inputs, "Vector", operation="MULTIPLY_ADD")
    for projection in ("FLAT", "SPHERE", "TUBE"):
        _outputs(scene, tree, projection.lower(), _texture(tree, image, co, projection=projection))
    for blend in (0.0, 0.25, 1.0):
        node = _texture(tree, image, co, projection="BOX", projection_blend=blend, extension="EXTEND")
        _outputs(scene, tree, f"box_{blend * 100:.0f}", node)
    node = _texture(tree, image, co, projection="BOX", projection_blend=0.4, interpolation="Closest")
    _outputs(scene, tree, "box_closest", node)
    node = _texture(tree, image, co, projection="BOX", projection_blend=0.3, extension="MIRROR")
    _outputs(scene, tree, "box_unlinked_alpha", node, alpha=False)
    _outputs(scene, tree, "missing", _texture(tree, None, co))
    return _against_cycles(scene, mat, obj, tmp)


@pytest.mark.parametrize("case", PROJECTION_CASES)
def test_image_texture_projections_match_cycles(projection_results, case):
    # measured: Sphere 4.1e-6, Tube 2.3e-6 (atan2 and the angle on the GPU, through the texel
    # slopes), the others at most 1.2e-6
    if case in ("sphere", "tube"):
        _compare_texture(projection_results, case, 1.5e-5, "<= 4.1e-6")
    else:
        _compare_texture(projection_results, case, 4e-6, "<= 1.2e-6")


# --- the generated source --------------------------------------------------------------------------

def _compile(mat, targets):
    images: dict = {}
    g, groups = reader.read_material(mat, "ALL", images)
    flat = graph.flatten(g, groups)
    aovs = {n.props["aov_name"]: n.name for n in flat.nodes.values() if n.kind == "ShaderNodeOutputAOV"}
    return codegen.compile_graph(flat, {f"r_{t}": (aovs[t], "Color") for t in targets}), images


def test_one_image_at_one_coordinate_is_sampled_once(tmp_path):
    """Two nodes of one image, coordinate and settings (one in a group) share one sample; another
    interpolation samples again; the image is one sampler, named by its key outside the source;
    a Blend or a coordinate's value edited compiles to the same source."""
    scene, mat, tree, u, v = _plane_scene()
    image = _make_image("srgb", tmp_path)
    vector = _vector(tree, u, v)
    a = _texture(tree, image, vector)
    b = _texture(tree, image, vector)
    c = _texture(tree, image, vector, interpolation="Closest")
    d = _texture(tree, image, vector, projection="BOX", projection_blend=0.2)
    for name, node in zip("abcd", (a, b, c, d)):
        _aov(scene, tree, name, node.outputs["Color"], "COLOR")
    compiled, images = _compile(mat, "abcd")
    key = image_reader.image_key(image)
    assert compiled.images == (key,) and set(images) == {key} and images[key] == image
    assert compiled.source.count("node_tex_image_flat(graph_image_0") == 2, compiled.source
    assert compiled.source.count("node_tex_image_box(graph_image_0") == 1
    assert "TEX_IMAGE_CLOSEST" in compiled.source and "TEX_IMAGE_TEXELS_SRGB_ASSOCIATE" in compiled.source
    assert "0.2" not in compiled.source and "2.6" not in compiled.source
    d.projection_blend = 0.7
    next(n for n in tree.nodes if n.bl_idname == "ShaderNodeVectorMath").inputs[1].default_value[0] = 3.0
    assert _compile(mat, "abcd")[0].source == compiled.source


def test_color_is_unassociated_only_where_alpha_is_read(tmp_path):
    """Cycles divides the colour by alpha only where the Alpha output is linked, and never for
    data (Non-Color) or channel-packed images."""
    scene, mat, tree, u, v = _plane_scene()
    image = _make_image("srgb", tmp_path)
    node = _texture(tree, image, None)
    _aov(scene, tree, "c", node.outputs["Color"], "COLOR")
    assert "tex_image_output(s0, false, true)" in _compile(mat, "c")[0].source
    _aov(scene, tree, "a", node.outputs["Alpha"])
    source = _compile(mat, "c")[0].source
    assert "tex_image_output(s0, true, true)" in source and "g.uv" in source
    image.alpha_mode = "CHANNEL_PACKED"
    source = _compile(mat, "c")[0].source
    assert "tex_image_output(s0, false, true)" in source and "TEX_IMAGE_TEXELS_SRGB)" in source
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "STRAIGHT"
    source = _compile(mat, "c")[0].source
    assert "tex_image_output(s0, false, false)" in source and "TEX_IMAGE_TEXELS_BYTES)" in source

