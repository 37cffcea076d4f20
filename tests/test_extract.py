"""extract.snapshot: what the renderer is given for a scene, checked against numbers derived by
hand (triangle counts, matrices set in the test, closed-form light and camera values)."""

from __future__ import annotations

import math

import bpy
import numpy as np
import pytest
import scenes

from addon.blender import extract
from addon.blender import geometry as mesh_reader
from addon.scene import snapshot as S

SIZE = 32


def snap_of() -> S.Snapshot:
    return extract.snapshot(bpy.context.evaluated_depsgraph_get(), SIZE, SIZE)


def new_scene():
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene)
    return scene


def mesh_object(scene, name, verts, faces, location=(0.0, 0.0, 0.0)):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    scene.collection.objects.link(obj)
    return obj


CUBE_VERTS = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
CUBE_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def cube(scene, name="Cube", location=(0.0, 0.0, 0.0)):
    return mesh_object(scene, name, CUBE_VERTS, CUBE_FACES, location)


def only_item(snap):
    assert len(snap.items) == 1
    item = snap.items[0]
    return item, snap.geometries[item.geometry]


# --- 1. modifiers ------------------------------------------------------------------------------

def test_cube_without_modifier_has_12_triangles():
    scene = new_scene()
    cube(scene)
    snap = snap_of()
    assert snap.triangle_count == 12
    assert len(snap.geometries) == 1


def test_subdivision_surface_is_evaluated():
    scene = new_scene()
    obj = cube(scene)
    mod = obj.modifiers.new("Subsurf", "SUBSURF")
    mod.levels = mod.render_levels = 2
    snap = snap_of()
    assert snap.triangle_count == 2 * 6 * 4**2  # 96 quads


def test_shared_mesh_with_and_without_modifier_gives_two_geometries():
    scene = new_scene()
    a = cube(scene, "A")
    b = bpy.data.objects.new("B", a.data)
    b.location = (4.0, 0.0, 0.0)
    scene.collection.objects.link(b)
    mod = a.modifiers.new("Subsurf", "SUBSURF")
    mod.levels = mod.render_levels = 2
    snap = snap_of()
    assert len(snap.items) == 2
    counts = sorted(snap.geometries[i.geometry].triangle_count for i in snap.items)
    assert counts == [12, 192]


# --- 2. instances ------------------------------------------------------------------------------

def test_array_modifier_is_one_geometry_of_three_planes():
    scene = new_scene()
    obj = scenes.plane(scene, size=2.0)
    mod = obj.modifiers.new("Array", "ARRAY")
    mod.count = 3  # relative offset (1, 0, 0): copies at x + 0, 2, 4
    snap = snap_of()
    _, geo = only_item(snap)
    assert len(snap.geometries) == 1
    assert geo.triangle_count == 6
    np.testing.assert_allclose(geo.positions.min(axis=0), [-1, -1, 0], atol=1e-6)
    np.testing.assert_allclose(geo.positions.max(axis=0), [5, 1, 0], atol=1e-6)


def test_collection_instance_shares_one_geometry():
    scene = new_scene()
    coll = bpy.data.collections.new("Source")
    scene.collection.children.link(coll)
    mesh = bpy.data.meshes.new("Quad")
    mesh.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [], [(0, 1, 2, 3)])
    obj = bpy.data.objects.new("Quad", mesh)
    obj.location = (1.0, 2.0, 0.0)
    coll.objects.link(obj)
    empty = bpy.data.objects.new("Instancer", None)
    empty.instance_type = "COLLECTION"
    empty.instance_collection = coll
    empty.location = (10.0, 0.0, 3.0)
    scene.collection.objects.link(empty)

    snap = snap_of()
    assert len(snap.items) == 2
    assert len(snap.geometries) == 1
    assert snap.items[0].geometry == snap.items[1].geometry
    translations = sorted(tuple(float(x) for x in i.matrix[:3, 3]) for i in snap.items)
    np.testing.assert_allclose(translations, [(1, 2, 0), (11, 2, 3)], atol=1e-6)
    assert snap.triangle_count == 4


# --- 3. material slots -------------------------------------------------------------------------

