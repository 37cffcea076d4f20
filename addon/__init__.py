"""Shading Lab: a render engine that draws scenes with Blinn-Phong, Phong and physically based
GLSL shading, to see and measure what each model gets right and what it costs.

Package layout: ``snapshot``/``programs``/``brdf``/``multiscatter``/``shading``/``tonemap``/
``presets`` are pure Python (no ``bpy``); ``extract`` reads Blender data; ``gpu_library``,
``gpu_scene``, ``passes`` and ``renderer`` draw with ``gpu`` and read no Blender data;
``engine``/``viewport``/``properties``/``operators``/``ui`` are the Blender-facing layer.
Installed as an extension the package is ``bl_ext.<repo>.shading_lab``, so every import inside
it is relative.
"""



def _classes():
    # Imported here, not at the top: the pure modules (snapshot, programs, shading) must stay
    # importable without Blender, and importing this package runs this file first.
    from . import engine, operators, properties, ui

    return (*properties.classes, *engine.classes, *operators.classes, *ui.classes), (properties, ui, engine)


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
    from . import engine

    with engine.REGISTRATION:
        _register()


def _register():
    import atexit

    import bpy

    from . import engine

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

    from . import world_cache

    if __package__.startswith("bl_ext."):
        try:
            world_cache.set_user_folder(bpy.utils.extension_path_user(__package__, path="world_cache"))
        except Exception as exc:  # no user folder: the XDG cache folder then
            print(f"Shading Lab: no extension user folder for the world cache ({exc})")


#: How long unregister() waits for renders running on other threads to end.
RENDER_WAIT_S = 60.0


def unregister():
    from . import engine

    with engine.REGISTRATION:
        _unregister()


def _unregister():
    from . import engine, extract, gpu_library

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
    extract.IMAGES.clear()
    extract.GEOMETRY_MEMO.clear()
