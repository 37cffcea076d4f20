"""The world's precomputed maps kept on disk between sessions, by their content.

An image-lit world's maps (``gpu_environment``: the prefiltered atlas and the spherical
harmonics) take 0.2 s (a 1K world) to ~0.9 s (4K) on the GPU each time a session first renders
that world. They depend only on the lighting field's content and on the code that computes them,
so they are written here once, one file per world (``<key>.maps``: numpy ``.npy`` records, the
arrays' names then each array, uncompressed, 13.4 MB for any world 1K or wider), and read back by
the first render of a later session in ~20 ms (float32: the same maps to the bit). The
downsampled chains that surfaces sampling the world per pixel read are not kept: drawn again
when such a surface first asks (~40-80 ms), they would triple the file.

- The key (``content_key``) hashes the code (every GLSL file and the Python modules that build
  the maps), the GPU that drew them, and the field: its constant, the sun threshold, each image
  term's pixels (as read), weight, projection, interpolation and mapping. A changed pixel, a new
  version of the add-on or another GPU makes another key; a stale file is never read.
- Files are written by a background thread (to a temporary name, then renamed: a reader never sees
  half a file), and the folder is kept under ``budget_bytes()``, the least recently used dropped.
  A file that does not read back as expected is deleted and the maps are built again.
- The folder: ``SHADING_LAB_CACHE`` if set (``off`` turns the cache off), else the extension's
  user folder (``bpy.utils.extension_path_user``, which registration hands to
  ``set_user_folder``) when installed as an extension, else
  ``$XDG_CACHE_HOME/shading_lab`` (``~/.cache/shading_lab``). ``SHADING_LAB_CACHE_MB`` sets the
  budget (1024 MB by default: 76 worlds at 13.4 MB).

Pure Python (no ``bpy``, no ``gpu``): the GPU side (reading textures back, making them again) is
``gpu_environment``'s.
"""

from __future__ import annotations

import hashlib
import os
import threading
from pathlib import Path

import numpy as np

from ..scene.snapshot import MAX_ENVIRONMENT_IMAGES, World
from . import programs

DEFAULT_BUDGET_MB = 1024
_OFF = {"off", "0", "none", "false", "no"}

_lock = threading.Lock()
_code_digest: str | None = None
_writers: list[threading.Thread] = []
_warned: set[str] = set()
_user_folder: Path | None = None
#: Files written since start (tests count them).
SAVES = 0


def folder() -> Path | None:
    """Where the maps are kept, or None when the cache is off."""
    setting = os.environ.get("SHADING_LAB_CACHE", "").strip()
    if setting.lower() in _OFF:
        return None
    if setting:
        return Path(setting).expanduser()
    if _user_folder is not None:
        return _user_folder
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "shading_lab"


def set_user_folder(path) -> None:
    """The folder to use unless ``SHADING_LAB_CACHE`` says otherwise: registration passes the
    extension's user folder (None: the XDG cache folder)."""
    global _user_folder
    _user_folder = None if path is None else Path(path)


def budget_bytes() -> int:
    try:
        megabytes = float(os.environ.get("SHADING_LAB_CACHE_MB", DEFAULT_BUDGET_MB))
    except ValueError:
        megabytes = DEFAULT_BUDGET_MB
    return int(max(megabytes, 0.0) * (1 << 20))


def code_digest() -> str:
    """A hash of the code the maps come from: every GLSL file and the modules that compute them
    (read once per session)."""
    global _code_digest
    if _code_digest is None:
        package = Path(__file__).resolve().parents[1]
        h = hashlib.sha1()
        modules = [package / name for name in ("reference/environment.py", "frame/gpu_environment.py",
                                               "plan/world_cache.py")]
        for path in sorted(programs.glsl_dir().glob("*.glsl")) + modules:
            h.update(path.name.encode())
            h.update(path.read_bytes() if path.is_file() else b"-")
        _code_digest = h.hexdigest()
    return _code_digest


def content_key(terms, threshold: float, suns: bool, device: str = "") -> str:
    """The file name (without suffix) of the maps of the lighting field ``terms`` (its constant and
    its first ``MAX_ENVIRONMENT_IMAGES`` image terms, as the GPU sums them), with its brightest
    texels clamped at ``threshold`` when ``suns`` were split off, drawn by ``device``."""
    h = hashlib.sha1()
    h.update(code_digest().encode())
    h.update(device.encode())
    h.update(np.asarray([*World.constant(terms), threshold, float(suns)], np.float64).tobytes())
    for term in World.images(terms)[:MAX_ENVIRONMENT_IMAGES]:
        pixels = np.ascontiguousarray(term.image.pixels)
        h.update(f"{term.image.storage}|{pixels.dtype.str}|{pixels.shape}|{term.projection}|"
                 f"{bool(term.closest)}".encode())
        h.update(np.asarray(term.weight, np.float64).tobytes())
        h.update(np.asarray(term.lookup, np.float32).tobytes())
        h.update(pixels.data)
    return h.hexdigest()


