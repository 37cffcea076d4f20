"""The scene snapshot: plain data (numpy arrays and dataclasses) that every later stage reads.

``snapshot`` holds the types a render is made of (lights, materials, meshes, the world, the
settings), ``presets`` reads and validates the TOML scene and material presets, ``exposure``
keeps automatic exposure's state from frame to frame, ``matrices`` inverts the matrices a render
needs. Pure Python: imports nothing from the other packages, nor ``bpy`` or ``gpu``
(``tests/test_layers.py``).
"""
