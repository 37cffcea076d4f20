"""Ending a script's process the same way on every Blender release.

Blender 4.x as a Python module can hang for ever in its C++ static destructors at process exit
(one destroys a condition variable that a worker thread still waits on; seen with bpy 4.5.15 on
about every script that rendered). ``leave`` runs the Python clean-up, Blender's own exit handler
included, then on those releases ends the process without the destructors.
"""

from __future__ import annotations

import atexit
import os
import sys


def leave(code: int) -> None:
    """End the process with exit status ``code``."""
    sys.stdout.flush()
    sys.stderr.flush()
    if code:
        os._exit(code)  # inside `blender --python`, sys.exit would not end Blender's process
    bpy = sys.modules.get("bpy")
    if bpy is not None and not bpy.app.binary_path and bpy.app.version < (5, 0, 0):
        atexit._run_exitfuncs()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
    sys.exit(0)
