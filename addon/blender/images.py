"""Images read for rendering: each image's pixels read once per session into ``ImageData`` and
kept while the image is unchanged (``IMAGES``), UDIM tiles one by one, keyed by ``image_key``."""

from __future__ import annotations

import itertools
import os
import tempfile
import threading

import bpy
import numpy as np

from ..scene import snapshot as S


def image_key(image: bpy.types.Image) -> str:
    """An image's identity for this session. Names repeat across linked libraries (``Img`` here
    and ``Img [lib.blend]``), so the datablock's session uid is part of it."""
    return f"{image.name_full}#{image.session_uid}"


#: Colour spaces whose byte values are used as they are (no transfer function to undo).
_LINEAR_BYTE_SPACES = {"Non-Color", "Linear Rec.709", "Linear", "Raw", "Linear CIE-XYZ E"}


def _fingerprint(image: bpy.types.Image) -> tuple:
    # is_dirty: pixels read while an image was edited are read again once it is saved (they are
    # then a file's: ImageData.saved)
    return (tuple(image.size), image.is_float, image.colorspace_settings.name, image.alpha_mode,
            image.filepath_raw, image.source, image.packed_file is not None, image.use_half_precision,
            image.is_dirty)


class _ImageCache:
    """Pixels read from images, kept between renders: reading a 2048 x 2048 image costs ~160 ms
    here, so each image is read once and again only when it changed (a different fingerprint:
    size, colour space, file; unsaved edits; or a depsgraph update naming it, see ``forget``).
    At most ``budget`` bytes are kept, the least recently used dropped first; a file load or
    unregister empties it. Renders, previews and the viewport read scenes on different threads:
    a lock guards it."""

    def __init__(self, budget: int = 1 << 30):
        self._lock = threading.Lock()
        self._entries: dict[str, tuple[tuple, S.ImageData]] = {}  # in order of last use
        self.budget = budget
        self.reads = 0  # images read from Blender since start (tests count them)

    def get(self, key: str, image: bpy.types.Image, warnings: list[str]) -> S.ImageData | None:
        """Image ``key``'s pixels, or a UDIM tile's (``codegen.tile_key``: ``image``'s tile)."""
        fingerprint = _fingerprint(image)
        with self._lock:
            entry = self._entries.pop(key, None)
            if entry is not None and entry[0] == fingerprint and not image.is_dirty:
                self._entries[key] = entry  # most recently used last
                return entry[1]
        if image.source == "TILED" and key != image_key(image):
            data = read_tile(key, image, int(key.rsplit("#", 1)[1]), warnings)
        else:
            data = read_image(key, image, warnings)
        self.reads += 1
        if data is not None:
            with self._lock:
                self._entries[key] = (_fingerprint(image), data)  # after loading: the real size
                while self._nbytes() > self.budget and len(self._entries) > 1:
                    del self._entries[next(iter(self._entries))]
        return data

    def _nbytes(self) -> int:
        return sum(data.pixels.nbytes for _, data in self._entries.values())

    def forget(self, keys) -> None:
        """Drop images ``keys``, and their UDIM tiles (``codegen.tile_key``)."""
        keys = set(keys)
        with self._lock:
            for key in [k for k in self._entries if k in keys or k.rsplit("#", 1)[0] in keys]:
                del self._entries[key]

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()


IMAGES = _ImageCache()
_REVISIONS = itertools.count(1)


def read_image(key: str, image: bpy.types.Image, warnings: list[str]) -> S.ImageData | None:
    """The pixels of ``image`` as the GPU samples them (None, with a warning, when it has none)."""
    count = len(image.pixels)  # loads the image if it is not yet
    width, height = image.size
    if count == 0 or width * height * 4 != count:
        warnings.append(f"Image '{image.name_full}' has no pixels (missing file?): the materials "
                        f"that use it are drawn without it")
        return None
    flat = np.empty(count, np.float32)
    image.pixels.foreach_get(flat)
    pixels = flat.reshape(height, width, 4)
    space = image.colorspace_settings.name
    if image.is_float:
        # the smallest and largest value say it all in two passes without a temporary: a NaN
        # makes both NaN, an infinity one of them infinite (a 1024 x 512 image: ~2 ms, where
        # testing every texel and taking the largest magnitude took ~18)
        low, high = float(flat.min(initial=0.0)), float(flat.max(initial=0.0))
        if not (np.isfinite(low) and np.isfinite(high)):  # NaN or Inf would poison every sum
            bad = ~np.isfinite(pixels)
            warnings.append(f"Image '{image.name_full}' has {int(bad.any(axis=-1).sum())} texels that are "
                            f"not finite numbers: they are read as 0")
            pixels = np.where(bad, 0.0, pixels).astype(np.float32)
            low, high = float(pixels.min(initial=0.0)), float(pixels.max(initial=0.0))
        # half floats top out at 65504: a sun baked into a sky goes beyond, keep those in float
        half = image.use_half_precision and max(high, -low) <= 65504.0
        storage = "HALF" if half else "FLOAT"
        pixels = pixels.astype(np.float16) if half else pixels
    else:
        storage = "SRGB8" if space == "sRGB" else "UNORM8"
        if storage == "UNORM8" and space not in _LINEAR_BYTE_SPACES and not image.colorspace_settings.is_data:
            warnings.append(f"Image '{image.name_full}': colour space {space} is read as linear "
                            f"(Shading Lab converts sRGB, linear and Non-Color images)")
        pixels = np.rint(pixels * 255.0).astype(np.uint8)  # the image's own bytes
    if image.alpha_mode == "NONE":  # "ignore the alpha channel of the file"
        pixels[..., 3] = 255 if pixels.dtype == np.uint8 else 1.0
    saved = not image.is_dirty and (image.source in {"FILE", "SEQUENCE", "MOVIE", "TILED"}
                                    or image.packed_file is not None)
    return S.ImageData(key, pixels, storage, next(_REVISIONS), saved)


