"""Timing in one process, round-robin: every configuration rendered in turn, round after round
with the order rotated each round, so that machine noise hits them alike; round 0 is an untimed
warm-up (program compiles, tables, caches), the medians are over the timed rounds. What the
benchmarks compare are ratios measured in one such run (CPU-rasteriser times: Mesa llvmpipe).

A run's configurations share one process on purpose: a ratio between two configurations is
only as good as the conditions they share. Where a first use is what is measured, the
benchmark starts a fresh process per case instead (``process.run_case``)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Hashable, Sequence

import render as cli


class Progress(cli.Progress):
    """render.py's progress line, its total growing as the run announces what comes."""

    def __init__(self):
        super().__init__(0)

    def expect(self, steps: int) -> None:
        self.total += steps

    def step(self, label: str) -> None:
        self.total = max(self.total, self.done + 1)
        super().step(label)


def render_timed(scene=None) -> dict[str, float]:
    """One final render: the engine's phase times (``engine.last_timings``: extraction, draw with
    the GPU work fenced by the read-back, result; Shading Lab only) and the operator's
    ``wall_ms``."""
    import bpy

    from addon.blender import engine

    scene = scene or bpy.context.scene
    ours = scene.render.engine == "SHADING_LAB"
    engine.last_timings.clear()
    start = time.perf_counter()
    try:
        bpy.ops.render.render()
    except RuntimeError as exc:
        raise cli.CliError(f"render failed ({scene.render.engine}): {str(exc).strip()}") from None
    wall = 1e3 * (time.perf_counter() - start)
    if ours and not engine.last_timings:
        raise cli.CliError("Shading Lab reported no timings: the render failed (see the console)")
    return {**(dict(engine.last_timings) if ours else {}), "wall_ms": wall}


def medians(samples: list[dict[str, float]]) -> dict[str, float]:
    return {k: statistics.median(s[k] for s in samples) for k in samples[0]}


def collect(items: Sequence, rounds: int, run: Callable, progress: Progress | None = None, label: str = "",
            state_of: Callable | None = None) -> list[list[dict[str, float]]]:
    """``run(item)`` -> timings, for one warm-up round then ``rounds`` timed rounds, the order
    rotated each round; every timed round's timings of each item, in ``items``' order.

    ``state_of(item)``: what a render leaves behind that the next one pays for (the engine it
    drew with, the size of its shadow maps ...). A timed render that follows a render of another
    state is preceded by an untimed one of its own, so that each item is timed in its steady
    state (on the CPU rasteriser our first render after an EEVEE render took 50-100 ms longer,
    1.5-2.5x on hdr's ~95 ms frame, its shadow pass 23-33 -> 91-113 ms; a Workbench render in
    between cost nothing: consistent with EEVEE's hundreds of programs displacing ours from the
    rasteriser's cache of compiled code, not established)."""
    if progress is not None:
        progress.expect((rounds + 1) * len(items))
    samples: list[list[dict[str, float]]] = [[] for _ in items]
    order = list(range(len(items)))
    last = None
    for r in range(rounds + 1):
        k = r % len(items)
        for i in order[k:] + order[:k]:
            state = state_of(items[i]) if state_of is not None else None
            if r > 0 and state != last:
                run(items[i])  # settles this state after another's render
            t = run(items[i])
            last = state
            if r > 0:
                samples[i].append(t)
            if progress is not None:
                progress.step(f"{label} round {r}/{rounds}".strip())
    return samples


def round_robin(items: Sequence, rounds: int, run: Callable, progress: Progress | None = None,
                label: str = "", state_of: Callable | None = None) -> list[dict[str, float]]:
    """``collect``'s median timings of each item, in ``items``' order."""
    return [medians(s) for s in collect(items, rounds, run, progress, label, state_of)]


def median_ms(configs: Sequence[Hashable], apply: Callable[[Hashable], None], rounds: int,
              progress: Progress | None = None, label: str = "", key: str = "draw_ms",
              state_of: Callable | None = None) -> dict:
    """{config: median ``key`` of the scene's render (default the engine's draw time, GPU work
    fenced by the read-back)}; ``apply(config)`` sets the scene up for one."""

    def run(config):
        apply(config)
        return render_timed()

    times = round_robin(list(configs), rounds, run, progress, label, state_of)
    return {c: t[key] for c, t in zip(configs, times)}
