"""The material compiler: a material's shader node tree (``scene.nodes``, read by
``blender.nodes``) turned into what the shading programs evaluate per fragment.

``graph`` flattens a tree as Blender evaluates it: node groups inlined at any depth (the active
Group Output, a group used twice), reroutes and muted nodes passed through as Blender passes them,
every input resolved to a constant or to one node's output, only what the output reaches kept, in
the order it is computed. ``convert`` is the one table of Blender's implicit conversions between
socket types. ``codegen`` writes a flat graph as one GLSL function (glsl/node_*.glsl). Pure
Python: imports ``scene`` and itself, never ``bpy`` or ``gpu``
(``tests/test_layers.py``).
"""
