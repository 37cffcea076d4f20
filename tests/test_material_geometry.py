"""What a compiled graph reads of the mesh beyond the fragment, as the engine draws it, against
Cycles: the Geometry node's Parametric, Pointiness and Random Per Island, the Wireframe node (world
size and pixel size), Texture Coordinate's and UV Map's From Instancer, and the Holdout BSDF.

One scene, under a perspective camera, both renderers writing AOVs at pixel centres: a lumpy
sphere (its vertices moved by a seeded noise: every pointiness), a cylinder with n-gon caps (the
triangles Blender makes of them), three separate cubes in one mesh (islands) and, instanced on the
faces of a hidden grid, small cubes whose material reads their instancer's coordinates. A second
scene: Holdout on opaque and partly transparent surfaces, with the film transparent and not,
compared in colour and alpha.
"""

from __future__ import annotations

import math
import time

import bpy
import numpy as np
import pytest
import scenes
from gpu_harness import run_on_gpu
from test_cycles import _cycles
from test_material_aovs import engine_and_cycles_aovs

from addon.blender import extract
from addon.frame import passes, renderer
from addon.materials import mesh_attributes

SIZE = 96

#: AOV name -> (node kind, output, AOV type, node settings)
AOVS = {
    "position": ("ShaderNodeNewGeometry", "Position", "COLOR", {}),
    "parametric": ("ShaderNodeNewGeometry", "Parametric", "COLOR", {}),
    "pointiness": ("ShaderNodeNewGeometry", "Pointiness", "VALUE", {}),
    "island": ("ShaderNodeNewGeometry", "Random Per Island", "VALUE", {}),
    "wire": ("ShaderNodeWireframe", "Fac", "VALUE", {"use_pixel_size": False}),
    "wire_pixel": ("ShaderNodeWireframe", "Fac", "VALUE", {"use_pixel_size": True}),
    "instancer_generated": ("ShaderNodeTexCoord", "Generated", "COLOR", {"from_instancer": True}),
    "instancer_uv": ("ShaderNodeTexCoord", "UV", "COLOR", {"from_instancer": True}),
    "instancer_uv_map": ("ShaderNodeUVMap", "UV", "COLOR", {"from_instancer": True}),
}
#: Wireframe sizes: world units, pixels.
WIRE_SIZE, WIRE_PIXELS = 0.03, 1.0


