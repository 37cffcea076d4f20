"""The Blender layer: the only code that reads Blender data for rendering or talks to its UI.

``engine`` is the render engine (final renders, previews) and ``viewport`` its interactive
session; ``extract`` reads the evaluated depsgraph into a ``scene.snapshot.Snapshot`` (the only
module that reads scene data for rendering); ``properties``, ``ui`` and ``operators`` are the
settings, panels and operators; ``scene_builder`` builds preset scenes into Blender and
``world_bake`` renders an unreadable world with Cycles. May import every other package, ``bpy``,
``gpu`` and ``mathutils``; nothing below it imports it (``tests/test_layers.py``).
"""