def test_two_material_slots_give_sorted_ranges_and_params():
    scene = new_scene()
    # Face 0 (x in [-1, 0]) uses slot 1, face 1 (x in [0, 1]) uses slot 0: ranges must sort.
    obj = mesh_object(scene, "Two", [(-1, -1, 0), (0, -1, 0), (0, 1, 0), (-1, 1, 0),
                                     (1, -1, 0), (1, 1, 0)], [(0, 1, 2, 3), (1, 4, 5, 2)])
    red = scenes.material("Red", base_color=(1.0, 0.0, 0.0))
    blue = scenes.material("Blue", base_color=(0.0, 0.0, 1.0))
    obj.data.materials.append(red)
    obj.data.materials.append(blue)
    obj.data.polygons[0].material_index = 1
    obj.data.polygons[1].material_index = 0

    snap = snap_of()
    item, geo = only_item(snap)
    assert geo.ranges == [(0, 0, 6), (1, 6, 6)]  # two quads, two triangles (six corners) each
    corners = geo.per_corner(geo.positions)
    assert (corners[0:6, 0] >= 0).all()  # slot 0 = the right-hand face
    assert (corners[6:12, 0] <= 0).all()
    assert item.materials == [red.name_full, blue.name_full]
    assert snap.materials[red.name_full].base_color == pytest.approx((1.0, 0.0, 0.0))
    assert snap.materials[blue.name_full].base_color == pytest.approx((0.0, 0.0, 1.0))


# --- 4. normals --------------------------------------------------------------------------------

def test_flat_cube_normals_are_face_normals():
    scene = new_scene()
    cube(scene)
    _, geo = only_item(snap_of())
    n = geo.per_corner(geo.normals).astype(np.float64)
    axes = np.concatenate([np.eye(3), -np.eye(3)])
    assert np.abs(n @ axes.T).max(axis=1) == pytest.approx(np.ones(len(n)), abs=1e-6)
    p = geo.per_corner(geo.positions).reshape(-1, 3, 3).astype(np.float64)
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    face /= np.linalg.norm(face, axis=1, keepdims=True)
    np.testing.assert_allclose(n.reshape(-1, 3, 3), np.repeat(face[:, None], 3, axis=1),
                               atol=1e-6)


def test_smooth_sphere_normals_are_radial():
    new_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.5, segments=32, ring_count=16,
                                         location=(0.0, 0.0, 0.0))
    bpy.context.active_object.data.shade_smooth()
    _, geo = only_item(snap_of())
    radial = geo.positions / np.linalg.norm(geo.positions, axis=1, keepdims=True)
    dots = np.sum(radial * geo.normals, axis=1)
    assert dots.min() > 0.999
    # Flat shading would not pass: its corner normals are face normals, off-radial at corners.
    bpy.context.active_object.data.shade_flat()
    _, flat = only_item(snap_of())
    flat_radial = flat.positions / np.linalg.norm(flat.positions, axis=1, keepdims=True)
    assert np.sum(flat_radial * flat.normals, axis=1).min() < 0.999


def test_custom_normals_override_geometry():
    scene = new_scene()
    # A plane tilted in object space: face normal (0, -1, 1) / sqrt 2.
    obj = mesh_object(scene, "Tilted", [(-1, -1, -1), (1, -1, -1), (1, 1, 1), (-1, 1, 1)],
                      [(0, 1, 2, 3)])
    obj.data.normals_split_custom_set_from_vertices([(0.0, 0.0, 1.0)] * 4)
    _, geo = only_item(snap_of())
    np.testing.assert_allclose(geo.per_corner(geo.normals), np.tile([0.0, 0.0, 1.0], (6, 1)), atol=1e-4)


# --- 5. cameras --------------------------------------------------------------------------------

