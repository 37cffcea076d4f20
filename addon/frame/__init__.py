"""The GPU frame: a snapshot drawn as a list of passes through Blender's ``gpu`` module.

``renderer`` orders the passes of a frame, ``passes`` defines them (shadow maps, occlusion,
G-buffer, shading, transparency, exposure, post), ``gpu_scene`` holds one scene's GPU copy
(geometry, uniform buffers, textures, uploaded on change), ``gpu_library`` the compiled programs
and tables every renderer shares, ``gpu_environment`` the world's light precomputed on the GPU.
Imports ``gpu``, ``scene``, ``reference``, ``materials``, ``plan`` and itself; never ``bpy`` nor the Blender
layer: images and meshes arrive as arrays (``tests/test_layers.py``).
"""
