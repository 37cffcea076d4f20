"""Planning a frame from the snapshot: what to compute, before anything is drawn.

``programs`` turns a scene's features into defines and GLSL source (the program-cache key) and
packs the uniform blocks; ``shadows`` places each light's shadow maps; ``light_tiles`` decides
which lights reach which screen tiles; ``auto_terms`` picks each material's cheapest terms within
the artist's error bound (costs in ``term_costs.json``); ``world_cache`` keeps the world's
precomputed maps on disk. Pure Python: imports ``scene``, ``reference``, ``materials`` and
itself, never ``bpy`` or ``gpu`` (``tests/test_layers.py``).
"""