def test_perspective_camera():
    scene = scenes.reset(size=SIZE)
    data = bpy.data.cameras.new("Persp")
    data.type = "PERSP"
    data.lens = 50.0
    data.sensor_width = 36.0
    data.sensor_fit = "AUTO"
    cam = bpy.data.objects.new("Persp", data)
    location, rotation = (1.0, -2.0, 3.0), (0.4, -0.3, 0.7)
    cam.location, cam.rotation_euler = location, rotation
    scene.collection.objects.link(cam)
    scene.camera = cam
    c = snap_of().camera

    assert c.is_perspective
    assert c.position == pytest.approx(location, abs=1e-5)
    forward = -scenes.euler_matrix(rotation)[:, 2]
    assert c.forward == pytest.approx(tuple(forward), abs=1e-5)
    point = np.append(np.array(location) + 7.0 * forward, 1.0)
    clip = c.view_projection.astype(np.float64) @ point
    assert clip[3] > 0
    assert clip[:2] / clip[3] == pytest.approx((0.0, 0.0), abs=1e-5)
    # A point one unit to the camera's right at depth d lands at x_ndc = focal scale / d.
    right = scenes.euler_matrix(rotation)[:, 0]
    clip = c.view_projection.astype(np.float64) @ np.append(point[:3] + right, 1.0)
    assert clip[0] / clip[3] == pytest.approx(2.0 * 50.0 / 36.0 / 7.0, rel=1e-4)
    assert c.projection[0, 0] == pytest.approx(2.0 * 50.0 / 36.0, rel=1e-5)


def test_orthographic_camera_scale():
    scene = scenes.reset(size=SIZE)
    scenes.ortho_camera(scene, location=(0.0, 0.0, 5.0), scale=3.0)
    c = snap_of().camera
    assert not c.is_perspective
    assert c.projection[0, 0] == pytest.approx(2.0 / 3.0, rel=1e-6)
    assert c.projection[1, 1] == pytest.approx(2.0 / 3.0, rel=1e-6)
    assert c.forward == pytest.approx((0.0, 0.0, -1.0), abs=1e-6)


def test_missing_camera_raises():
    scenes.reset(size=SIZE)
    with pytest.raises(extract.ExtractError):
        snap_of()


# --- 6. lights ---------------------------------------------------------------------------------

def only_light(snap):
    assert len(snap.lights) == 1
    return snap.lights[0]


def test_point_light_intensity():
    scene = new_scene()
    color, power = (1.0, 0.5, 0.25), 80.0
    scenes.light(scene, "POINT", energy=power, color=color, location=(1.0, 2.0, 3.0),
                 diffuse_factor=0.25, specular_factor=0.5)
    light = only_light(snap_of())
    assert light.kind == "POINT"
    assert light.position == pytest.approx((1.0, 2.0, 3.0))
    assert light.intensity == pytest.approx(tuple(c * power / (4 * math.pi) for c in color))
    assert light.diffuse_factor == pytest.approx(0.25)
    assert light.specular_factor == pytest.approx(0.5)


def test_light_exposure_doubles_per_stop():
    if "exposure" not in bpy.types.Light.bl_rna.properties:
        pytest.skip("this Blender's lights have no Exposure (added in 4.3)")
    scene = new_scene()
    scenes.light(scene, "POINT", energy=10.0, exposure=2.0)
    light = only_light(snap_of())
    assert light.intensity == pytest.approx((10.0 * 4.0 / (4 * math.pi),) * 3)


def test_spot_light_cone():
    scene = new_scene()
    size, blend = math.radians(50.0), 0.2
    rotation = (0.5, 0.0, 0.0)
    scenes.light(scene, "SPOT", energy=40.0, rotation=rotation, spot_size=size, spot_blend=blend)
    light = only_light(snap_of())
    assert light.kind == "SPOT"
    assert light.spot_cos_half == pytest.approx(math.cos(size / 2))
    assert light.spot_smooth == pytest.approx(1.0 / ((1.0 - math.cos(size / 2)) * blend), rel=1e-5)
    assert light.intensity == pytest.approx((40.0 / (4 * math.pi),) * 3)
    assert light.direction == pytest.approx(tuple(-scenes.euler_matrix(rotation)[:, 2]), abs=1e-6)