def _material(scene, name: str) -> bpy.types.Material:
    """A diffuse material writing every AOV of ``AOVS`` (each node once per settings)."""
    mat = bpy.data.materials.new(name)
    tree = scenes.node_tree(mat)
    tree.nodes.clear()
    surface = tree.nodes.new("ShaderNodeBsdfDiffuse")
    tree.links.new(surface.outputs["BSDF"], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    made = {}
    names = {aov.name for aov in scene.view_layers[0].aovs}
    for aov_name, (kind, output, aov_type, props) in AOVS.items():
        key = (kind, tuple(sorted(props.items())))
        node = made.get(key)
        if node is None:
            node = made[key] = tree.nodes.new(kind)
            for prop, value in props.items():
                setattr(node, prop, value)
            if kind == "ShaderNodeWireframe":
                node.inputs["Size"].default_value = WIRE_PIXELS if props["use_pixel_size"] else WIRE_SIZE
        if aov_name not in names:
            aov = scene.view_layers[0].aovs.add()
            aov.name, aov.type = aov_name, aov_type
        out = tree.nodes.new("ShaderNodeOutputAOV")
        out.aov_name = aov_name
        tree.links.new(node.outputs[output], out.inputs["Color" if aov_type == "COLOR" else "Value"])
    return mat


def _lumpy_sphere(scene, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=14, ring_count=7, radius=0.55, location=(-0.75, 0.0, 0.6))
    obj = bpy.context.active_object
    mesh = obj.data
    rng = np.random.default_rng(7)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    co *= rng.uniform(0.85, 1.15, (len(co), 1)).astype(np.float32)
    mesh.vertices.foreach_set("co", co.ravel())
    mesh.update()
    bpy.ops.object.shade_smooth()
    obj.rotation_euler = (0.3, 0.2, 0.4)
    mesh.materials.append(mat)
    return obj


def _islands(scene, mat):
    """A cylinder with n-gon caps and three cubes, one mesh."""
    bpy.ops.mesh.primitive_cylinder_add(vertices=9, radius=0.3, depth=0.5, end_fill_type="NGON",
                                        location=(0.55, 0.0, 0.85), rotation=(0.9, 0.2, 0.3))
    cylinder = bpy.context.active_object
    for k, (x, y, z) in enumerate([(0.3, 0.1, 0.25), (0.8, -0.1, 0.3), (1.25, 0.2, 0.75)]):
        bpy.ops.mesh.primitive_cube_add(size=0.35, location=(x, y, z), rotation=(0.4 * k, 0.7, 0.2 * k))
    split = bpy.data.meshes.new("Split")  # a cube of six unjoined faces: six islands, welded corners
    corners = [(x, y, z) for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (-0.2, 0.2)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    split.from_pydata([corners[i] for f in faces for i in f], [],
                      [tuple(range(4 * k, 4 * k + 4)) for k in range(6)])
    split_obj = bpy.data.objects.new("CubeSplit", split)
    split_obj.location, split_obj.rotation_euler = (0.0, -0.3, 0.05), (0.5, 0.3, 0.8)
    scene.collection.objects.link(split_obj)
    cubes = [o for o in scene.objects if o.name.startswith("Cube")]
    for o in (cylinder, *cubes):
        o.select_set(True)
    bpy.context.view_layer.objects.active = cylinder
    bpy.ops.object.join()
    cylinder.data.materials.clear()
    cylinder.data.materials.append(mat)
    return cylinder


def _instances(scene, mat):
    """Small cubes instanced on the faces of a grid (hidden), their material reading the grid's
    Generated and UV at each face."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=4, y_subdivisions=3, size=1.3,
                                    location=(-0.65, 0.0, -0.75), rotation=(1.35, 0.0, 0.1))
    grid = bpy.context.active_object
    grid.instance_type = "FACES"
    grid.show_instancer_for_render = False
    bpy.ops.mesh.primitive_cube_add(size=0.22)
    cube = bpy.context.active_object
    cube.data.materials.append(mat)
    cube.parent = grid
    return grid


def _particles(scene, mat):
    """Small cubes as the hair particles of a plane (their instancer's Generated and UV at each
    hair's root)."""
    bpy.ops.mesh.primitive_plane_add(size=1.1, location=(0.75, 0.3, -0.75), rotation=(1.3, 0.0, -0.2))
    emitter = bpy.context.active_object
    emitter.show_instancer_for_render = False
    bpy.ops.mesh.primitive_cube_add(size=0.25, location=(5.0, 5.0, 5.0))
    cube = bpy.context.active_object
    cube.data.materials.append(mat)
    emitter.modifiers.new("Hair", "PARTICLE_SYSTEM")
    settings = emitter.particle_systems[0].settings
    settings.type = "HAIR"
    settings.count = 7
    settings.hair_length = 0.2
    settings.render_type = "OBJECT"
    settings.instance_object = cube
    settings.particle_size = 4.0
    cube.hide_render = True
    return emitter


def _scene():
    scene = scenes.reset(size=SIZE)
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = (0.1, -4.0, 0.3), (math.radians(86.0), 0.0, math.radians(2.0))
    cam.data.lens = 40.0
    scene.collection.objects.link(cam)
    scene.camera = cam
    mat = _material(scene, "Geometry")
    _lumpy_sphere(scene, mat)
    _islands(scene, mat)
    instanced = _material(scene, "Instanced")
    _instances(scene, instanced)
    _particles(scene, instanced)
    return scene


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    kinds = {name: aov_type for name, (_, _, aov_type, _) in AOVS.items()}
    return engine_and_cycles_aovs(_scene(), tmp_path_factory.mktemp("geometry"), kinds, SIZE)


#: Measured with bpy 5.0.1 on 1,619 pixels (2026-12): the largest difference of the AOVs whose
#: values vary smoothly, and how many pixels differ by more than 1e-3 (a pixel centre on a triangle's
#: edge falls in either triangle: Parametric jumps there; a Wireframe's edge pixel either side of
#: its width). Bounds 3x, plus 1e-6 (a pixel) for a measured 0.
MEASURED = {"parametric": (2.8e-5, 1), "pointiness": (5.4e-7, 0), "island": (0.0, 0), "wire": (0.0, 0),
            "wire_pixel": (0.0, 2), "instancer_generated": (0.0, 0), "instancer_uv": (0.0, 0),
            "instancer_uv_map": (0.0, 0)}


@pytest.mark.parametrize("name", MEASURED)
def test_geometry_aov_matches_cycles(rendered, name):
    ours, theirs, inner = rendered
    assert inner.sum() > 1000
    a, b = ours[name][inner], theirs[name][inner]
    err = np.abs(a - b).max(axis=-1)
    apart = err > 1e-3
    largest = float(err[~apart].max())
    print(f"{name}: {apart.sum()} of {inner.sum()} px apart, the rest within {largest:.2e}")
    measured, pixels = MEASURED[name]
    assert apart.sum() <= 3 * pixels + 1, f"{name}: {apart.sum()} pixels apart (measured {pixels})"
    assert largest <= 3.0 * measured + 1e-6, f"{name}: {largest:.2e} (measured {measured:.2e})"


def test_geometry_aovs_vary(rendered):
    """What the comparisons compare is not trivial: the islands, the wires' share, the instances."""
    _ours, theirs, inner = rendered
    islands = len(np.unique(theirs["island"][inner]))
    wires = float(theirs["wire"][inner].mean()), float(theirs["wire_pixel"][inner].mean())
    uvs = len(np.unique(theirs["instancer_uv"][inner].round(5), axis=0))
    generated = len(np.unique(theirs["instancer_generated"][inner].round(5), axis=0))
    pointiness = np.ptp(theirs["pointiness"][inner])
    print(f"{islands} islands, wires {wires[0]:.2f} and {wires[1]:.2f} of the pixels, {uvs} instancer UVs, "
          f"{generated} instancer Generated, pointiness spread {pointiness:.2f}")
    # (the sphere, a joined mesh of a cylinder, three cubes and the faces of a six-face cube seen, two
    # instanced cubes)
    assert islands >= 8 and all(0.15 < w < 0.6 for w in wires) and uvs >= 19 and generated >= 8
    assert pointiness > 0.1


# --- the mesh's attributes, apart --------------------------------------------------------------

def test_pointiness_of_welded_duplicates():
    """A cube whose faces are separate (24 vertices, each corner three times) has the pointiness of
    the welded cube: a corner's normal (1, 1, 1)/sqrt 3 against its three edges' mean direction
    -(1, 1, 1)/3, the angle's cosine -1/3 x sqrt 3 ... over pi, blurred with its three neighbours' equal
    values: acos(-1/sqrt 3) / pi everywhere (an independent closed form)."""
    corners = np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    positions = corners[[i for f in faces for i in f]]
    normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    edges = [(4 * k + i, 4 * k + (i + 1) % 4) for k in range(6) for i in range(4)]
    values = mesh_attributes.pointiness(positions, normals, np.array(edges))
    expected = math.acos(-1.0 / math.sqrt(3.0)) / math.pi
    print(f"pointiness {values.min():.7f} .. {values.max():.7f}, closed form {expected:.7f}")
    assert np.abs(values - expected).max() < 1e-6
    islands = mesh_attributes.random_per_island(np.array(edges), 24, np.arange(0, 24, 4))
    assert len(np.unique(islands)) == 6  # no edge joins two faces: six islands


def test_random_per_island_of_a_large_grid():
    """The islands of a 500 x 500 grid (499,000 edges): one island, one value. Its time is printed,
    not asserted (timings belong in benchmarks): 0.09 s of CPU on 4.2, 4.5 and 5.0; a quadratic join
    would show as this test's duration."""
    n = 500
    index = np.arange(n * n).reshape(n, n)
    edges = np.concatenate([np.stack([index[:, :-1].ravel(), index[:, 1:].ravel()], 1),
                            np.stack([index[:-1].ravel(), index[1:].ravel()], 1)])
    start = time.process_time()
    values = mesh_attributes.random_per_island(edges, n * n, index[:-1, :-1].ravel())
    print(f"499,000 edges: {time.process_time() - start:.2f} s of CPU time")
    assert len(np.unique(values)) == 1, f"{len(np.unique(values))} values over one island"


# --- Holdout -------------------------------------------------------------------------------------

HOLDOUT_SIZE = 48
#: Where each case's square lies (its centre's x; 0.25 wide: 6 pixels, its edges on pixel edges):
#: over the red plane (top row of squares) and over the world (bottom row).
HOLDOUT_CASES = {"pure": -0.75, "mixed": -0.375, "transparent": 0.0, "principled": 0.375, "stacked": 0.75}
#: Cycles' alpha of the partly transparent squares over the world, the film opaque and transparent:
#: 1 - the Holdout's weight, less what the film's transparent world adds through the rest.
HOLDOUT_ALPHA = {"transparent": (0.6, 0.0), "principled": (0.7, 0.35), "stacked": (0.6, 0.3)}


def _emission(tree, color):
    node = tree.nodes.new("ShaderNodeEmission")
    node.inputs["Color"].default_value = (*color, 1.0)
    return node.outputs[0]


def _principled_alpha(tree, alpha: float):
    """A Principled BSDF that emits (0.2, 0.5, 0.9) and reflects nothing (black base, no
    specular), of ``alpha``."""
    node = tree.nodes.new("ShaderNodeBsdfPrincipled")
    node.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    node.inputs["Specular IOR Level"].default_value = 0.0
    node.inputs["Emission Color"].default_value = (0.2, 0.5, 0.9, 1.0)
    node.inputs["Emission Strength"].default_value = 1.0
    node.inputs["Alpha"].default_value = alpha
    return node.outputs[0]


def _holdout_material(case: str) -> bpy.types.Material:
    """pure: a Holdout alone; mixed: green emission mixed with a Holdout by Generated's x (0 .. 1
    across the square); transparent: a Transparent BSDF mixed with a Holdout at 0.4; principled: a
    Principled BSDF of Alpha 0.5 mixed with a Holdout at 0.3; behind: a Principled BSDF of Alpha 0.5
    alone (the stacked square's second layer, behind a transparent one)."""
    mat = bpy.data.materials.new(case)
    tree = scenes.node_tree(mat)
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"]
    if case == "behind":
        tree.links.new(_principled_alpha(tree, 0.5), out)
        return mat
    holdout = tree.nodes.new("ShaderNodeHoldout").outputs[0]
    if case == "pure":
        tree.links.new(holdout, out)
        return mat
    mix = tree.nodes.new("ShaderNodeMixShader")
    if case == "mixed":
        uv = tree.nodes.new("ShaderNodeSeparateXYZ")
        tree.links.new(tree.nodes.new("ShaderNodeTexCoord").outputs["Generated"], uv.inputs[0])
        tree.links.new(uv.outputs["X"], mix.inputs["Fac"])
        tree.links.new(_emission(tree, (0.1, 0.9, 0.3)), mix.inputs[1])
    elif case == "principled":
        mix.inputs["Fac"].default_value = 0.3
        tree.links.new(_principled_alpha(tree, 0.5), mix.inputs[1])
    else:
        mix.inputs["Fac"].default_value = 0.4
        tree.links.new(tree.nodes.new("ShaderNodeBsdfTransparent").outputs[0], mix.inputs[1])
    tree.links.new(holdout, mix.inputs[2])
    tree.links.new(mix.outputs[0], out)
    return mat


def _holdout_scene(film_transparent: bool):
    """A red emitting plane over the top half of the view, the world (0.2, 0.3, 0.4) below; each
    case's square over each (the stacked one: the transparent Holdout's over a Principled BSDF of
    Alpha 0.5)."""
    scene = scenes.reset(size=HOLDOUT_SIZE)
    scene.world.color = (0.2, 0.3, 0.4)
    if scene.world.node_tree is not None:  # Blender 5's worlds are node-based (4.x: the colour)
        background = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
        background.inputs["Color"].default_value = (0.2, 0.3, 0.4, 1.0)
        background.inputs["Strength"].default_value = 1.0
    scene.render.film_transparent = film_transparent
    scenes.ortho_camera(scene)
    back = bpy.data.materials.new("Red")
    tree = scenes.node_tree(back)
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(_emission(tree, (1.0, 0.0, 0.0)), output.inputs["Surface"])
    scenes.plane(scene, size=2.0, location=(0.0, 1.0, -1.0), material=back)
    behind = _holdout_material("behind")
    for case, x in HOLDOUT_CASES.items():
        mat = _holdout_material("transparent" if case == "stacked" else case)
        for y in (0.5, -0.5):
            scenes.plane(scene, size=0.25, location=(x, y, 0.0), material=mat)
            if case == "stacked":
                scenes.plane(scene, size=0.25, location=(x, y, -0.5), material=behind)
    return scene


@pytest.fixture(scope="module")
def holdout_renders(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("holdout")
    out = {}
    for film in (False, True):
        scene = _holdout_scene(film)
        ours = scenes.render(scene, tmp / f"ours_{film}.exr").astype(np.float64)
        theirs = _cycles(scene, tmp / f"cycles_{film}.exr", samples=1).astype(np.float64)
        out[film] = (ours, theirs)
    return out


def _square(case: str, over_plane: bool) -> tuple[slice, slice]:
    """The pixels of a case's square (rows top first, columns)."""
    column = int(round((HOLDOUT_CASES[case] + 1.0) * HOLDOUT_SIZE / 2.0))
    row = HOLDOUT_SIZE // 4 if over_plane else 3 * HOLDOUT_SIZE // 4
    return slice(row - 3, row + 3), slice(column - 3, column + 3)


@pytest.mark.parametrize("film", [False, True], ids=["film", "film_transparent"])
def test_holdout_matches_cycles(holdout_renders, film):
    """Colour and alpha against Cycles over the whole frame (the squares, the red plane, the world):
    Holdouts on opaque and on partly transparent surfaces (a Transparent BSDF, a Principled BSDF's
    Alpha, a second transparent layer behind), over an opaque object and over the world. A peeled
    layer's Holdout share is carried through the transparency pass and taken out of the alpha."""
    ours, theirs = holdout_renders[film]
    colour = float(np.abs(ours[..., :3] - theirs[..., :3]).max())
    alpha = float(np.abs(ours[..., 3] - theirs[..., 3]).max())
    print(f"film {'transparent' if film else 'opaque'}: colour within {colour:.2e}, alpha within {alpha:.2e}")
    # measured: colour 6.4e-7, alpha 7.2e-7 (the mixed square: its factor from Generated)
    assert colour < 1e-6 and alpha < 1e-6, (colour, alpha)
    for case in HOLDOUT_CASES:  # what Cycles gives: the squares hide the red plane, cut the alpha
        r, c = _square(case, True)
        cut = 1.0 - theirs[r, c, 3].mean()
        assert cut > 0.25, (case, cut)
    # the partly transparent Holdouts over the world: Cycles' alpha (the coverage's before the
    # share was carried: 1 and 0.4 for the transparent square)
    for case, expected in HOLDOUT_ALPHA.items():
        r, c = _square(case, False)
        assert np.abs(theirs[r, c, 3] - expected[film]).max() < 1e-6, (case, theirs[r, c, 3])
        assert np.abs(ours[r, c, 3] - expected[film]).max() < 1e-6, (case, ours[r, c, 3])


def test_holdout_share_kept_only_while_a_peeled_holdout_is_drawn():
    """The transparency pass's Holdout colours (the layer's and both accumulators' second colour)
    exist while a peeled material holds a Holdout: three textures more, dropped by the first frame
    without one (the same renderer), and every one freed with the renderer."""
    state = {}

    def frame(depsgraph):
        r = state.setdefault("renderer", renderer.Renderer())
        r.render(extract.snapshot(depsgraph, HOLDOUT_SIZE, HOLDOUT_SIZE))
        step = next(p for p in r._passes.values() if isinstance(p, passes.TransparencyPass))
        return len(step.textures()), step

    scene = _holdout_scene(False)
    with_holdout, step = run_on_gpu(frame)
    behind = _holdout_material("behind")
    for obj in scene.objects:  # the Holdouts on partly transparent surfaces replaced
        name = obj.active_material.name if obj.active_material is not None else ""
        if name.startswith(("transparent", "principled")):
            obj.active_material = behind
    without, _ = run_on_gpu(frame)
    state["renderer"].free()
    assert with_holdout == without + 3, (with_holdout, without)
    assert step.textures() == [] and step.holdout is None


def test_wireframe_mask_casts_its_wires(tmp_path):
    """An icosphere cut to its wires (Wireframe mixing a Diffuse BSDF with a Transparent one) under a
    shadowing sun, over a ground: the wires drawn and their shadow cast through the shadow map's
    coverage program (which reads the triangle texture too), against Cycles."""
    scene = scenes.reset(size=48)
    scenes.ortho_camera(scene, scale=3.0)
    sun = scenes.light(scene, "SUN", energy=3.0, rotation=(0.6, 0.0, 0.3))
    sun.data.use_shadow = True
    scenes.plane(scene, size=3.0, location=(0.0, 0.0, -1.0), material=bpy.data.materials.new("Ground"))
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1, radius=0.9)
    mat = bpy.data.materials.new("Wires")
    tree = scenes.node_tree(mat)
    tree.nodes.clear()
    wire = tree.nodes.new("ShaderNodeWireframe")
    wire.inputs["Size"].default_value = 0.1
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(wire.outputs["Fac"], mix.inputs["Fac"])
    tree.links.new(tree.nodes.new("ShaderNodeBsdfTransparent").outputs[0], mix.inputs[1])
    tree.links.new(tree.nodes.new("ShaderNodeBsdfDiffuse").outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    bpy.context.active_object.data.materials.append(mat)
    ours = scenes.render(scene, tmp_path / "ours.exr")[..., :3].astype(np.float64)
    theirs = _cycles(scene, tmp_path / "cycles.exr", samples=1)[..., :3].astype(np.float64)
    apart = np.abs(ours - theirs).mean(-1) > 0.05
    shadowed = theirs.mean(-1) < 0.5 * np.median(theirs.mean(-1))
    print(f"{apart.sum()} of {apart.size} px apart by more than 0.05; {shadowed.sum()} px shadowed or wire")
    assert shadowed.sum() > 250  # the wires and their shadow
    # measured 29 (pixels on a wire's or its shadow's edge: the shadow map's texels)
    assert apart.sum() <= 87, f"{apart.sum()} px apart (measured 29)"
