"""The numpy reference twins: the shading math of ``glsl/`` written again in numpy, term for term.

``brdf`` (the BRDF terms), ``shading`` (lights and shading models), ``environment`` (the world's
light), ``ltc`` (area lights' linearly transformed cosines), ``multiscatter`` (the albedo tables,
shipped in ``tables.npz``) and ``tonemap`` (exposure, tone curves, transfer functions). The tests
hold each GLSL function to its twin, and each twin to independent sources. Pure Python: imports
only ``scene`` and itself, never ``bpy`` or ``gpu`` (``tests/test_layers.py``).
"""