def test_sun_light_irradiance_and_direction():
    scene = new_scene()
    rotation = (0.3, 0.6, -1.1)
    scenes.light(scene, "SUN", energy=3.0, color=(0.5, 1.0, 0.2), rotation=rotation)
    light = only_light(snap_of())
    assert light.kind == "SUN"
    assert light.intensity == pytest.approx((1.5, 3.0, 0.6))
    assert light.direction == pytest.approx(tuple(-scenes.euler_matrix(rotation)[:, 2]), abs=1e-6)


def test_area_light_intensity():
    scene = new_scene()
    scenes.light(scene, "AREA", energy=50.0, color=(0.2, 0.4, 1.0), size=0.5)
    light = only_light(snap_of())
    assert light.kind == "AREA"
    assert light.intensity == pytest.approx(tuple(c * 50.0 / math.pi for c in (0.2, 0.4, 1.0)))


# --- 7. materials ------------------------------------------------------------------------------

def test_object_without_material_uses_default():
    scene = new_scene()
    scenes.plane(scene)
    snap = snap_of()
    item, _ = only_item(snap)
    assert item.materials == [""]
    assert snap.materials[""] == S.DEFAULT_MATERIAL


def principled(mat):
    tree = mat.node_tree
    if tree is None:  # pragma: no cover - Blender 5 materials are node-based from the start
        mat.use_nodes = True
        tree = mat.node_tree
    return next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")


def test_principled_fallback():
    scene = new_scene()
    mat = bpy.data.materials.new("Painted")
    node = principled(mat)
    node.inputs["Base Color"].default_value = (0.2, 0.4, 0.6, 1.0)
    node.inputs["Metallic"].default_value = 0.7
    node.inputs["Roughness"].default_value = 0.3
    node.inputs["IOR"].default_value = 2.0
    assert node.inputs["Specular IOR Level"].default_value == pytest.approx(0.5)
    scenes.plane(scene, material=mat)
    snap = snap_of()
    params = snap.materials[mat.name_full]
    assert params.base_color == pytest.approx((0.2, 0.4, 0.6), abs=1e-6)
    assert params.metalness == pytest.approx(0.7, abs=1e-6)
    assert params.roughness == pytest.approx(0.3, abs=1e-6)
    assert params.f0 == pytest.approx(((2.0 - 1.0) / (2.0 + 1.0)) ** 2, rel=1e-6)

    # Blinn-Phong highlight: the metal's share takes the base colour, the dielectric's is white
    assert params.specular_color == pytest.approx([0.3 + 0.7 * c for c in (0.2, 0.4, 0.6)], abs=1e-6)

    node.inputs["Specular IOR Level"].default_value = 0.0
    params = snap_of().materials[mat.name_full]
    assert params.f0 == 0.0
    # no dielectric specular lobe: no white highlight either, only the metal's coloured one
    assert params.specular_color == pytest.approx([0.7 * c for c in (0.2, 0.4, 0.6)], abs=1e-6)


@pytest.mark.parametrize("shader", ["ShaderNodeBsdfDiffuse", "ShaderNodeEmission"])
def test_surfaces_without_a_specular_lobe_have_no_highlight_in_any_model(shader):
    scene = new_scene()
    mat = bpy.data.materials.new(shader)
    tree = scenes.node_tree(mat)
    node = tree.nodes.new(shader)
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(node.outputs[0], output.inputs["Surface"])
    scenes.plane(scene, material=mat)
    params = snap_of().materials[mat.name_full]
    assert params.f0 == 0.0 and params.metalness == 0.0
    assert params.specular_color == (0.0, 0.0, 0.0)


# --- 8. empty and degenerate meshes ------------------------------------------------------------

def test_meshes_without_faces_are_skipped():
    scene = new_scene()
    mesh_object(scene, "Loose", [(0, 0, 0), (1, 0, 0), (0, 1, 0)], [])
    mesh_object(scene, "Nothing", [], [])
    snap = snap_of()
    assert snap.items == []
    assert snap.geometries == {}
    assert snap.triangle_count == 0


def test_degenerate_triangle_is_kept_finite():
    scene = new_scene()
    mesh_object(scene, "Sliver", [(0, 0, 0), (1, 0, 0), (2, 0, 0)], [(0, 1, 2)])
    _, geo = only_item(snap_of())
    assert geo.triangle_count == 1
    assert np.isfinite(geo.positions).all()
    assert np.isfinite(geo.normals).all()


