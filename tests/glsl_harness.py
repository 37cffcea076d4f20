"""Evaluate GLSL from glsl/ on the GPU over a table of inputs: one input set per pixel of a
float target, read back. Terms are tested in isolation this way, not only through renders.

    values = evaluate("result = vec4(D_GGX(a.x, a.y, a.z));", {"a": rows})

``rows`` are (N, 4) arrays; each name becomes a ``vec4`` in the body, which assigns the
``vec4 result``. The shader library (the same files, in the same order, as the product's
programs) and any defines are compiled in; model files may be added for their shade_direct().
"""

from __future__ import annotations

import math

import gpu
import numpy as np
from gpu_harness import run_on_gpu

from addon.frame import gpu_library, gpu_scene
from addon.plan import programs

LIBRARY = programs.FRAGMENT_LIBRARY + programs.PBR_LIBRARY + ("tonemap.glsl",)
WIDTH = 256


def _texture(rows: np.ndarray, w: int, h: int) -> gpu.types.GPUTexture:
    padded = np.zeros((w * h, 4), np.float32)
    padded[: len(rows)] = rows
    data = gpu.types.Buffer("FLOAT", w * h * 4, padded.ravel())  # numpy's buffer: one copy, no list
    return gpu.types.GPUTexture((w, h), format="RGBA32F", data=data)


def evaluate(body: str, inputs: dict[str, np.ndarray], defines: dict[str, str] | None = None,
             extra: tuple[str, ...] = (), terms=None, source: str = "",
             samplers: dict | None = None) -> np.ndarray:
    """(N, 4) float32: ``result`` of ``body`` for each row of the inputs; ``source`` is GLSL
    placed after the ``extra`` files, before main(). ``samplers``: more ``sampler2D`` the code
    reads, by name: a GPU texture, or an ``ImageData`` uploaded as the engine uploads it
    (addon/frame/gpu_scene.image_texture)."""
    arrays = {name: np.asarray(a, np.float32).reshape(-1, 4) for name, a in inputs.items()}
    n = len(next(iter(arrays.values())))
    w = min(n, WIDTH)
    h = math.ceil(n / w)
    defs = {"SL_MAX_LIGHTS": "1", "SL_OBJECT_BLOCK": str(programs.OBJECT_BLOCK), **(defines or {})}
    fetch = "\n".join(f"  vec4 {name} = texelFetch(in_{name}, px, 0);" for name in arrays)
    main = f"void main()\n{{\n  ivec2 px = ivec2(gl_FragCoord.xy);\n{fetch}\n  vec4 result = vec4(0.0);\n" \
           f"  {body}\n  frag_color = result;\n}}\n"
    fragment = "\n".join([programs.read_glsl(f) for f in LIBRARY + tuple(extra)] + [source, main])

    def job(_depsgraph):
        info = gpu.types.GPUShaderCreateInfo()
        for name, value in sorted(defs.items()):
            info.define(name, value)
        info.typedef_source(programs.read_glsl("uniforms.glsl"))
        slot = 0
        layers = "SL_LAYERS" in defs  # the layering estimate (principled.glsl)
        albedo_table = "SL_MULTISCATTER" in defs or layers or "SL_LTC" in defs
        if albedo_table:
            info.sampler(slot, "FLOAT_2D", "ms_table")
            slot += 1
        if layers:
            info.sampler(slot, "FLOAT_2D", "s_table")
            slot += 1
        if "SL_LTC" in defs:
            info.sampler(slot, "FLOAT_2D", "ltc_table")
            slot += 1
        if "SL_SHEEN" in defs:
            info.sampler(slot, "FLOAT_2D", "sheen_table")
            slot += 1
        film_table = "SL_THIN_FILM" in defs and "SL_THIN_FILM_CYCLES_4" not in defs  # (4.x's: no table)
        if film_table:
            info.sampler(slot, "FLOAT_2D", "thin_film_table")
            slot += 1
        if "SL_SUBSURFACE" in defs:
            info.sampler(slot, "FLOAT_2D", "subsurface_table")
            slot += 1
        for name in arrays:
            info.sampler(slot, "FLOAT_2D", f"in_{name}")
            slot += 1
        for name in samplers or {}:
            info.sampler(slot, "FLOAT_2D", name)
            slot += 1
        info.vertex_in(0, "VEC2", "pos")
        info.fragment_out(0, "VEC4", "frag_color")
        info.vertex_source(programs.read_glsl("post.vert.glsl"))
        info.fragment_source(fragment)
        shader = gpu.shader.create_from_info(info)
        textures = {name: _texture(a, w, h) for name, a in arrays.items()}
        bound = {name: t if isinstance(t, gpu.types.GPUTexture) else gpu_scene.image_texture(t)
                 for name, t in (samplers or {}).items()}
        fmt = gpu.types.GPUVertFormat()
        fmt.attr_add(id="pos", comp_type="F32", len=2, fetch_mode="FLOAT")
        vbo = gpu.types.GPUVertBuf(fmt, 3)
        vbo.attr_fill("pos", ((-1.0, -1.0), (3.0, -1.0), (-1.0, 3.0)))
        batch = gpu.types.GPUBatch(type="TRIS", buf=vbo)
        target = gpu.types.GPUOffScreen(w, h, format="RGBA32F")
        try:
            with target.bind():
                fb = gpu.state.active_framebuffer_get()
                fb.clear(color=(0.0, 0.0, 0.0, 0.0))
                shader.bind()
                if albedo_table:
                    shader.uniform_sampler("ms_table", gpu_library.albedo_table(terms, "SL_GLOSSY" in defs))
                if layers:
                    shader.uniform_sampler("s_table", gpu_library.s_table())
                if "SL_LTC" in defs:
                    shader.uniform_sampler("ltc_table", gpu_library.ltc_table(terms))
                if "SL_SHEEN" in defs:
                    shader.uniform_sampler("sheen_table", gpu_library.sheen_table())
                if film_table:
                    shader.uniform_sampler("thin_film_table", gpu_library.thin_film_table())
                if "SL_SUBSURFACE" in defs:
                    shader.uniform_sampler("subsurface_table", gpu_library.subsurface_table())
                for name, texture in textures.items():
                    shader.uniform_sampler(f"in_{name}", texture)
                for name, texture in bound.items():
                    shader.uniform_sampler(name, texture)
                batch.draw(shader)
                out = fb.read_color(0, 0, w, h, 4, 0, "FLOAT")
        finally:
            target.free()
        out.dimensions = w * h * 4
        return np.array(out, np.float32).reshape(-1, 4)[:n]

    return run_on_gpu(job)
