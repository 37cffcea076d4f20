"""Scene-specialised programs: what the defines compile in, and compile errors reaching the user."""

from __future__ import annotations

import re
from dataclasses import replace

import bpy
import pytest
import scenes

from addon.frame import gpu_library
from addon.plan import programs
from addon.scene import snapshot as S


def preprocess(source: str, defines: dict[str, str]) -> str:
    """The conditional part of the GLSL preprocessor (#ifdef/#ifndef/#if defined/#elif/#else/
    #endif), enough to see which lines a compiler receives for these defines."""
    out, stack = [], []  # stack of (taking, any_branch_taken)

    def holds(expr: str) -> bool:  # "defined(A) || defined(B)" or "NAME > N", the forms glsl/ uses
        compared = re.fullmatch(r"\s*(\w+)\s*>\s*(\d+)\s*", expr)
        if compared:
            return int(defines.get(compared[1], 0)) > int(compared[2])
        names = re.findall(r"defined\s*\(\s*(\w+)\s*\)", expr)
        assert names and "&&" not in expr and "!" not in expr, f"unsupported #if: {expr}"
        return any(name in defines for name in names)

    for line in source.splitlines():
        s = line.strip()
        live = all(t for t, _ in stack)
        if s.startswith("#ifdef") or s.startswith("#ifndef") or s.startswith("#if "):
            if s.startswith("#ifdef"):
                cond = s.split()[1] in defines
            elif s.startswith("#ifndef"):
                cond = s.split()[1] not in defines
            else:
                cond = holds(s[3:])
            stack.append((cond, cond))
        elif s.startswith("#elif"):
            taken = stack[-1][1]
            cond = not taken and holds(s[5:])
            stack[-1] = (cond, taken or cond)
        elif s.startswith("#else"):
            stack[-1] = (not stack[-1][1], True)
        elif s.startswith("#endif"):
            stack.pop()
        elif live:
            out.append(line)
    assert not stack, "unbalanced #if/#endif"
    return "\n".join(out)


def _compiled(features: programs.Features) -> str:
    src = programs.program_source(features)
    return preprocess(src.fragment, dict(src.defines))


def test_a_scene_without_spot_lights_compiles_no_spot_code():
    code = _compiled(programs.Features("PBR", 2, frozenset({"POINT", "SUN"})))
    assert "E_Point(" in code and "E_Sun(" in code
    assert "E_Spot(" not in code and "E_Area(" not in code
    spot_only = _compiled(programs.Features("PBR", 1, frozenset({"SPOT"})))
    assert "E_Spot(" in spot_only and "E_Sun(" not in spot_only
    assert "E_Point(" in spot_only  # the spot builds on the point light's falloff


def test_models_compile_only_their_own_lobes():
    assert "shade_direct" in _compiled(programs.Features("PBR"))
    assert "D_GGX(NoH" in _compiled(programs.Features("PBR"))
    assert "S_BlinnPhong(dot" not in _compiled(programs.Features("PBR"))
    assert "D_GGX(NoH" not in _compiled(programs.Features("BLINN_PHONG"))


def test_feature_keys():
    a = programs.Features("PBR", 4, frozenset({"POINT"}))
    assert a.defines() == (("SL_DIFFUSE_LAMBERT", "1"), ("SL_FRESNEL_SCHLICK", "1"), ("SL_HAS_POINT", "1"),
                           ("SL_LIGHTS_POINT", "1"), ("SL_LIGHT_RADII", "1"), ("SL_MAX_LIGHTS", "4"),
                           ("SL_MODEL_PBR", "1"), ("SL_NDF_GGX", "1"),
                           ("SL_VISIBILITY_SMITH_CORRELATED", "1"))
    # a loop per group of lights the scene has (a kind, with or without shadow maps); with
    # shadows and no groups named, both for every kind; without shadows, none with maps
    shadowed = programs.Features("PBR", 4, frozenset({"POINT", "AREA"}), shadow_layers=6, shadow_size=1024)
    assert shadowed.light_groups == {"POINT", "AREA", "POINT_SHADOWED", "AREA_SHADOWED"}
    only = replace(shadowed, light_groups=frozenset({"POINT_SHADOWED", "AREA"}))
    assert [d for d in only.defines() if d[0].startswith("SL_LIGHTS_")] == [
        ("SL_LIGHTS_AREA", "1"), ("SL_LIGHTS_POINT_SHADOWED", "1")]
    assert replace(only, shadow_layers=0).light_groups == {"POINT", "AREA"}
    assert ("SL_ONE_LIGHT_LOOP", "1") in replace(only, light_groups=frozenset()).defines()
    # a scene whose point lights have no radius reads no light's shape; without point or spot
    # lights no radius can matter
    assert ("SL_LIGHT_RADII", "1") not in programs.Features("PBR", 4, frozenset({"POINT"}),
                                                            light_radii=False).defines()
    assert ("SL_LIGHT_RADII", "1") not in programs.Features("PBR", 4, frozenset({"SUN"})).defines()
    # likewise an area light's spread code: only where an area light may have one
    assert ("SL_AREA_SPREAD", "1") in programs.Features("PBR", 4, frozenset({"AREA"})).defines()
    assert ("SL_AREA_SPREAD", "1") not in programs.Features("PBR", 4, frozenset({"AREA"}),
                                                            area_spread=False).defines()
    assert ("SL_AREA_SPREAD", "1") not in a.defines()
    # and an area light's n-gon: only where one may be a disk or an ellipse
    assert ("SL_AREA_ELLIPSE", "1") in programs.Features("PBR", 4, frozenset({"AREA"})).defines()
    assert ("SL_AREA_ELLIPSE", "1") not in programs.Features("PBR", 4, frozenset({"AREA"}),
                                                             area_ellipse=False).defines()
    assert ("SL_AREA_ELLIPSE", "1") not in a.defines()
    # terms a model does not use do not split its programs
    bp = programs.Features("BLINN_PHONG", 4, frozenset({"POINT"}), S.Terms(ndf="BECKMANN", multiscatter=True))
    assert bp.defines() == programs.Features("BLINN_PHONG", 4, frozenset({"POINT"})).defines()
    assert programs.Features("PBR", 4, frozenset({"POINT"})).defines() == a.defines()
    assert [programs.light_slots(n) for n in (0, 1, 2, 3, 5, 64)] == [1, 1, 2, 4, 8, 64]
    with pytest.raises(ValueError, match="unknown shading model"):
        programs.Features("TOON")


