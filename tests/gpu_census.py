"""A census of the GPU objects the add-on makes: every texture, framebuffer, uniform buffer,
vertex/index buffer, batch, offscreen target and shader created while it runs, and which of them
are still alive.

Blender's ``gpu`` types take neither weak references nor subclasses, so the census replaces their
constructors (``gpu.types.GPUTexture`` and the rest, ``gpu.shader.create_from_info``) with
functions that make the real object and keep it in a list. An object is *alive* while anything
but that list refers to it: ``settle()`` drops every object only the list holds (which frees it
on the GPU), repeats until nothing more goes (a batch going frees its vertex buffer), and returns
what is left, by kind.
"""

from __future__ import annotations

import collections
import contextlib
import gc
import sys

import gpu

TYPES = ("GPUTexture", "GPUFrameBuffer", "GPUUniformBuf", "GPUVertBuf", "GPUIndexBuf", "GPUBatch",
         "GPUOffScreen")


class Census:
    def __init__(self):
        self.held: list = []
        self.made: collections.Counter = collections.Counter()

    def _counting(self, kind: str, make):
        def counted(*args, **kwargs):
            obj = make(*args, **kwargs)
            self.held.append(obj)
            self.made[kind] += 1
            return obj
        return counted

    @contextlib.contextmanager
    def active(self):
        """Count what is made inside the ``with`` block (the constructors are restored after)."""
        originals = {name: getattr(gpu.types, name) for name in TYPES}
        create = gpu.shader.create_from_info
        try:
            for name, make in originals.items():
                setattr(gpu.types, name, self._counting(name, make))
            gpu.shader.create_from_info = self._counting("GPUShader", create)
            yield self
        finally:
            for name, make in originals.items():
                setattr(gpu.types, name, make)
            gpu.shader.create_from_info = create

    def settle(self) -> collections.Counter:
        """The objects made so far that are still referenced outside the census, by kind."""
        gc.collect()
        while True:
            # an object in the list, bound to the comprehension's name and passed to getrefcount
            # has three references; one more means someone else holds it
            alive = [obj for obj in self.held if sys.getrefcount(obj) > 3]
            if len(alive) == len(self.held):
                break
            self.held = alive  # the rest go now, and with them what only they referred to
        return collections.Counter(type(obj).__name__ for obj in self.held)

    def forget(self) -> None:
        """Stop holding anything (the objects still alive stay alive, uncounted)."""
        self.held = []
