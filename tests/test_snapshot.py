"""Pure helpers of the snapshot module (no Blender needed)."""

import math

import pytest

from addon.scene import snapshot as S


@pytest.mark.parametrize("r", [0.1, 0.25, 0.5, 0.75, 1.0])
def test_shininess_roughness_mapping_round_trips(r):
    s = S.shininess_from_roughness(r)
    alpha = r * r
    assert s == pytest.approx(min(max(2 / alpha ** 2 - 2, 1.0), 1e4))  # Walter 2007: 2 / alpha^2 - 2
    if 1.0 < s < 1e4:
        assert S.roughness_from_shininess(s) == pytest.approx(r, rel=1e-9)


def test_mapping_clamps_and_known_values():
    assert S.shininess_from_roughness(0.5) == pytest.approx(30.0)  # alpha 0.25 -> 2/0.0625 - 2
    assert S.shininess_from_roughness(0.0) == 1e4  # a mirror, capped
    assert S.shininess_from_roughness(1.0) == 1.0  # widest lobe
    assert S.roughness_from_shininess(0.0) == 1.0
    assert S.roughness_from_shininess(1e6) < 0.04


def test_f0_from_ior_and_spot_smooth():
    assert S.f0_from_ior(1.5) == pytest.approx(0.04)
    assert S.f0_from_ior(1.0) == 0.0
    assert S.spot_smooth(math.radians(60), 0.0) == 1e20  # a hard edge
    assert S.spot_smooth(math.radians(60), 0.5) == pytest.approx(1 / ((1 - math.cos(math.radians(30))) * 0.5))


def test_terms_validation_and_override():
    with pytest.raises(ValueError, match="unknown ndf term"):
        S.Terms(ndf="PHONG")
    t = S.Terms().override(ndf="BECKMANN", diffuse="")
    assert (t.ndf, t.diffuse) == ("BECKMANN", "LAMBERT")