def load(key: str, shapes: dict[str, tuple]) -> dict[str, np.ndarray] | None:
    """The arrays kept for ``key``, if there and each of the shape ``shapes`` says; None
    otherwise. A file that does not read back whole is deleted."""
    where = folder()
    if where is None:
        return None
    path = where / f"{key}.maps"
    if not path.is_file():
        return None
    try:
        with open(path, "rb") as stream:
            names = [str(n) for n in np.lib.format.read_array(stream, allow_pickle=False)]
            arrays = {name: np.lib.format.read_array(stream, allow_pickle=False) for name in names}
        for name, shape in shapes.items():
            if name not in arrays or arrays[name].shape != tuple(shape) or arrays[name].dtype.kind != "f":
                found = arrays[name].shape if name in arrays else "nothing"
                raise ValueError(f"{name}: expected floats of shape {tuple(shape)}, found {found}")
        os.utime(path)  # recently used: kept longest
    except Exception as exc:  # truncated, corrupt or foreign: build the maps again
        _warn_once(f"unreadable:{path}", f"Shading Lab: the world cache file {path} could not be read "
                                          f"({exc}); the world's lighting is computed again")
        try:
            path.unlink()
        except OSError:
            pass
        return None
    return arrays


def save_later(key: str, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` for ``key`` on a background thread (the render goes on), then keep the
    folder within its budget. Failing to write (a read-only disk, no space) says so once on the
    console and changes nothing else."""
    where = folder()
    if where is None:
        return
    # not a daemon (Blender's render threads are, to Python): the interpreter waits for it at exit
    thread = threading.Thread(target=_write, args=(where, key, arrays), name="shading-lab-world-cache",
                              daemon=False)
    with _lock:
        _writers[:] = [t for t in _writers if t.is_alive()]
        _writers.append(thread)
    thread.start()


def wait() -> None:
    """Until every pending write is done (tests and benchmarks; at exit the interpreter waits for
    them too)."""
    with _lock:
        pending = list(_writers)
    for thread in pending:
        thread.join()


def _write(where: Path, key: str, arrays: dict[str, np.ndarray]) -> None:
    global SAVES
    path = where / f"{key}.maps"
    temporary = where / f"{key}.{os.getpid()}.{threading.get_ident()}.tmp"
    try:
        where.mkdir(parents=True, exist_ok=True)
        with open(temporary, "wb") as stream:  # .npy records: the names, then each array
            np.lib.format.write_array(stream, np.array(list(arrays)), allow_pickle=False)
            for array in arrays.values():
                np.lib.format.write_array(stream, np.ascontiguousarray(array), allow_pickle=False)
        os.replace(temporary, path)
        with _lock:
            SAVES += 1
        _keep_within_budget(where, budget_bytes())
    except OSError as exc:
        try:
            temporary.unlink()
        except OSError:
            pass
        _warn_once(f"write:{where}", f"Shading Lab: cannot keep the world's lighting in {where} ({exc}); "
                                     f"it is computed again in the next session")


def usage() -> tuple[int, int]:
    """(worlds, bytes) kept in the folder now (0, 0 when it is off or empty)."""
    where = folder()
    if where is None or not where.is_dir():
        return 0, 0
    sizes = []
    for path in where.glob("*.maps"):
        try:
            sizes.append(path.stat().st_size)
        except OSError:
            continue
    return len(sizes), sum(sizes)


def clear() -> tuple[int, int]:
    """Delete every kept world (after pending writes): (worlds, bytes) deleted."""
    wait()
    where = folder()
    if where is None or not where.is_dir():
        return 0, 0
    count = size = 0
    for path in where.glob("*.maps"):
        try:
            bytes_ = path.stat().st_size
            path.unlink()
        except OSError:
            continue
        count, size = count + 1, size + bytes_
    return count, size


def _keep_within_budget(where: Path, budget: int) -> None:
    """Delete the least recently used files until the folder's maps fit in ``budget`` bytes;
    temporary files a stopped writer left behind go too once an hour old."""
    import time

    files = []
    for path in where.iterdir():
        try:
            stat = path.stat()
        except OSError:
            continue
        if path.suffix == ".tmp" and time.time() - stat.st_mtime > 3600:
            path.unlink(missing_ok=True)
        elif path.suffix == ".maps":
            files.append((stat.st_mtime, stat.st_size, path))
    files.sort()
    total = sum(size for _, size, _ in files)
    for _, size, path in files:
        if total <= budget:
            break
        path.unlink(missing_ok=True)
        total -= size


def _warn_once(what: str, message: str) -> None:
    with _lock:
        if what in _warned:
            return
        _warned.add(what)
    print(message)