def _tile_path(image: bpy.types.Image, number: int) -> str | None:
    """The file of a UDIM image's tile: its path with ``<UDIM>`` as the tile's number or
    ``<UVTILE>`` as ``u<column>_v<row>`` (both counted from 1), as Blender and Cycles name tile
    files; relative paths resolved against the blend file (and the image's library)."""
    path = image.filepath_raw
    column, row = (number - 1001) % 10 + 1, (number - 1001) // 10 + 1
    if "<UDIM>" in path:
        path = path.replace("<UDIM>", str(number))
    elif "<UVTILE>" in path:
        path = path.replace("<UVTILE>", f"u{column}_v{row}")
    else:
        return None
    return bpy.path.abspath(path, library=image.library)


def read_tile(key: str, image: bpy.types.Image, number: int, warnings: list[str]) -> S.ImageData | None:
    """The pixels of a UDIM image's tile ``number`` (``image.pixels`` holds its first tile alone):
    its packed file, else its file on disk, loaded as a temporary image with the image's colour
    space, alpha mode and precision and read as any image (``_read_image``); a generated image's
    first tile from the image itself. None, with a warning, where it has none (the tile is then
    drawn as Blender draws a missing image)."""
    numbers = [tile.number for tile in image.tiles]
    if number not in numbers:
        warnings.append(f"Image '{image.name_full}' has no UDIM tile {number}: it is drawn as a missing "
                        f"image")
        return None
    if image.is_dirty:
        warnings.append(f"Image '{image.name_full}': its UDIM tiles are read from their files; unsaved edits "
                        f"are not drawn")
    packed = next((p for p in image.packed_files if p.tile_number == number), None)
    if packed is None and image.packed_file is None and number == numbers[0] and not image.filepath_raw:
        return read_image(key, image, warnings)  # a generated image: its first tile is its pixels
    path, temporary = (None, None) if packed is not None else (_tile_path(image, number), None)
    try:
        if packed is not None:  # written out to be loaded
            suffix = os.path.splitext(packed.filepath)[1] or ".png"
            with tempfile.NamedTemporaryFile(suffix=suffix, delete=False) as f:
                f.write(packed.packed_file.data)
            path = temporary = f.name
        if path is None or not os.path.isfile(path):
            warnings.append(f"Image '{image.name_full}': UDIM tile {number} has no file ("
                            f"{path or 'no <UDIM> or <UVTILE> in its path'}): it is drawn as a missing image")
            return None
        tile = bpy.data.images.load(path, check_existing=False)
        try:
            tile.name = f"{image.name} tile {number}"
            tile.colorspace_settings.name = image.colorspace_settings.name
            tile.alpha_mode = image.alpha_mode
            tile.use_half_precision = image.use_half_precision
            return read_image(key, tile, warnings)
        finally:
            bpy.data.images.remove(tile)
    except (RuntimeError, OSError) as error:  # an unreadable file, or bpy.data not writable here
        warnings.append(f"Image '{image.name_full}': UDIM tile {number} could not be read ({error}): it is "
                        f"drawn as a missing image")
        return None
    finally:
        if temporary is not None:
            os.unlink(temporary)


def image_updates(depsgraph) -> set[str]:
    """Keys of the images a depsgraph update names (reloaded, repainted, re-generated)."""
    return {image_key(u.id.original) for u in depsgraph.updates if isinstance(u.id, bpy.types.Image)}
