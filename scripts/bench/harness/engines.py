"""The other renderers, set up one way for every benchmark: EEVEE and Workbench as peers timed
beside Shading Lab, Cycles as the reference. The settings themselves live in
``scripts/reference.py`` (which ``compare.py`` and ``results.py`` use too): Cycles direct light
only, world on and occluded, lights as the file has them, pixel centres, cached on disk; EEVEE
with its light threshold lowered, lights and shadows as the file has them; Workbench with its
own studio lighting."""

from __future__ import annotations

import time
from pathlib import Path

from . import timing

OURS = "SHADING_LAB"
#: key -> (label, engine, samples); "EEVEE" stands for this Blender's EEVEE (``reference.EEVEE``).
PEERS = {"eevee-1": ("EEVEE 1 spp", "EEVEE", 1), "eevee-16": ("EEVEE 16 spp", "EEVEE", 16),
         "workbench": ("Workbench", "BLENDER_WORKBENCH", 1)}


def label(peer: str) -> str:
    return PEERS[peer][0]


def engine_id(peer: str) -> str:
    import reference

    engine = PEERS[peer][1]
    return reference.EEVEE if engine == "EEVEE" else engine


def use(scene, peer: str) -> None:
    """Render ``scene`` with the peer ``peer`` (a key of ``PEERS``) from now on."""
    import reference

    reference.use_engine(scene, engine_id(peer), PEERS[peer][2])


def timed(scene, peer: str) -> dict[str, float]:
    """One render of the peer: ``{"wall_ms": ...}`` (``timing.render_timed``)."""
    use(scene, peer)
    return timing.render_timed(scene)


def image(scene, path: Path, peer: str | None = None) -> tuple:
    """(image, wall ms) of a render with the scene's engine, or the peer's, through a 32-bit EXR
    at ``path`` (the engine restored after a peer's)."""
    import reference

    previous = scene.render.engine
    try:
        if peer is not None:
            use(scene, peer)
        start = time.perf_counter()
        pixels = reference.render_to_array(scene, path)
        return pixels, 1e3 * (time.perf_counter() - start)
    finally:
        scene.render.engine = previous


def cycles(scene, samples: int, cache: bool = True) -> tuple:
    """(Cycles reference image, whether it came from the cache): ``reference.render_reference``;
    ``cache`` False for scenes whose fingerprint misses what sets them apart (rays' visibility)."""
    import reference

    return reference.render_reference(scene, samples=samples, **({} if cache else {"cache_dir": None}))