# --- 9. curves, text and metaballs ---------------------------------------------------------------

def reference_triangles(obj) -> int:
    """Triangles of the object's evaluated mesh, read by Blender itself (not by extract)."""
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = bpy.data.meshes.new_from_object(evaluated)
    mesh.calc_loop_triangles()
    count = len(mesh.loop_triangles)
    bpy.data.meshes.remove(mesh)
    return count


def assert_drawn_once(obj):
    snap = snap_of()
    expected = reference_triangles(obj)
    assert expected > 0
    assert snap.triangle_count > 0
    # One object, one surface: drawing it twice doubles the triangles (and the work).
    assert len(snap.items) == 1
    assert snap.triangle_count == expected


def test_text_object_evaluates_to_triangles():
    scene = new_scene()
    data = bpy.data.curves.new("Text", type="FONT")
    data.body = "Hi"
    obj = bpy.data.objects.new("Text", data)
    scene.collection.objects.link(obj)
    assert_drawn_once(obj)


@pytest.mark.parametrize("shape", ["bevel", "extrude"])
def test_bezier_curve_evaluates_to_triangles(shape):
    scene = new_scene()
    data = bpy.data.curves.new("Curve", type="CURVE")
    data.dimensions = "3D"
    spline = data.splines.new("BEZIER")
    spline.bezier_points.add(1)
    for point, co in zip(spline.bezier_points, [(-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)]):
        point.co = co
        point.handle_left_type = point.handle_right_type = "AUTO"
    if shape == "bevel":
        data.bevel_depth = 0.1
    else:
        data.extrude = 0.2
    obj = bpy.data.objects.new("Curve", data)
    scene.collection.objects.link(obj)
    assert_drawn_once(obj)


def test_metaball_evaluates_to_triangles():
    scene = new_scene()
    data = bpy.data.metaballs.new("Ball")
    data.elements.new()
    obj = bpy.data.objects.new("Ball", data)
    scene.collection.objects.link(obj)
    assert_drawn_once(obj)


# --- 10. world ---------------------------------------------------------------------------------

def test_world_background_colour_times_strength():
    scene = new_scene()
    if scene.world.node_tree is None:  # Blender 4.x: a new world has no nodes until asked
        scene.world.use_nodes = True
    bg = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (0.1, 0.2, 0.3, 1.0)
    bg.inputs["Strength"].default_value = 2.0
    assert snap_of().world_color == pytest.approx((0.2, 0.4, 0.6), abs=1e-6)


# --- 11. a large mesh --------------------------------------------------------------------------

def test_large_grid_arrays():
    new_scene()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=200, y_subdivisions=200, size=2.0)
    assert len(bpy.context.active_object.data.polygons) == 200 * 200
    _, geo = only_item(snap_of())
    triangles = 2 * 200 * 200
    assert geo.triangle_count == triangles
    corners = 4 * 200 * 200  # a row per face corner, indexed by the triangles
    for array in (geo.positions, geo.normals):
        assert array.dtype == np.float32
        assert array.shape == (corners, 3)
        assert array.flags.c_contiguous
    assert geo.indices.shape == (3 * triangles,) and geo.indices.dtype == np.int32
    assert geo.ranges == [(0, 0, 3 * triangles)]