def test_compile_error_reaches_the_user_and_clears(tmp_path, monkeypatch):
    scene = scenes.reset(size=8)
    scenes.ortho_camera(scene)
    scenes.plane(scene)
    scenes.light(scene, "SUN")
    real = programs.read_glsl

    def broken(name):
        text = real(name)
        return text + "\nthis is not GLSL;\n" if name == "model_pbr.glsl" else text

    gpu_library.LIBRARY.clear()
    monkeypatch.setattr(programs, "read_glsl", broken)
    with pytest.raises(RuntimeError, match="could not compile its PBR program"):
        bpy.ops.render.render()
    assert "could not compile" in gpu_library.LIBRARY.compile_error
    monkeypatch.setattr(programs, "read_glsl", real)
    gpu_library.LIBRARY.clear()
    assert scenes.render(scene, tmp_path / "ok.exr")[..., 0].max() > 0
    assert gpu_library.LIBRARY.compile_error == ""


def test_the_lights_block_holds_512_lights_of_the_texels_the_shaders_read():
    """A light is LIGHT_FLOATS floats on the CPU and LIGHT_TEXELS vec4 in the shaders
    (glsl/uniforms.glsl); the uniform block (64 KiB) holds the 512-light slot, the 1,024 go to the
    light texture."""
    source = (programs.glsl_dir() / "uniforms.glsl").read_text()
    texels = int(re.search(r"#define LIGHT_TEXELS (\d+)", source).group(1))
    assert programs.LIGHT_FLOATS == 4 * texels, (programs.LIGHT_FLOATS, texels)
    assert programs.light_block_fits(512) and not programs.light_block_fits(1024)
    assert 512 * texels * 16 <= programs.UNIFORM_BLOCK_BYTES < 1024 * texels * 16
    assert ("SL_LIGHT_BLOCK", "1") in programs.Features(max_lights=512, light_block=True).defines()
    assert ("SL_LIGHT_BLOCK", "1") not in programs.Features(max_lights=1024).defines()


def test_a_light_sequence_compiles_one_call_per_light_and_no_loop():
    """A scene of a few lights (programs.UNROLLED_LIGHTS) shades each by its own call, its index
    and kind constants: the define holds the calls in light_order's order; without shadow maps
    none looks a shadow up; with light culling (a tile's own list) the loops come back."""
    order = programs.LIGHT_GROUP_ORDER
    sequence = (order.index("POINT_SHADOWED"), order.index("SUN"))
    f = programs.Features("PBR", 2, frozenset({"POINT", "SUN"}), shadow_layers=6, shadow_size=1024,
                          light_sequence=sequence)
    defines = dict(f.defines())
    assert defines["SL_LIGHT_SEQUENCE"] == ("shade_light(c, s, ng, 0, LIGHT_POINT, true); "
                                            "shade_light(c, s, ng, 1, LIGHT_SUN, false);")
    assert not any(name.startswith("SL_LIGHTS_") or name == "SL_ONE_LIGHT_LOOP" for name in defines)
    code = _compiled(f)
    assert "shade_light(" in code and "SL_LIGHT_SEQUENCE" in code
    unshadowed = replace(f, shadow_layers=0)
    assert unshadowed.light_sequence == (order.index("POINT"), order.index("SUN"))
    assert "true" not in dict(unshadowed.defines())["SL_LIGHT_SEQUENCE"]
    tiled = replace(f, light_tiles=True)
    assert tiled.light_sequence == () and "SL_LIGHT_SEQUENCE" not in dict(tiled.defines())
    assert ("SL_LIGHTS_POINT_SHADOWED", "1") in tiled.defines()
    # from a scene's lights: at most UNROLLED_LIGHTS of them, in light_order's order
    lights = [S.Light(kind="SUN", position=(0, 0, 0), direction=(0, 0, -1), intensity=(1, 1, 1)),
              S.Light(kind="POINT", position=(0, 0, 1), direction=(0, 0, -1), intensity=(1, 1, 1))]
    assert programs.light_sequence(lights, (-1, 0)) == sequence
    assert programs.light_sequence(lights * 2, (-1, 0, -1, 0)) == ()
