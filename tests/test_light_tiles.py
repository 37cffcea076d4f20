"""Light culling's tile lists (addon/plan/light_tiles.py), against a brute-force expectation: every pixel
of a ground plane lists, in light order, every light whose influence sphere holds the plane's
point under that pixel."""

from __future__ import annotations

import math

import numpy as np
import pytest

from addon.plan import light_tiles


def _perspective(fov_deg: float, aspect: float, near=0.1, far=100.0) -> np.ndarray:
    f = 1.0 / math.tan(math.radians(fov_deg) / 2.0)
    return np.array([[f / aspect, 0, 0, 0], [0, f, 0, 0],
                     [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]])


def _look_at(eye, target) -> np.ndarray:
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    f = target - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, [0.0, 0.0, 1.0])
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def _ground_points(vp: np.ndarray, width: int, height: int) -> np.ndarray:
    """World points on z = 0 under each pixel centre (nan where the ray misses the ground)."""
    inv = np.linalg.inv(vp)
    xs = (np.arange(width) + 0.5) / width * 2 - 1
    ys = (np.arange(height) + 0.5) / height * 2 - 1
    gx, gy = np.meshgrid(xs, ys)
    near = np.stack([gx, gy, -np.ones_like(gx), np.ones_like(gx)], -1) @ inv.T
    far = np.stack([gx, gy, np.ones_like(gx), np.ones_like(gx)], -1) @ inv.T
    near, far = near[..., :3] / near[..., 3:], far[..., :3] / far[..., 3:]
    t = near[..., 2] / (near[..., 2] - far[..., 2])
    p = near + (far - near) * t[..., None]
    p[(t < 0) | (t > 1)] = np.nan
    return p


