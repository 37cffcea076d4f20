"""The numpy reference twins: the shading math of ``glsl/`` written again in numpy, term for term.

``brdf`` (the BRDF terms), ``shading`` (lights and shading models), ``environment`` (the world's
light), ``ltc`` (area lights' linearly transformed cosines), ``multiscatter`` (the albedo tables,
shipped in ``tables.npz``), ``tonemap`` (exposure, tone curves, transfer functions) and ``normals``
(Cycles' rules for a bent normal's light: the terminator's shadowing, the valid specular normal); ``color``
the colour nodes' (blend modes, HSV and HSL, colour converters). The tests
hold each GLSL function to its twin, and each twin to independent sources. Pure Python: imports
only ``scene`` and itself, never ``bpy`` or ``gpu`` (``tests/test_layers.py``).
"""
