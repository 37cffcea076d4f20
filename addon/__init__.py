"""Shading Lab: a render engine that draws scenes with Blinn-Phong, Phong and physically based
GLSL shading, to see and measure what each model gets right and what it costs.

Packages, lowest first; each imports only those above it in this list (``tests/test_layers.py``).
A render runs up the list: ``blender.extract`` reads the depsgraph into a ``scene`` snapshot,
``plan`` decides what to compute, ``frame`` draws it, ``blender.engine`` hands back the result.

- ``scene``: the snapshot, plain data; presets, exposure state, matrices. Pure Python.
- ``reference``: the numpy twins of ``glsl/``'s shading math. Pure Python.
- ``materials``: the material compiler: shader node trees flattened as Blender evaluates them.
  Pure Python.
- ``plan``: programs and their defines, shadow-map layout, light culling, the Auto term set,
  the world cache. Pure Python.
- ``frame``: the GPU frame (passes, programs, uploaded scene) through ``gpu``; no ``bpy``.
- ``blender``: engine, viewport, extraction, properties, panels, operators; the only ``bpy``.

Installed as an extension the package is ``bl_ext.<repo>.shading_lab``, so every import inside
it is relative.
"""



def _classes():
    # Imported here, not at the top: the pure modules (snapshot, programs, shading) must stay
    # importable without Blender, and importing this package runs this file first.
    from .blender import engine, operators, properties, ui

    return ((*properties.classes, *engine.classes, *operators.classes, *ui.classes),
            (properties, ui, engine, operators))


_registered = False


def _undo(items) -> None:
    """Unregister ``items`` (classes and modules, in the order they were registered), last first."""
    import bpy

    for item in reversed(items):
        if isinstance(item, type):
            bpy.utils.unregister_class(item)
        else:
            item.unregister()


def register():
    from .blender import engine

    with engine.REGISTRATION:
        _register()


def _register():
    import atexit

    import bpy

    from .blender import engine

    global _registered
    if _registered:
        return
    engine.ACTIVITY.wait_idle(RENDER_WAIT_S)  # not while a render on another thread uses RNA
    classes, modules = _classes()
    done: list = []
    try:
        for cls in classes:
            bpy.utils.register_class(cls)
            done.append(cls)
        for module in modules:
            module.register()
            done.append(module)
    except Exception:  # leave nothing half-registered: the next register() starts clean
        _undo(done)
        raise
    _registered = True
    _use_extension_folder()
    if not bpy.app.binary_path:
        # Blender as a Python module never disables add-ons at exit, and 4.x then leaks the
        # registered classes and can hang in its exit destructors: unregister first (once).
        atexit.unregister(unregister)
        atexit.register(unregister)


def _use_extension_folder() -> None:
    """Installed as an extension, the world cache lives in the extension's own user folder."""
    import bpy

    from .plan import world_cache

    if __package__.startswith("bl_ext."):
        try:
            world_cache.set_user_folder(bpy.utils.extension_path_user(__package__, path="world_cache"))
        except Exception as exc:  # no user folder: the XDG cache folder then
            print(f"Shading Lab: no extension user folder for the world cache ({exc})")


#: How long unregister() waits for renders running on other threads to end.
RENDER_WAIT_S = 60.0


def unregister():
    from .blender import engine

    with engine.REGISTRATION:
        _unregister()


def _unregister():
    from .blender import engine, extract, geometry, images
    from .frame import gpu_library

    global _registered
    if not _registered:
        return
    # a final render or preview may be running on its own thread: let it finish with the engine
    # and programs it uses (a render cannot outlive its engine class)
    if not engine.ACTIVITY.wait_idle(RENDER_WAIT_S):
        print(f"Shading Lab: a render was still running after {RENDER_WAIT_S:.0f} s; unregistering anyway")
    _registered = False
    classes, modules = _classes()
    _undo([*classes, *modules])
    gpu_library.LIBRARY.clear()
    images.IMAGES.clear()
    geometry.GEOMETRY_MEMO.clear()
    extract.FALLBACK_READS.clear()
    extract.bake.forget()