def test_what_is_not_read_is_said_once():
    """Unread surface shaders, node-driven inputs and undrawn object types each give one warning,
    however many objects share them."""
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    mix = scenes.unread_material()
    ramp = bpy.data.materials.new("Ramped")
    tree = scenes.node_tree(ramp)
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    # a Particle Info node (a particle's data: not compiled)
    tree.links.new(tree.nodes.new("ShaderNodeParticleInfo").outputs["Random"], bsdf.inputs["Base Color"])
    # a Specular BSDF (EEVEE's) mixed in: its Clear Coat is not drawn
    specular = tree.nodes.new("ShaderNodeEeveeSpecular")
    tree.links.new(tree.nodes.new("ShaderNodeValue").outputs[0], specular.inputs["Clear Coat"])
    shader_mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(bsdf.outputs["BSDF"], shader_mix.inputs[1])
    tree.links.new(specular.outputs["BSDF"], shader_mix.inputs[2])
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(shader_mix.outputs["Shader"], out.inputs["Surface"])
    for i, mat in enumerate((mix, mix, ramp)):
        scenes.plane(scene, size=0.5, location=(i, 0.0, 0.0), material=mat)
    for i in range(2):
        scene.collection.objects.link(bpy.data.objects.new(f"Hair{i}", bpy.data.hair_curves.new(f"Hair{i}")))
    scene.collection.objects.link(bpy.data.objects.new("Smoke", bpy.data.volumes.new("Smoke")))
    snap = extract.snapshot(bpy.context.evaluated_depsgraph_get())
    said = "\n".join(snap.warnings)
    assert len(snap.warnings) == 5, snap.warnings
    assert "Material 'Haired': 1 of 1 nodes not compiled (Hair BSDF (ShaderNodeBsdfHair))" in said
    assert ("Material 'Ramped': 1 of 5 nodes not compiled (Particle Info (ShaderNodeParticleInfo)): "
            "baked") in said
    # (the plane has no UV map to bake on: its object says so)
    assert "material 'Ramped': Particle Info > Random not compiled and not baked (it has no UV map)" in said
    assert "Material 'Ramped': its Clear Coat (Specular BSDF) not drawn" in said
    assert "Not drawn (Shading Lab draws meshes): 2 hair curves object(s), 1 volume(s)" in said


# --- triangulation read as arrays: identical to Blender's loop triangles ------------------------

def _mesh_of(name: str, verts, faces, material_indices=None) -> bpy.types.Mesh:
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in faces])
    if material_indices is not None:
        mesh.polygons.foreach_set("material_index", np.asarray(material_indices, np.int32))
    mesh.update()
    return mesh


def _blenders_triangles(mesh):
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    loops, faces = np.empty(3 * n, np.int32), np.empty(n, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    mesh.loop_triangles.foreach_get("polygon_index", faces)
    return loops.reshape(-1, 3), faces


def _test_meshes():
    rng = np.random.default_rng(5)
    n = 40  # a bumpy grid: non-planar quads, some folded along 0-2 (Blender splits them 1-3)
    xs, ys = np.meshgrid(np.arange(n), np.arange(n))
    verts = np.column_stack([xs.ravel(), ys.ravel(), rng.normal(0.0, 0.8, n * n)])
    quads = [(y * n + x, y * n + x + 1, (y + 1) * n + x + 1, (y + 1) * n + x)
             for y in range(n - 1) for x in range(n - 1)]
    yield _mesh_of("Bumpy", verts, quads, rng.integers(0, 3, len(quads)))
    darts = []  # concave (arrow-head) quads in the plane, in every rotation of their corners
    dverts = []
    for k in range(4):
        base = len(dverts)
        shape = [(0, 0, 0), (2, 1, 0), (0, 2, 0), (0.5, 1, 0)]
        dverts += [(x + 3 * k, y, z) for x, y, z in shape]
        darts.append(tuple(base + (i + k) % 4 for i in range(4)))
    yield _mesh_of("Darts", dverts, darts)
    # triangles and quads mixed
    bpy.ops.mesh.primitive_uv_sphere_add(segments=17, ring_count=9)  # tris at the poles, quads between
    sphere = bpy.context.object
    yield sphere.data
    # larger faces: read from Blender
    yield _mesh_of("Ngons", [(math.cos(a), math.sin(a), 0.1 * math.sin(3 * a))
                             for a in np.linspace(0, 2 * math.pi, 9)[:-1]], [tuple(range(8))])


def test_triangles_read_as_arrays_equal_blenders_loop_triangles():
    scenes.reset()
    flips = 0
    for mesh in _test_meshes():
        expected_loops, expected_faces = _blenders_triangles(mesh)
        co = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
        corner_vert = np.empty(len(mesh.loops), np.int32)
        mesh.loops.foreach_get("vertex_index", corner_vert)
        loops, faces = mesh_reader.triangle_corners(mesh, co.reshape(-1, 3)[corner_vert])
        assert np.array_equal(faces, expected_faces), mesh.name
        assert np.array_equal(loops, expected_loops), (
            f"{mesh.name}: {int((loops != expected_loops).any(axis=1).sum())} triangles differ")
        starts = np.empty(len(mesh.polygons), np.int32)
        mesh.polygons.foreach_get("loop_start", starts)
        flips += int(np.sum(loops[:, 0] != starts[faces]))  # a first triangle split along 1-3
    assert flips >= 10, f"the test meshes must fold some quads along 0-2 ({flips} flipped triangles)"


def test_mesh_geometry_keeps_material_ranges_of_the_fast_path():
    scenes.reset()
    mesh = next(_test_meshes())
    geometry = mesh_reader.mesh_geometry("bumpy", mesh)
    loops, faces = _blenders_triangles(mesh)
    mats = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", mats)
    counts = np.bincount(mats[faces], minlength=3)
    assert [(s, c) for s, _, c in geometry.ranges] == [(s, 3 * int(counts[s])) for s in range(3)]
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    corner_vert = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_vert)
    order = np.argsort(mats[faces], kind="stable")
    expected = co.reshape(-1, 3)[corner_vert[loops[order].reshape(-1)]]
    assert np.array_equal(geometry.per_corner(geometry.positions), expected)