@pytest.mark.parametrize("eye", [(0.0, -12.0, 6.0), (3.0, -2.0, 20.0), (0.0, -3.0, 0.5)])
def test_every_pixel_lists_every_light_that_reaches_it_in_order(eye):
    rng = np.random.default_rng(len(str(eye)))
    width, height, tile = 160, 96, 16
    vp = _perspective(50.0, width / height) @ _look_at(eye, (0.0, 0.0, 0.0))
    n = 60
    centres = np.column_stack([rng.uniform(-10, 10, n), rng.uniform(-10, 10, n), rng.uniform(-1, 3, n)])
    radii = rng.uniform(0.3, 4.0, n)
    radii[::13] = np.inf  # some lights reach everywhere
    lists = light_tiles.tile_lists(centres, radii, vp, width, height, tile)
    points = _ground_points(vp, width, height)
    missing = listed_extra = 0
    for y in range(height):
        for x in range(width):
            first, count = lists.header[y // tile, x // tile].astype(int)
            listed = lists.entries.reshape(-1)[first:first + count].astype(int)
            assert np.all(np.diff(listed) > 0), "a tile lists its lights in light order"
            p = points[y, x]
            if np.isnan(p).any():
                continue
            reach = np.nonzero(np.linalg.norm(centres - p, axis=1) < radii)[0]
            missing += len(np.setdiff1d(reach, listed))
            listed_extra += len(listed) - len(reach)
    assert missing == 0, f"{missing} (pixel, light) pairs within reach but not listed"
    total = lists.entry_count
    every = n * lists.header.shape[0] * lists.header.shape[1]
    print(f"\n{total} entries of {every} without culling")
    assert total < every, "culling must leave some lights out of some tiles"


def test_a_light_around_the_camera_is_in_every_tile_as_the_tile_tests_find():
    """A light whose reach holds the camera's centre is listed in every tile without testing its
    pairs: the tests themselves (the tile's cone and its four side planes) pass it everywhere, as
    a sphere that holds a frustum's apex meets it; a light just short of the camera is tested."""
    width, height, tile = 160, 96, 16
    eye = np.array([1.0, -6.0, 2.5])
    vp = _perspective(50.0, width / height) @ _look_at(tuple(eye), (0.0, 0.0, 0.0))
    rng = np.random.default_rng(5)
    offsets = rng.normal(size=(12, 3))
    centres = eye + offsets * rng.uniform(0.2, 5.0, (12, 1)) / np.linalg.norm(offsets, axis=1, keepdims=True)
    distance = np.linalg.norm(centres - eye, axis=1)
    radii = distance * np.where(np.arange(12) < 8, 1.01, 0.99)  # 8 around the camera, 4 short of it
    lists = light_tiles.tile_lists(centres, radii, vp, width, height, tile)
    columns, rows = lists.columns, lists.header.shape[0]
    ty, tx = (a.ravel() for a in np.mgrid[0:rows, 0:columns])
    edges = light_tiles._tile_edges(tile, width, height, columns, rows)
    entries = lists.entries.reshape(-1)
    listed = [set(entries[int(f):int(f) + int(c)].astype(int)) for f, c in lists.header.reshape(-1, 2)]
    for i in range(12):
        light = np.full(len(tx), i)
        tested = (light_tiles._within_tile_bound(centres, radii, light, tx, ty, edges, vp)
                  & light_tiles._meets_tile(centres, radii, light, tx, ty, edges, vp))
        in_lists = np.array([i in tile_set for tile_set in listed])
        if i < 8:
            assert tested.all() and in_lists.all(), (i, int(tested.sum()), int(in_lists.sum()))
        else:
            assert np.array_equal(in_lists, tested), (i, int(tested.sum()), int(in_lists.sum()))
    assert sum(len(t) for t in listed) < 12 * len(listed), "the lights short of the camera go somewhere"


def _ortho(width_m: float, aspect: float) -> np.ndarray:
    return np.diag([2.0 / width_m, 2.0 * aspect / width_m, -0.01, 1.0])


def _pairs_meeting_tiles(centres, radii, vp, width, height, tile, rays=9) -> int:
    """(tile, light) pairs whose sphere meets the tile's frustum, by brute force: rays x rays rays
    across each tile, edges included, each a half-line from the camera (a line for an
    orthographic view); a pair counts if some ray passes within the radius of the centre. The
    rays sample the frustum from inside, so this can only undercount."""
    inverse = np.linalg.inv(vp)
    ortho = np.allclose(vp[3, :3], 0.0)
    columns, rows = -(-width // tile), -(-height // tile)
    total = 0
    for ty in range(rows):
        for tx in range(columns):
            x = np.linspace(tx * tile, min((tx + 1) * tile, width), rays) / width * 2 - 1
            y = np.linspace(ty * tile, min((ty + 1) * tile, height), rays) / height * 2 - 1
            gx, gy = (a.reshape(-1) for a in np.meshgrid(x, y))
            near = np.stack([gx, gy, -np.ones_like(gx), np.ones_like(gx)], -1) @ inverse.T
            far = np.stack([gx, gy, np.ones_like(gx), np.ones_like(gx)], -1) @ inverse.T
            near, far = near[:, :3] / near[:, 3:], far[:, :3] / far[:, 3:]
            d = far - near
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            if not ortho:
                eye = inverse @ np.array([0.0, 0.0, 1.0, 0.0])
                near = np.broadcast_to(eye[:3] / eye[3], near.shape)
            rel = centres[:, None, :] - near[None]  # (lights, rays, 3)
            t = np.sum(rel * d[None], axis=-1)
            if not ortho:
                t = np.maximum(t, 0.0)
            dist = np.linalg.norm(rel - t[..., None] * d[None], axis=-1)
            total += int(np.sum((dist <= radii[:, None]).any(axis=1)))
    return total


@pytest.mark.parametrize("view", ["perspective", "orthographic"])
def test_tiles_list_few_lights_that_miss_them(view):
    """The side planes of a tile's frustum let a sphere near a corner through (it meets all four
    planes and misses the tile): a cone about the tile (perspective) or its rectangle
    (orthographic) cuts those out. Listed (tile, light) pairs against those whose sphere really
    meets the tile's frustum (brute force, which can only undercount)."""
    rng = np.random.default_rng(7)
    width, height, tile = 96, 64, 8
    n = 40
    if view == "perspective":
        vp = _perspective(50.0, width / height) @ _look_at((0.0, -12.0, 6.0), (0.0, 0.0, 0.0))
        centres = np.column_stack([rng.uniform(-8, 8, n), rng.uniform(-8, 8, n), rng.uniform(-1, 3, n)])
    else:
        vp = _ortho(8.0, width / height)
        centres = np.column_stack([rng.uniform(-4, 4, n), rng.uniform(-3, 3, n), rng.uniform(-1, 1, n)])
    radii = rng.uniform(0.3, 2.0, n)
    lists = light_tiles.tile_lists(centres, radii, vp, width, height, tile)
    exact = _pairs_meeting_tiles(centres, radii, vp, width, height, tile)
    ratio = lists.entry_count / exact
    print(f"\n{view}: {lists.entry_count} pairs listed, {exact} meet their tile: {ratio:.4f}")
    # measured 1.019 (perspective: the cone's rounding about the tile's square), 1 exactly
    # (orthographic); with the side planes alone 1.124 / 1.130. The same counts with 9, 17 and 33
    # rays a side: the brute force has converged.
    assert 1.0 <= ratio <= {"perspective": 1.05, "orthographic": 1.0}[view], ratio


def test_unbounded_lights_are_in_every_tile_and_too_many_entries_make_one_list():
    vp = _perspective(60.0, 1.0) @ _look_at((0, -5, 5), (0, 0, 0))
    lists = light_tiles.tile_lists(np.zeros((3, 3)), [np.inf] * 3, vp, 64, 64, 16)
    assert lists.header.shape == (4, 4, 2)
    assert np.all(lists.header[..., 1] == 3)
    many = light_tiles.MAX_ENTRIES // 16 + 1  # every one of them in all 16 tiles
    lists = light_tiles.tile_lists(np.zeros((many, 3)), np.full(many, np.inf), vp, 64, 64, 16)
    assert lists.header.shape == (1, 1, 2) and lists.header[0, 0, 1] == many
    assert lists.tile >= 1 << 24  # every fragment reads tile (0, 0)


def test_lists_pay_where_the_tiles_leave_out_a_fifth_of_the_lights():
    """A view's lists pay where its tiles leave out SKIPPED_TO_PAY (a fifth) of the lights on
    average: a light reaching everywhere and one reaching a disc of radius r about the middle of
    an orthographic view 8 m x 4 m list 1 + f a tile, f between the disc's share of the view
    (clipped to it, in closed form) and that of the disc widened by a tile's diagonal."""
    width, height, tile = 256, 128, 8
    vp = _ortho(8.0, width / height)
    metres_per_tile = 8.0 / width * tile

    def clipped_disc(r: float) -> float:  # the disc's area inside |y| <= 2 (r < 4: |x| <= 4 holds)
        y = min(r, 2.0)
        return 2.0 * (y * math.sqrt(r * r - y * y) + r * r * math.asin(y / r))

    shares = {}
    for r in (1.0, 3.0):
        lists = light_tiles.tile_lists([[0.0, 0.0, 0.0]] * 2, [np.inf, r], vp, width, height, tile)
        share = lists.mean_listed - 1.0
        low, high = clipped_disc(r) / 32.0, clipped_disc(r + math.sqrt(2.0) * metres_per_tile) / 32.0
        print(f"r = {r} m: a tile lists {lists.mean_listed:.3f} of 2 "
              f"(the disc's share {low:.3f} to {high:.3f})")
        assert low <= share <= high, (r, share, low, high)
        shares[r] = lists_pay = light_tiles.lists_pay(lists, 2)
        assert lists_pay == (lists.mean_listed <= 2.0 * (1.0 - light_tiles.SKIPPED_TO_PAY))
    assert shares == {1.0: True, 3.0: False}  # leaving out 0.85 and 0.25 of a light
    # at the threshold exactly: 1.6 of 2 listed pays, a little more does not
    header = np.zeros((1, 5, 2), np.float32)
    header[0, :, 1] = (2, 2, 2, 1, 1)
    exact = light_tiles.TileLists(tile, header, np.zeros((1, light_tiles.LIST_WIDTH), np.float32))
    assert exact.mean_listed == pytest.approx(1.6) and light_tiles.lists_pay(exact, 2)
    header[0, 4, 1] = 2
    assert not light_tiles.lists_pay(exact, 2) and not light_tiles.lists_pay(exact, 0)


def test_influence_radius():
    assert light_tiles.influence_radius("POINT", (100.0, 50.0, 0.0), 0.01) == pytest.approx(
        100.0 * math.sqrt(light_tiles.WINDOW_PEAK_LOSS))
    # the window's largest loss, (2x - x^3) at x = sqrt(2/3), found by brute force
    x = np.linspace(0.0, 1.0, 1000001)
    assert (2 * x - x ** 3).max() == pytest.approx(light_tiles.WINDOW_PEAK_LOSS, rel=1e-10)
    assert light_tiles.influence_radius("POINT", (100.0, 50.0, 0.0), 0.01, custom=3.0) == 3.0
    assert light_tiles.influence_radius("SUN", (1.0, 1.0, 1.0), 0.01) == math.inf
    assert light_tiles.influence_radius("AREA", (1.0, 1.0, 1.0), 0.0) == math.inf


# --- in the renderer ------------------------------------------------------------------------------

import scenes  # noqa: E402


def _lights_over_a_plane(size: int, count: int, cutoff: float | None, seed: int = 2):
    """An orthographic view of a Lambert plane (rho 0.5, no specular) 4 m across, under ``count``
    point lights at random (with Custom Distance ``cutoff`` if given) and a sun."""
    scene = scenes.lambert_scene(size)
    scene.camera.data.ortho_scale = 4.0
    rng = np.random.default_rng(seed)
    for _ in range(count):
        x, y = rng.uniform(-2.2, 2.2, 2)
        light = scenes.light(scene, "POINT", energy=float(rng.uniform(5, 50)), location=(x, y, 0.4),
                             color=tuple(rng.uniform(0.3, 1.0, 3)))
        if cutoff is not None:
            light.data.use_custom_distance = True
            light.data.cutoff_distance = cutoff
    return scene


def _record_programs(monkeypatch) -> list:
    """The features of every shading program made from now on (the test's monkeypatch undoes it)."""
    from addon.frame import gpu_library

    made = []
    shading_program = gpu_library.shading_program
    monkeypatch.setattr(gpu_library, "shading_program",
                        lambda features: made.append(features) or shading_program(features))
    return made


@pytest.mark.parametrize("model", ["BLINN_PHONG", "PBR"])
def test_culling_on_equals_off_bit_for_bit(model, tmp_path, monkeypatch):
    """40 lights that each reach 0.8 m (a tenth of the view's width), a sun that reaches
    everywhere: the frame shading each tile's lights equals the frame shading every light, to the
    bit, and its tiles list far fewer lights than there are."""
    from addon.blender import engine

    scene = _lights_over_a_plane(96, 40, cutoff=0.8)
    scene.shading_lab.model = model
    made = _record_programs(monkeypatch)
    culled = scenes.render(scene, tmp_path / "culled.exr")
    assert made and all(f.light_tiles for f in made), made
    scene.shading_lab.light_culling = False
    every = scenes.render(scene, tmp_path / "every.exr")
    assert np.array_equal(culled, every), f"max difference {np.abs(culled - every).max():.3g}"
    assert every[..., :3].max() > 2.0 * scenes.LAMBERT, "the point lights must light the plane"
    assert engine.last_timings  # rendered by the engine


@pytest.mark.parametrize("model", ["BLINN_PHONG", "PBR"])
def test_culling_on_equals_off_with_shadows_and_light_sizes(model, tmp_path, monkeypatch):
    """Culling with what real lights have on: 6 point lights with a radius and a spot light,
    reaching 1.2 m each and casting soft shadows from two tilted plates above the plane, and a
    shadowed sun: the culled frame equals the frame shading every light, to the bit (a culled
    light is skipped before its shadow lookup, which the tile's list must not change)."""
    scene = _lights_over_a_plane(96, 6, cutoff=1.2, seed=5)
    scene.shading_lab.model = model
    for obj in scene.objects:
        if obj.type == "LIGHT":
            obj.data.use_shadow = True
            if obj.data.type == "POINT":
                obj.data.shadow_soft_size = 0.08
    spot = scenes.light(scene, "SPOT", energy=60.0, location=(0.4, -0.6, 1.2), spot_size=1.2,
                        shadow_soft_size=0.05, use_shadow=True)
    spot.data.use_custom_distance, spot.data.cutoff_distance = True, 1.5
    scenes.plane(scene, size=1.0, location=(-0.6, 0.4, 0.15), rotation=(0.3, 0.0, 0.0))
    scenes.plane(scene, size=0.8, location=(0.7, -0.5, 0.2), rotation=(0.0, 0.4, 0.2))
    made = _record_programs(monkeypatch)
    culled = scenes.render(scene, tmp_path / "culled.exr")
    assert made and all(f.light_tiles for f in made), made
    scene.shading_lab.light_culling = False
    every = scenes.render(scene, tmp_path / "every.exr")
    assert np.array_equal(culled, every), f"max difference {np.abs(culled - every).max():.3g}"
    for obj in scene.objects:
        if obj.type == "LIGHT":
            obj.data.use_shadow = False
    unshadowed = scenes.render(scene, tmp_path / "unshadowed.exr")
    shadowed = float((culled[..., :3].sum(axis=2) < 0.95 * unshadowed[..., :3].sum(axis=2)).mean())
    print(f"shadowed: {shadowed:.3f} of the pixels")
    assert shadowed > 0.02, f"the plates must shadow the plane: {shadowed:.3f} of the pixels"


def test_a_light_reaches_exactly_its_custom_distance(tmp_path):
    scene = scenes.reset(size=64)
    scenes.ortho_camera(scene, scale=4.0)
    scenes.plane(scene, size=6.0, material=scenes.material(base_color=(0.5, 0.5, 0.5), f0=0.0,
                                                            specular_color=(0.0, 0.0, 0.0)))
    light = scenes.light(scene, "POINT", energy=100.0, location=(0.0, 0.0, 0.5))
    light.data.use_custom_distance, light.data.cutoff_distance = True, 1.0
    image = scenes.render(scene, tmp_path / "cut.exr")[..., 0]
    xs = (np.arange(64) + 0.5) / 64 * 4.0 - 2.0
    gx, gy = np.meshgrid(xs, -xs)  # top row first
    d = np.sqrt(gx ** 2 + gy ** 2 + 0.25)
    assert np.all(image[d >= 1.0] == 0.0), "lit beyond the custom distance"
    assert np.all(image[d < 0.95] > 0.0)


@pytest.mark.parametrize("lights,energy,threshold", [(1, 2500.0, 12.0), (3, 2500.0, 12.0), (3, 25.0, 9.5)])
def test_the_threshold_drops_at_most_its_irradiance(lights, energy, threshold, tmp_path):
    """A Lambert plane (10 m) under one point light 2 m above it, against the closed form without a
    reach. With two more lights (under the plane, lighting none of it) the scene has more than one
    or two lights and the Light Threshold t gives each a reach where its irradiance falls to t,
    scaled by the scene's brightness where that is below pi W/m^2 (a 0.18 grey at middle grey):
    the irradiance the lights give together at the box's centre, each at least half its diagonal
    away, here 3 I / 50. The irradiance removed is the window's, I cos(theta) / d^2 (1 - (1 - (d/r)^4)^2),
    at most the scaled threshold anywhere. In a 100x dimmer scene the threshold is scaled with it
    (an absolute 9.5 W/m^2 would end the 25 W light 0.46 m from it, before the plane). A light
    alone (or with one other) is shaded by its own call and reaches everywhere: nothing removed."""
    scene = scenes.reset(size=96)
    scenes.ortho_camera(scene, scale=8.0)
    rho = 0.5
    scenes.plane(scene, size=10.0, material=scenes.material(base_color=(rho, rho, rho), f0=0.0,
                                                             specular_color=(0.0, 0.0, 0.0)))
    height = 2.0
    scenes.light(scene, "POINT", energy=energy, location=(0.0, 0.0, height))
    for x in range(lights - 1):  # below the plane: they light none of what the camera sees
        scenes.light(scene, "POINT", energy=energy, location=(x - 0.5, 0.0, -3.0))
    scene.shading_lab.model = "PBR"
    scene.shading_lab.light_threshold = threshold
    image = scenes.render(scene, tmp_path / "window.exr")[..., 0].astype(np.float64)
    xs = (np.arange(96) + 0.5) / 96 * 8.0 - 4.0
    gx, gy = np.meshgrid(xs, -xs)
    d2 = gx ** 2 + gy ** 2 + height ** 2
    intensity = energy / (4 * math.pi)
    irradiance = intensity * (height / np.sqrt(d2)) / d2  # I cos(theta) / d^2
    scene_irradiance = lights * intensity / 50.0  # each light within half the box's diagonal (50 m^2)
    effective = threshold * min(1.0, scene_irradiance / math.pi)
    reach = math.sqrt(intensity * light_tiles.WINDOW_PEAK_LOSS / effective) if lights > 2 else math.inf
    window = np.clip(1.0 - (d2 / reach ** 2) ** 2, 0.0, 1.0) ** 2
    dropped = irradiance - image * math.pi / rho
    err = np.abs(dropped - irradiance * (1.0 - window)).max()
    worst = dropped.max()
    print(f"\n{lights} lights of {energy} W: reach {reach:.2f} m, most irradiance dropped {worst:.4g} "
          f"W/m^2 (threshold {effective:.4g}); against the window's closed form {err:.2e}")
    assert err < 1e-5 * irradiance.max(), f"dropped irradiance off the window's closed form by {err:.2e}"
    assert worst <= effective, f"dropped {worst:.4f} W/m^2, threshold {effective}"
    if lights > 2:
        assert height < reach < math.hypot(4.0, height), "the reach must end inside the view"
        assert np.all(image[d2 >= reach ** 2] == 0.0) and worst > 0.5 * effective, worst  # cos theta < 1
    else:
        assert worst < 1e-6 * irradiance.max(), f"a lone light lost {worst:.2e} W/m^2"


def test_culling_pays_only_where_some_light_reaches_less_than_the_scene():
    """Light culling pays where some light's reach ends inside the drawn scene's box: a light
    whose reach holds every corner of the box is listed by every tile, so the program shades
    without lists (a scene of a few lights then shades each by its own call: programs.
    light_sequence)."""
    from types import SimpleNamespace

    from addon.plan import programs

    def snap(*lights, culling=True):
        return SimpleNamespace(settings=SimpleNamespace(light_culling=culling),
                               lights=[SimpleNamespace(position=p, influence=r) for p, r in lights])

    box = (np.array([-2.0, -2.0, 0.0]), np.array([2.0, 2.0, 1.0]))
    far_corner = math.sqrt(2.0 ** 2 + 2.0 ** 2 + 1.0 ** 2)  # from the origin, the box's corners
    everywhere = snap(((0.0, 0.0, 0.0), far_corner + 1e-3), ((0.0, 0.0, 5.0), math.inf))
    assert not programs.uses_light_tiles(everywhere, box)
    assert programs.uses_light_tiles(everywhere)  # without the box: some reach is finite
    short = snap(((0.0, 0.0, 0.0), far_corner - 1e-3), ((0.0, 0.0, 5.0), math.inf))
    assert programs.uses_light_tiles(short, box)
    assert not programs.uses_light_tiles(snap(((0.0, 0.0, 0.0), 1.0), culling=False), box)
    assert not programs.uses_light_tiles(snap(((0.0, 0.0, 5.0), math.inf)), box)


def test_a_view_whose_tiles_leave_out_little_shades_without_them(tmp_path, monkeypatch):
    """A point light whose reach ends just inside the plane's corners, beside a sun: its tiles
    would list 1.9 of the 2 lights a tile, so the view shades without lists (its two lights
    each by its own call); reaching 0.5 m, the lists leave out most of it and the view shades
    through them. The same image either way as without culling, to the bit."""
    scene = _lights_over_a_plane(48, 1, cutoff=2.5, seed=3)  # the plane's corners 2.86 m away
    point = next(obj for obj in scene.objects if obj.type == "LIGHT" and obj.data.type == "POINT")
    point.location = (0.0, 0.0, 0.4)
    scene.shading_lab.model = "PBR"
    made = _record_programs(monkeypatch)
    images = {}
    for cutoff in (2.5, 0.5):
        point.data.cutoff_distance = cutoff
        scene.shading_lab.light_culling = True
        made.clear()
        images[cutoff] = scenes.render(scene, tmp_path / f"culling_{cutoff}.exr")
        assert made and all(f.light_tiles == (cutoff == 0.5) for f in made), (cutoff, made)
        assert all(bool(f.light_sequence) == (cutoff == 2.5) for f in made), (cutoff, made)
        scene.shading_lab.light_culling = False
        every = scenes.render(scene, tmp_path / f"every_{cutoff}.exr")
        difference = float(np.abs(images[cutoff] - every).max())
        assert difference == 0.0, f"max difference {difference:.3g}"
    lit = float(np.abs(images[2.5] - images[0.5])[..., :3].max())  # measured
    print(f"the point light's reach changes a pixel by up to {lit:.3f}")
    assert lit > 0.5, f"the point light must light the plane: {lit:.3f}"


def _two_lights_and_plates(size: int = 64):
    """A plane under two tilted plates, lit by a square area light and a spot light (each of
    size, casting soft shadows), neither with a Custom Distance: both reach the whole scene."""
    import bpy

    scene = _lights_over_a_plane(size, 0, cutoff=None)
    for obj in [obj for obj in scene.objects if obj.type == "LIGHT"]:  # (its sun)
        bpy.data.objects.remove(obj)
    scene.shading_lab.model = "PBR"
    scenes.plane(scene, size=1.0, location=(-0.6, 0.4, 0.25), rotation=(0.3, 0.0, 0.0))
    scenes.plane(scene, size=0.8, location=(0.7, -0.5, 0.3), rotation=(0.0, 0.4, 0.2))
    scenes.light(scene, "AREA", energy=40.0, location=(-0.3, 0.2, 1.5), size=0.4, use_shadow=True)
    scenes.light(scene, "SPOT", energy=60.0, location=(0.4, -0.6, 1.2), spot_size=1.2,
                 shadow_soft_size=0.05, use_shadow=True)
    return scene


def test_a_few_lights_each_shaded_by_its_own_call_equal_the_loops(tmp_path, monkeypatch):
    """A scene of two lights (an area light and a spot, each casting soft shadows) shades each by
    its own call with constants (programs.UNROLLED_LIGHTS): the same image, to the bit, as the
    loops over each group of lights; a third light turns back to the loops."""
    from addon.plan import programs

    scene = _two_lights_and_plates()
    scene.shading_lab.light_threshold = 0.0  # the reach would follow UNROLLED_LIGHTS (programs.light_reaches)
    made = _record_programs(monkeypatch)
    called = scenes.render(scene, tmp_path / "called.exr")
    area, spot = (programs.LIGHT_GROUP_ORDER.index(g) for g in ("AREA_SHADOWED", "SPOT_SHADOWED"))
    assert {f.light_sequence for f in made} == {tuple(sorted((area, spot)))}, made
    assert not any(f.light_tiles for f in made)
    defines = dict(made[-1].defines())
    assert defines["SL_LIGHT_SEQUENCE"] == programs.sequence_source(made[-1].light_sequence)
    assert not any(name.startswith("SL_LIGHTS_") for name in defines)
    made.clear()
    monkeypatch.setattr(programs, "UNROLLED_LIGHTS", 0)
    looped = scenes.render(scene, tmp_path / "looped.exr")
    assert made and all(f.light_sequence == () for f in made), made
    assert np.array_equal(called, looped), f"max difference {np.abs(called - looped).max():.3g}"
    brightest = float(looped[..., :3].max())  # measured 2.61: the area light under the plates
    assert brightest > 1.0, f"the lights must light the plane: brightest pixel {brightest:.3f}"
    monkeypatch.setattr(programs, "UNROLLED_LIGHTS", 2)
    made.clear()
    scenes.light(scene, "POINT", energy=20.0, location=(1.0, 1.0, 1.0))
    scenes.render(scene, tmp_path / "three.exr")
    assert made and all(f.light_sequence == () for f in made), made
