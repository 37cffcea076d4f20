"""Shading Lab: a render engine that draws scenes with Blinn-Phong, Phong and physically based
GLSL shading, to see and measure what each model gets right and what it costs.

Package layout: ``snapshot``/``programs``/``shading`` are pure Python (no ``bpy``); ``extract``
reads Blender data; ``renderer`` draws with ``gpu``; ``engine``/``properties``/``ui`` are the
Blender-facing layer. Installed as an extension the package is ``bl_ext.<repo>.shading_lab``,
so every import inside it is relative.
"""

import bpy

from . import engine, properties, ui

_CLASSES = (*properties.classes, *engine.classes, *ui.classes)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    ui.register()


def unregister():
    ui.unregister()
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
    from . import renderer

    renderer.clear_program_cache()