def _winding_of(obj) -> int:
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    try:
        return mesh_reader.mesh_geometry("k", mesh).winding
    finally:
        evaluated.to_mesh_clear()


def test_closed_surfaces_and_their_facing():
    """``MeshGeometry.winding``: +1 for closed surfaces facing out (a UV sphere with its pole fans,
    a cube of quads, a torus), -1 for the same turned inside out, 0 for an open surface (a plane,
    a cube missing a face), a face turned against its neighbours, and three faces on one edge."""
    import bmesh

    scenes.reset()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12)
    sphere = bpy.context.object
    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.object
    bpy.ops.mesh.primitive_torus_add()
    torus = bpy.context.object
    assert [_winding_of(o) for o in (sphere, cube, torus)] == [1, 1, 1]
    for obj in (sphere, cube):
        obj.data.flip_normals()
    assert [_winding_of(o) for o in (sphere, cube)] == [-1, -1]
    bpy.ops.mesh.primitive_plane_add()
    assert _winding_of(bpy.context.object) == 0

    def edited(obj, change):
        mesh = bmesh.new()
        mesh.from_mesh(obj.data)
        change(mesh)
        mesh.to_mesh(obj.data)
        mesh.free()
        obj.data.update()
        return _winding_of(obj)

    bpy.ops.mesh.primitive_cube_add()
    assert edited(bpy.context.object,
                  lambda m: bmesh.ops.delete(m, geom=[m.faces[:][0]], context="FACES_ONLY")) == 0
    bpy.ops.mesh.primitive_cube_add()
    assert edited(bpy.context.object, lambda m: m.faces[:][0].normal_flip()) == 0

    def fin(m):  # a third face on one of the cube's edges
        m.verts.ensure_lookup_table()
        edge = m.edges[:][0]
        far = m.verts.new((5.0, 5.0, 5.0))
        m.faces.new((edge.verts[0], edge.verts[1], far))

    bpy.ops.mesh.primitive_cube_add()
    assert edited(bpy.context.object, fin) == 0


def _geometry_arrays(snap: S.Snapshot) -> list:
    """Each drawn item's geometry as arrays, in the snapshot's order (a modifier renames the mesh)."""
    return [(g.positions, g.normals, g.uvs, g.tangents, g.indices, g.ranges, g.winding)
            for g in (snap.geometries[item.geometry] for item in snap.items)]


def _same_arrays(a, b) -> bool:
    return all((x is None and y is None) or (x is not None and y is not None and np.array_equal(x, y))
               for x, y in zip(a, b))


