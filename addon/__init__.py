"""Shading Lab: a render engine that draws scenes with Blinn-Phong, Phong and physically based
GLSL shading, to see and measure what each model gets right and what it costs.

Package layout: ``snapshot``/``programs``/``shading`` are pure Python (no ``bpy``); ``extract``
reads Blender data; ``renderer`` draws with ``gpu``; ``engine``/``properties``/``ui`` are the
Blender-facing layer. Installed as an extension the package is ``bl_ext.<repo>.shading_lab``,
so every import inside it is relative.
"""



def _classes():
    # Imported here, not at the top: the pure modules (snapshot, programs, shading) must stay
    # importable without Blender, and importing this package runs this file first.
    from . import engine, operators, properties, ui

    return (*properties.classes, *engine.classes, *operators.classes, *ui.classes), (properties, ui)


def register():
    import bpy

    classes, modules = _classes()
    for cls in classes:
        bpy.utils.register_class(cls)
    for module in modules:
        module.register()


def unregister():
    import bpy

    from . import renderer

    classes, modules = _classes()
    for module in reversed(modules):
        module.unregister()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
    renderer.clear_program_cache()
