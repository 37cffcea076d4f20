"""Blender's orco: the undeformed positions of a deformed mesh, from which Cycles takes Generated
texture coordinates (intern/cycles/blender/mesh.cpp, attr_create_generated: the CD_ORCO layer
mapped by the texture space), so that a texture stays on a surface an armature, shape keys, a
lattice, hooks or any deforming modifier move.

Python sees no CD_ORCO layer, so it is made again from what it does see. Blender's modifier stack
(blenkernel's mesh_calc_modifiers, learnt from) makes it of the original mesh's vertex positions
(``BKE_mesh_orco_verts_get``: shape keys' basis, before any key or modifier) carried through the
constructive modifiers alone, deforming ones left out; where the stack only deformed the mesh, or
kept its vertices' number, that is the original mesh's positions, vertex for vertex. Where a
deformation comes with modifiers that change the number of vertices (an Armature and a Subdivision
Surface) it cannot be made without evaluating the stack again without its deformations, which
would change the artist's file: Generated then follows the deformed surface, and a note says so.
"""

from __future__ import annotations

import numpy as np


def _positions(mesh) -> np.ndarray:
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def undeformed_positions(obj, mesh, depsgraph) -> tuple[np.ndarray | None, str]:
    """(positions, note): the undeformed positions ((V, 3) float32, object space, one per vertex of
    ``mesh``, ``obj``'s evaluated mesh) where a deformation moved its vertices and the stack kept
    their number; None where nothing deformed them (Generated from the positions as they are, as
    Blender keeps no orco then), or where they cannot be made (``note`` says why: a deformation
    beside modifiers that change the number of vertices). An object in Edit Mode takes its positions
    as they are (its original mesh's are only written back when it leaves Edit Mode), and so does
    a mesh a Geometry Nodes modifier instances in the object's name (not the object's own)."""
    original = obj.original
    source = getattr(original, "data", None)
    if source is None or getattr(original, "mode", "OBJECT") == "EDIT":
        return None, ""
    if obj.data is None or obj.data.as_pointer() != original.evaluated_get(depsgraph).data.as_pointer():
        return None, ""  # another mesh drawn in the object's name (Geometry Nodes' instances): not its own
    settings = "RENDER" if getattr(depsgraph, "mode", "VIEWPORT") == "RENDER" else "PREVIEW"
    if not original.is_deform_modified(depsgraph.scene, settings):
        return None, ""  # constructive modifiers alone: the orco is the positions they made
    if len(source.vertices) != len(mesh.vertices):
        return None, (f"Object '{original.name}': its Generated coordinates follow the deformed surface "
                      f"(it is deformed, and its modifiers change its number of vertices)")
    undeformed = _positions(source)
    if np.array_equal(undeformed, _positions(mesh)):
        return None, ""  # deformed by nothing (an armature at rest, keys at 0)
    return undeformed, ""