def test_geometry_memo_gives_what_reading_anew_gives():
    """``mesh_reader.GEOMETRY_MEMO``: a still scene read again takes its meshes' geometry from the memo
    (each mesh once), and after each kind of edit -- a vertex moved, a face's material, flat
    shading, a UV, the faces flipped, a modifier added, a normal map's tangents asked for -- every
    geometry equals the one read with the memo emptied (the edit reached it), and the edited mesh's
    differs from before it."""
    scene = new_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=12, ring_count=6)  # UVs, tris and quads
    sphere = bpy.context.object
    bpy.ops.object.shade_smooth()
    for name in ("A", "B"):
        sphere.data.materials.append(bpy.data.materials.new(name))
    cube = mesh_object(scene, "Box", CUBE_VERTS, CUBE_FACES, location=(3.0, 0.0, 0.0))
    memo = mesh_reader.GEOMETRY_MEMO
    memo.clear()
    before = _geometry_arrays(snap_of())
    hits = memo.hits
    again = _geometry_arrays(snap_of())
    assert memo.hits - hits == 2, f"{memo.hits - hits} of 2 meshes taken from the memo"
    assert len(before) == len(again) == 2 and all(map(_same_arrays, before, again))

    def normal_map():
        material = sphere.data.materials[0]
        nodes = scenes.node_tree(material).nodes
        bsdf = nodes["Principled BSDF"]
        image = bpy.data.images.new("Bumps", 4, 4)
        tex, nmap = nodes.new("ShaderNodeTexImage"), nodes.new("ShaderNodeNormalMap")
        tex.image = image
        material.node_tree.links.new(tex.outputs["Color"], nmap.inputs["Color"])
        material.node_tree.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])

    edits = {
        "a vertex moved": lambda: setattr(sphere.data.vertices[5], "co", (0.0, 0.1, 1.2)),
        "a face's material": lambda: setattr(sphere.data.polygons[3], "material_index", 1),
        "flat shading": lambda: sphere.data.shade_flat(),
        "a UV": lambda: setattr(sphere.data.uv_layers.active.data[7], "uv", (0.3, 0.9)),
        "the faces flipped": lambda: cube.data.flip_normals(),
        "a modifier": lambda: cube.modifiers.new("Sub", "SUBSURF"),
        "tangents": normal_map,
    }
    last = again
    for what, edit in edits.items():
        edit()
        for obj in (sphere, cube):
            obj.data.update()
        hits = memo.hits
        read = _geometry_arrays(snap_of())
        assert memo.hits - hits == 1, f"{what}: {memo.hits - hits} meshes from the memo, not the other one"
        memo.clear()
        fresh = _geometry_arrays(snap_of())
        assert all(map(_same_arrays, read, fresh)), f"{what}: the memo's geometry is stale"
        changed = [not _same_arrays(a, b) for a, b in zip(read, last)]
        assert sum(changed) == 1, f"{what}: {sum(changed)} meshes read differently from before, not 1"
        last = read


def test_geometry_memo_keeps_at_most_its_limit():
    memo = mesh_reader.GeometryMemo(limit=100)

    def geometry(corners):
        return S.MeshGeometry("g", np.zeros((corners, 3), np.float32), np.zeros((corners, 3), np.float32), [])

    arrays = (np.arange(4),)
    memo.put("a", arrays, False, geometry(60))
    memo.put("b", arrays, False, geometry(30))
    assert memo.get("a", arrays, False) is not None  # a is now the most recently used
    memo.put("c", arrays, False, geometry(30))  # 120 corners: b, the least recently used, leaves
    assert [k for k in ("a", "b", "c") if memo.get(k, arrays, False) is not None] == ["a", "c"]
    memo.put("d", arrays, False, geometry(101))  # larger than the limit: not kept
    assert memo.get("d", arrays, False) is None
    assert memo.get("a", (np.arange(5),), False) is None and memo.get("a", arrays, True) is None
    # equal bits, not equal values: -0.0 is another array than 0.0 (its geometry's signs differ),
    # and a NaN matches itself
    zeros = (np.array([0.0, np.nan], np.float32),)
    memo.put("z", zeros, False, geometry(1))
    assert memo.get("z", (np.array([0.0, np.nan], np.float32),), False) is not None
    assert memo.get("z", (np.array([-0.0, np.nan], np.float32),), False) is None
