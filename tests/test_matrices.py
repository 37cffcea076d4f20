"""The closed-form inverses of addon/scene/matrices.py (no Blender needed), checked against numpy's
LAPACK inverse and against the identity; and a render that inverts nothing through LAPACK."""

from __future__ import annotations

import numpy as np
import pytest

from addon.scene.matrices import cross3, determinant3, invert


def _affine(rng) -> np.ndarray:
    """A rotation, a scale over four decades per axis and a translation: an object's or a camera's
    world matrix."""
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    m = np.eye(4)
    m[:3, :3] = rotation * rng.uniform(0.01, 100.0, size=3)
    m[:3, 3] = rng.normal(size=3) * 50.0
    return m


def _perspective(near: float, far: float, shift: float) -> np.ndarray:
    """A camera's projection with a lens shift (Blender's form)."""
    p = np.zeros((4, 4))
    p[0, 0], p[1, 1], p[0, 2], p[1, 2] = 2.4, 4.2, shift, -shift
    p[2, 2], p[2, 3], p[3, 2] = (far + near) / (near - far), 2.0 * far * near / (near - far), -1.0
    return p


def test_stacks_and_single_matrices_equal_lapack():
    """Measured: relative difference from numpy.linalg.inv <= 2.3e-14 (3x3 normal matrices with
    condition numbers up to ~5e3) and the product with the matrix within 1e-13 of the identity
    (world matrices scaled 0.01-100), as LAPACK's own product (1.1e-13)."""
    rng = np.random.default_rng(7)
    affine = np.stack([_affine(rng) for _ in range(200)])
    off = np.abs(np.einsum("nij,njk->nik", invert(affine), affine) - np.eye(4)).max()
    assert off < 4e-13, f"stack of world matrices: {off:.3g} off the identity"
    single = max(np.abs(invert(m) @ m - np.eye(4)).max() for m in affine[:50])
    assert single < 4e-13, f"one world matrix at a time: {single:.3g} off the identity"
    normals = rng.normal(size=(100, 3, 3))
    lapack = np.linalg.inv(normals)
    relative = (np.abs(invert(normals) - lapack).max(axis=(1, 2)) / np.abs(lapack).max(axis=(1, 2))).max()
    assert relative < 1e-13, f"3x3: {relative:.3g} relative difference from LAPACK"
    assert invert(normals[0]).shape == (3, 3) and invert(affine[:1]).shape == (1, 4, 4)


@pytest.mark.parametrize("near, far", [(1e-4, 1e5), (0.1, 100.0), (1e-3, 1e7)])
def test_projections_with_extreme_clip_ranges(near, far):
    """Measured: 1.1e-16 - 1.8e-16 relative difference from LAPACK's inverse."""
    p = _perspective(near, far, 0.3)
    lapack = np.linalg.inv(p)
    relative = np.abs(invert(p) - lapack).max() / np.abs(lapack).max()
    assert relative < 1e-15, f"clip {near}-{far}: {relative:.3g} relative difference from LAPACK"


@pytest.mark.parametrize("m", [np.zeros((4, 4)), np.diag([1.0, 1.0, 0.0, 1.0]), np.full((3, 3), np.nan),
                               np.stack([np.eye(4), np.zeros((4, 4))])])
def test_singular_matrices_raise_as_numpy_does(m):
    with pytest.raises(np.linalg.LinAlgError):
        invert(m)


def test_cross3_is_the_cross_product():
    rng = np.random.default_rng(3)
    for a, b in rng.normal(size=(20, 2, 3)):
        np.testing.assert_array_equal(cross3(a, b), np.cross(a, b))
    np.testing.assert_array_equal(cross3((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), (0.0, 0.0, 1.0))


def test_determinant3_equals_lapack_with_its_sign():
    """Against numpy.linalg.det: random stacks (relative difference measured 1.1e-14, bound 5e-14),
    a mirror (negative), a flattening (exactly 0) and one matrix alone."""
    rng = np.random.default_rng(5)
    m = rng.normal(size=(200, 3, 3)) * rng.uniform(1e-3, 1e3, size=(200, 1, 1))
    ours, lapack = determinant3(m), np.linalg.det(m)
    rel = np.abs(ours - lapack) / np.abs(lapack)
    print(f"largest relative difference {rel.max():.2e}")
    assert rel.max() <= 5e-14 and np.array_equal(np.sign(ours), np.sign(lapack)), rel.max()
    assert determinant3(np.diag([-1.0, 2.0, 3.0])) == -6.0
    assert determinant3(np.diag([1.0, 0.0, 3.0])) == 0.0
    assert determinant3(m[0]) == pytest.approx(float(lapack[0]), rel=1e-13)


def test_other_shapes_are_refused():
    with pytest.raises(ValueError, match="3x3 or 4x4"):
        invert(np.eye(2))
    with pytest.raises(ValueError, match="3x3 or 4x4"):
        invert(np.ones(4))
    with pytest.raises(ValueError, match="3x3 matrices"):
        determinant3(np.eye(4))


def test_a_render_inverts_nothing_through_lapack(monkeypatch, tmp_path):
    """numpy's inverse and solve wake OpenBLAS's worker threads, which then spin beside the software
    rasteriser's (addon/scene/matrices.py): a render of a scene with shadow maps of both kinds (a point
    light's cube, a sun's), the world's occlusion and light tiles calls neither."""
    import scenes

    from addon.blender import scene_builder
    from addon.scene import presets

    scene = scenes.reset()
    scene_builder.build_scene(presets.load_scene_preset("material_grid"), scene)
    scene.render.resolution_x, scene.render.resolution_y = 64, 36
    calls = []

    def refuse(name):
        def call(*args, **kwargs):
            calls.append(name)
            raise AssertionError(f"numpy.linalg.{name} in a render")
        return call

    monkeypatch.setattr(np.linalg, "inv", refuse("inv"))
    monkeypatch.setattr(np.linalg, "solve", refuse("solve"))
    image = scenes.render(scene, tmp_path / "grid.exr")
    assert not calls, calls
    assert image[..., :3].max() > 0.0, "the grid rendered"
