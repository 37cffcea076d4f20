"""Scene and material presets: TOML data files read and validated against the schema in
``presets/README.md``.

Pure Python (``tomllib``, no ``bpy``): ``load_scene_preset`` and ``load_material_presets`` return
frozen dataclasses, or raise ``PresetError`` naming the file, the key path
(``objects[2].material.roughness``) and what was expected. ``scene_builder.py`` turns a
``ScenePreset`` into Blender data.
"""

from __future__ import annotations

import difflib
import json
import math
import re
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import Any

from .snapshot import MODEL_CHOICES, cli_names, f0_from_ior


def _find_presets_dir() -> Path:
    here = Path(__file__).resolve().parents[1]  # the package: addon/ in the source tree
    for candidate in (here / "presets", here.parent / "presets"):
        if candidate.is_dir():
            return candidate
    return here.parent / "presets"


#: The shipped presets (``<repository>/presets``; ``<package>/presets`` when packaged inside).
PRESETS_DIR = _find_presets_dir()
#: Files larger than this are refused before they are parsed.
MAX_FILE_BYTES = 1 << 20
MAX_RESOLUTION = 16384
#: Scene ``model`` values and the ``scene.shading_lab.model`` enum item each selects.
MODELS = cli_names(MODEL_CHOICES)
PRIMITIVES = ("plane", "cube", "uv_sphere", "ico_sphere", "cylinder", "torus")
LIGHT_KINDS = ("point", "spot", "sun", "area")
CAMERA_TYPES = ("perspective", "orthographic")
MODEL_FILE_SUFFIXES = (".blend", ".glb")
#: Material values an ``[[arrays]]`` entry may ramp from one end of the row to the other.
RAMP_KEYS = ("roughness", "metalness", "f0", "ior", "shininess")
MAX_ARRAY_COUNT = 256

_NAME = re.compile(r"^[A-Za-z0-9_-]+$")
_MISSING = object()


class PresetError(ValueError):
    """A preset file that cannot be used; the message names the file, the key and what was
    expected: ``presets/fresnel.toml: objects[1].location: expected 3 numbers, got "up"``."""

    def __init__(self, file: str, key: str, expected: str, got: Any = _MISSING, note: str = ""):
        self.file, self.key, self.expected = str(file), key, expected
        message = f"{file}: {key}: "
        if note:
            message += f"{note}; "
        message += f"expected {expected}"
        if got is not _MISSING:
            message += f", got {_show(got)}"
        super().__init__(message)


def _show(value: Any) -> str:
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, dict):
        text = "a table {" + ", ".join(str(k) for k in value) + "}"
    else:
        try:
            text = json.dumps(value, ensure_ascii=False, default=str)
        except (TypeError, ValueError):
            text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _display(path: Path) -> str:
    """The path as the user will recognise it: relative to the working directory when inside."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except (ValueError, OSError):
        return str(path)


# --- data --------------------------------------------------------------------------------------

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class MaterialPreset:
    """Shading inputs of one material. ``f0`` or ``ior`` gives the dielectric reflectance (neither:
    0.04); ``shininess``/``specular_color`` are explicit Blinn-Phong/Phong values (None: derived
    from roughness and base colour by the renderer)."""

    name: str
    base_color: Vec3 = (0.8, 0.8, 0.8)
    metalness: float = 0.0
    roughness: float = 0.5
    f0: float | None = None
    ior: float | None = None
    shininess: float | None = None
    specular_color: Vec3 | None = None
    description: str = ""
    preset: str = ""  # the library entry this material starts from, "" for an inline material
    #: the Principled BSDF's lobe inputs set (keys of ``PRINCIPLED_INPUTS``, in its order); the
    #: others stay at Blender's defaults
    principled: tuple[tuple[str, float | Vec3], ...] = ()

    @property
    def dielectric_f0(self) -> float:
        if self.f0 is not None:
            return self.f0
        if self.ior is not None:
            return f0_from_ior(self.ior)
        return 0.04

    @property
    def lobes(self) -> frozenset[str]:
        """The lobes (``LOBE_NAMES``) the material turns on: a switch off its default."""
        return frozenset(PRINCIPLED_INPUTS[key].lobe for key, value in self.principled
                         if PRINCIPLED_INPUTS[key].switch and value != PRINCIPLED_INPUTS[key].default)


@dataclass(frozen=True)
class CameraPreset:
    type: str = "perspective"  # or "orthographic"
    location: Vec3 = (0.0, -10.0, 5.0)
    rotation: Vec3 | None = None  # degrees, XYZ Euler
    look_at: Vec3 | None = None
    lens: float = 50.0  # mm, on Blender's 36 mm sensor
    ortho_scale: float = 6.0
    clip_start: float = 0.1
    clip_end: float = 1000.0


@dataclass(frozen=True)
class LightPreset:
    name: str
    kind: str  # point | spot | sun | area
    energy: float  # W (point, spot, area: power) or W/m^2 (sun: strength)
    location: Vec3 = (0.0, 0.0, 5.0)
    rotation: Vec3 | None = None  # degrees; None with no direction/look_at points down (-Z)
    direction: Vec3 | None = None  # the direction the light travels
    look_at: Vec3 | None = None
    color: Vec3 = (1.0, 1.0, 1.0)
    spot_size: float = 45.0  # degrees, full cone angle
    spot_blend: float = 0.15
    size: float = 1.0  # area light edge length, m


@dataclass(frozen=True)
class ObjectPreset:
    name: str
    primitive: str | None = None
    file: Path | None = None  # resolved, inside the presets folder
    object_name: str | None = None  # the object to take from ``file``
    location: Vec3 = (0.0, 0.0, 0.0)
    rotation: Vec3 = (0.0, 0.0, 0.0)  # degrees, XYZ Euler
    scale: Vec3 = (1.0, 1.0, 1.0)
    size: float = 2.0  # plane, cube: edge length
    radius: float = 1.0  # spheres, cylinder; torus: major radius
    minor_radius: float = 0.25  # torus
    depth: float = 2.0  # cylinder height
    segments: int = 32  # uv_sphere (rings = segments / 2), cylinder, torus
    subdivisions: int = 3  # ico_sphere
    smooth: bool = False
    material: MaterialPreset | None = None

    def triangle_estimate(self) -> int:
        """Triangles the primitive will have (0 for a file object)."""
        s = self.segments
        return {
            "plane": 2,
            "cube": 12,
            "uv_sphere": s * (max(s // 2, 2) - 1) * 2,
            "ico_sphere": 20 * 4 ** self.subdivisions,
            "cylinder": 4 * s - 4,
            "torus": 2 * s * max(s // 2, 3),
        }.get(self.primitive or "", 0)


#: Blender's bundled worlds (its ``datafiles/studiolights/world`` HDRIs, CC0): referenced by name,
#: never copied into the presets.
BUNDLED_WORLDS = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")


@dataclass(frozen=True)
class WorldPreset:
    """A world: a colour, or one of Blender's bundled HDRIs times a strength, turned about Z."""

    color: Vec3 = (0.0, 0.0, 0.0)
    image: str | None = None  # one of BUNDLED_WORLDS
    strength: float = 1.0
    rotation: float = 0.0  # degrees about the vertical axis


@dataclass(frozen=True)
class LightingVariant:
    name: str
    lights: tuple[LightPreset, ...]
    description: str = ""
    world_color: Vec3 | None = None
    world: WorldPreset | None = None  # a world image for this variant


@dataclass(frozen=True)
class ScenePreset:
    name: str
    description: str
    path: Path
    camera: CameraPreset
    lights: tuple[LightPreset, ...]
    objects: tuple[ObjectPreset, ...]
    variants: tuple[LightingVariant, ...] = ()
    resolution: tuple[int, int] = (960, 540)
    model: str = "PBR"  # the scene.shading_lab.model enum item
    ambient: float = 0.2
    ambient_source: str = "CONSTANT"  # the scene.shading_lab.ambient_source enum item
    world_color: Vec3 = (0.0, 0.0, 0.0)
    world: WorldPreset | None = None  # a world image (else the world is world_color)
    lobe: str | None = None  # the Principled lobe the scene shows (``LOBE_NAMES``), for the benchmarks

    @property
    def variant_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.variants)

    def lighting(self, variant: str | None = None) -> tuple[tuple[LightPreset, ...], WorldPreset]:
        """The lights and world of ``variant``; None gives the top-level ``[[lights]]`` and
        world, or the first variant when the file has neither lights nor a world image."""
        if variant is None:
            if self.lights or self.world is not None or not self.variants:
                return self.lights, self.world or WorldPreset(self.world_color)
            variant = self.variants[0].name
        for v in self.variants:
            if v.name == variant:
                if v.world is not None:
                    return v.lights, v.world
                if v.world_color is not None:
                    return v.lights, WorldPreset(v.world_color)
                return v.lights, self.world or WorldPreset(self.world_color)
        names = ", ".join(self.variant_names) or "(none)"
        raise PresetError(_display(self.path), "variants", f"one of {names}", got=variant,
                          note="no such lighting variant")

    def triangle_estimate(self) -> int:
        return sum(o.triangle_estimate() for o in self.objects)


# --- reading -----------------------------------------------------------------------------------

def _read_toml(path: Path) -> dict:
    shown = _display(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise PresetError(shown, "(file)", "an existing, readable preset file",
                          note=exc.strerror or "cannot read") from None
    if not path.is_file():
        raise PresetError(shown, "(file)", "a regular file")
    if size > MAX_FILE_BYTES:
        raise PresetError(shown, "(file size)", f"at most {MAX_FILE_BYTES} bytes (1 MiB)", got=size)
    with open(path, "rb") as f:
        raw = f.read(MAX_FILE_BYTES + 1)
    if len(raw) > MAX_FILE_BYTES:  # grew since stat
        raise PresetError(shown, "(file size)", f"at most {MAX_FILE_BYTES} bytes (1 MiB)", got=len(raw))
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise PresetError(shown, "(encoding)", "UTF-8 text", note=f"byte {exc.start} is not UTF-8") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        m = re.search(r"at line (\d+)", message)
        line = int(m.group(1)) if m else None
        key = _key_at_line(text, line) if line else None
        where = f"line {line}" if line else "end of file"
        if key:
            where += f" ({key})"
        raise PresetError(shown, where, "valid TOML (key = value, [table], [[array of tables]])",
                          note=f"TOML syntax error: {message}") from None


def _key_at_line(text: str, line: int) -> str | None:
    """Best-effort key path of a line that failed to parse: the enclosing [table] or
    [[array]] header (with its index) and the key before ``=``."""
    lines = text.splitlines()
    section, counts = "", {}
    for raw in lines[: max(line - 1, 0)]:
        s = raw.strip()
        m = re.match(r"^\[\[\s*([^\]]+?)\s*\]\]", s)
        if m:
            name = m.group(1)
            counts[name] = counts.get(name, -1) + 1
            section = f"{name}[{counts[name]}]"
            continue
        m = re.match(r"^\[\s*([^\]]+?)\s*\]", s)
        if m:
            section = m.group(1)
    current = lines[line - 1] if 0 < line <= len(lines) else ""
    m = re.match(r'^\s*([A-Za-z0-9_."-]+)\s*=', current)
    key = m.group(1).strip('"') if m else None
    if key and section:
        return f"{section}.{key}"
    return key or section or None


class _Reader:
    """Typed access to parsed TOML with errors that name the file and the key path."""

    def __init__(self, path: Path):
        self.path = path
        self.shown = _display(path)

    def fail(self, key: str, expected: str, got: Any = _MISSING, note: str = ""):
        raise PresetError(self.shown, key, expected, got=got, note=note)

    @staticmethod
    def join(path: str, key: str) -> str:
        return f"{path}.{key}" if path else key

    def table(self, value: Any, path: str) -> dict:
        if not isinstance(value, dict):
            self.fail(path, f"a table ([{path}] or {{ key = value }})", got=value)
        return value

    def table_list(self, value: Any, path: str) -> list[dict]:
        if not isinstance(value, list):
            self.fail(path, f"an array of tables ([[{path}]])", got=value)
        for i, item in enumerate(value):
            self.table(item, f"{path}[{i}]")
        return value

    def keys(self, tbl: dict, path: str, allowed, elsewhere: dict[str, str] | None = None):
        """Refuse keys not in ``allowed``; ``elsewhere`` maps keys that are valid in other
        contexts (another light kind, say) to why they do not apply here."""
        allowed = sorted(allowed)
        for key in tbl:
            if key in allowed:
                continue
            if elsewhere and key in elsewhere:
                self.fail(self.join(path, key), "one of: " + ", ".join(allowed), note=elsewhere[key])
            close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
            note = "unknown key" + (f' (did you mean "{close[0]}"?)' if close else "")
            self.fail(self.join(path, key), "one of: " + ", ".join(allowed), note=note)

    def get(self, tbl: dict, key: str, path: str, required: bool):
        if key not in tbl:
            if required:
                self.fail(self.join(path, key), "this key to be set", note="missing")
            return _MISSING
        return tbl[key]

    def number(self, tbl, key, path, default=_MISSING, lo=None, hi=None, lo_open=False):
        value = self.get(tbl, key, path, default is _MISSING)
        if value is _MISSING:
            return default
        return self.check_number(value, self.join(path, key), lo, hi, lo_open)

    def check_number(self, value, where, lo=None, hi=None, lo_open=False) -> float:
        expected = _range_text("a number", lo, hi, lo_open)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(where, expected, got=value)
        if (lo is not None and (value <= lo if lo_open else value < lo)) or (hi is not None and value > hi):
            self.fail(where, expected, got=value)
        return float(value)

    def integer(self, tbl, key, path, default=_MISSING, lo=None, hi=None) -> int:
        value = self.get(tbl, key, path, default is _MISSING)
        if value is _MISSING:
            return default
        expected = _range_text("an integer", lo, hi)
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(self.join(path, key), expected, got=value)
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            self.fail(self.join(path, key), expected, got=value)
        return value

    def string(self, tbl, key, path, default=_MISSING, choices=None) -> str:
        value = self.get(tbl, key, path, default is _MISSING)
        if value is _MISSING:
            return default
        if choices is not None:
            if value not in choices:
                close = difflib.get_close_matches(str(value).lower(), choices, n=1, cutoff=0.6)
                note = f'did you mean "{close[0]}"?' if isinstance(value, str) and close else ""
                self.fail(self.join(path, key), "one of " + ", ".join(f'"{c}"' for c in choices),
                          got=value, note=note)
            return value
        if not isinstance(value, str):
            self.fail(self.join(path, key), "a string", got=value)
        return value

    def boolean(self, tbl, key, path, default=_MISSING) -> bool:
        value = self.get(tbl, key, path, default is _MISSING)
        if value is _MISSING:
            return default
        if not isinstance(value, bool):
            self.fail(self.join(path, key), "true or false", got=value)
        return value

    def vec3(self, tbl, key, path, default=_MISSING, lo=None, hi=None, what="3 numbers") -> Vec3:
        value = self.get(tbl, key, path, default is _MISSING)
        if value is _MISSING:
            return default
        where = self.join(path, key)
        expected = what if lo is None and hi is None else _range_text(what, lo, hi)
        if not isinstance(value, list) or len(value) != 3:
            self.fail(where, expected, got=value)
        for x in value:
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                self.fail(where, expected, got=value)
            if (lo is not None and x < lo) or (hi is not None and x > hi):
                self.fail(where, expected, got=value)
        return (float(value[0]), float(value[1]), float(value[2]))

    def color(self, tbl, key, path, default=_MISSING, hi: float | None = 1.0) -> Vec3:
        return self.vec3(tbl, key, path, default, lo=0.0, hi=hi, what="3 numbers [r, g, b] (linear)")

    def scale(self, tbl, key, path) -> Vec3:
        value = tbl.get(key, _MISSING)
        if value is _MISSING:
            return (1.0, 1.0, 1.0)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            s = self.check_number(value, self.join(path, key), lo=0.0, lo_open=True)
            return (s, s, s)
        v = self.vec3(tbl, key, path, what="a number or 3 numbers")
        if min(v) <= 0.0:
            self.fail(self.join(path, key), "a number or 3 numbers, each > 0", got=value)
        return v

    def model_file(self, value: Any, where: str) -> Path:
        """A ``.blend``/``.glb`` path relative to the preset's folder that stays inside it."""
        root = self.path.parent.resolve()
        kinds = "/".join(MODEL_FILE_SUFFIXES)
        expected = f"a relative path to a {kinds} file inside the presets folder {root}"
        if not isinstance(value, str) or not value.strip():
            self.fail(where, expected, got=value)
        if (PurePosixPath(value).is_absolute() or PureWindowsPath(value).is_absolute()
                or PureWindowsPath(value).drive or value.startswith(("/", "\\", "~"))):
            self.fail(where, expected, got=value, note="absolute paths are refused")
        parts = re.split(r"[\\/]+", value)
        if ".." in parts:
            self.fail(where, expected, got=value, note='".." leaves the presets folder')
        full = (root / Path(*[p for p in parts if p not in ("", ".")])).resolve()
        if not full.is_relative_to(root):
            self.fail(where, expected, got=value,
                      note=f"resolves to {full}, outside the presets folder (a symbolic link?)")
        if full.suffix.lower() not in MODEL_FILE_SUFFIXES:
            self.fail(where, expected, got=value, note="unsupported file type")
        if not full.is_file():
            self.fail(where, expected, got=value, note="no such file")
        return full


def _fmt(x: float) -> str:
    return f"{x:g}"


def _range_text(what: str, lo=None, hi=None, lo_open=False) -> str:
    if lo is not None and hi is not None:
        return f"{what} in {'(' if lo_open else '['}{_fmt(lo)}, {_fmt(hi)}]"
    if lo is not None:
        return f"{what} {'>' if lo_open else '>='} {_fmt(lo)}"
    if hi is not None:
        return f"{what} <= {_fmt(hi)}"
    return what


# --- materials ---------------------------------------------------------------------------------

_MATERIAL_RANGES = {  # key: (lo, hi)
    "metalness": (0.0, 1.0),
    "roughness": (0.0, 1.0),
    "f0": (0.0, 1.0),
    "ior": (1.0, 10.0),
    "shininess": (0.0, 1e6),
}
_MATERIAL_VALUE_KEYS = ("base_color", "metalness", "roughness", "f0", "ior", "shininess", "specular_color")


@dataclass(frozen=True)
class PrincipledInput:
    """One of the Principled BSDF's lobe inputs a material preset may set: the input it sets, the
    lobe it belongs to, Blender's default and the range the preset may give (a colour: each
    channel). A lobe is on where one of its ``switch`` inputs is off its default (Blender's
    defaults turn every lobe off)."""

    socket: str
    lobe: str
    default: float | Vec3
    lo: float
    hi: float | None
    switch: bool = False

    @property
    def color(self) -> bool:
        return isinstance(self.default, tuple)


_WHITE = (1.0, 1.0, 1.0)
#: The Principled BSDF's inputs beyond the base a material preset may set (Blender 4.2 to 5.0 have
#: them all), by preset key; their ranges are the node's. A lobe joins the presets by its rows here.
PRINCIPLED_INPUTS = {
    "specular_tint": PrincipledInput("Specular Tint", "SPECULAR_TINT", _WHITE, 0.0, 1.0, switch=True),
    "coat_weight": PrincipledInput("Coat Weight", "COAT", 0.0, 0.0, 1.0, switch=True),
    "coat_roughness": PrincipledInput("Coat Roughness", "COAT", 0.03, 0.0, 1.0),
    "coat_ior": PrincipledInput("Coat IOR", "COAT", 1.5, 1.0, 4.0),
    "coat_tint": PrincipledInput("Coat Tint", "COAT", _WHITE, 0.0, 1.0),
    "sheen_weight": PrincipledInput("Sheen Weight", "SHEEN", 0.0, 0.0, 1.0, switch=True),
    "sheen_roughness": PrincipledInput("Sheen Roughness", "SHEEN", 0.5, 0.0, 1.0),
    "sheen_tint": PrincipledInput("Sheen Tint", "SHEEN", _WHITE, 0.0, 1.0),
    "anisotropic": PrincipledInput("Anisotropic", "ANISOTROPY", 0.0, 0.0, 1.0, switch=True),
    "anisotropic_rotation": PrincipledInput("Anisotropic Rotation", "ANISOTROPY", 0.0, 0.0, 1.0),
    "thin_film_thickness": PrincipledInput("Thin Film Thickness", "THIN_FILM", 0.0, 0.0, 1e5, switch=True),
    "thin_film_ior": PrincipledInput("Thin Film IOR", "THIN_FILM", 1.33, 1.0, 1000.0),
    "transmission_weight": PrincipledInput("Transmission Weight", "TRANSMISSION", 0.0, 0.0, 1.0,
                                           switch=True),
    "subsurface_weight": PrincipledInput("Subsurface Weight", "SUBSURFACE", 0.0, 0.0, 1.0, switch=True),
    "subsurface_radius": PrincipledInput("Subsurface Radius", "SUBSURFACE", (1.0, 0.2, 0.1), 0.0, None),
    "subsurface_scale": PrincipledInput("Subsurface Scale", "SUBSURFACE", 0.05, 0.0, None),
    "subsurface_ior": PrincipledInput("Subsurface IOR", "SUBSURFACE", 1.4, 1.01, 3.8),
    "subsurface_anisotropy": PrincipledInput("Subsurface Anisotropy", "SUBSURFACE", 0.0, 0.0, 1.0),
}
#: The lobes the presets can turn on, in ``PRINCIPLED_INPUTS``' order
LOBE_NAMES = tuple(dict.fromkeys(spec.lobe for spec in PRINCIPLED_INPUTS.values()))


def lobe_off(lobe: str) -> dict[str, float | Vec3]:
    """The Principled inputs (preset keys) that turn ``lobe`` off: its switches at their defaults."""
    return {key: spec.default for key, spec in PRINCIPLED_INPUTS.items() if spec.lobe == lobe and spec.switch}
_LIBRARY_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


def _material_values(r: _Reader, tbl: dict, path: str) -> dict:
    """The material keys present in ``tbl``, validated (a dict of MaterialPreset fields)."""
    out: dict = {}
    if "f0" in tbl and "ior" in tbl:
        r.fail(r.join(path, "ior"), "either f0 or ior, not both", got=tbl["ior"])
    if "base_color" in tbl:
        out["base_color"] = r.color(tbl, "base_color", path)
    if "specular_color" in tbl:
        out["specular_color"] = r.color(tbl, "specular_color", path, hi=None)
    for key, (lo, hi) in _MATERIAL_RANGES.items():
        if key in tbl:
            out[key] = r.number(tbl, key, path, lo=lo, hi=hi)
    if "f0" in out:
        out["ior"] = None
    if "ior" in out and out["ior"] is not None:
        out["f0"] = None
    principled = {}
    for key, spec in PRINCIPLED_INPUTS.items():
        if key in tbl:
            principled[key] = (r.color(tbl, key, path, hi=spec.hi) if spec.color
                               else r.number(tbl, key, path, lo=spec.lo, hi=spec.hi))
    if principled:
        out["principled"] = principled
    return out


def _principled(*tables: dict) -> tuple:
    """Principled inputs of ``tables`` (later ones win) in ``PRINCIPLED_INPUTS``' order."""
    merged = {k: v for t in tables for k, v in t.items()}
    return tuple((key, merged[key]) for key in PRINCIPLED_INPUTS if key in merged)


def load_material_presets(path: str | Path | None = None) -> dict[str, MaterialPreset]:
    """The material library ``path`` (default ``presets/materials.toml``): one ``[name]`` table per
    material with ``base_color``, ``metalness``, ``roughness`` (required) and optionally ``f0`` or
    ``ior``, ``shininess``, ``specular_color``, ``description``."""
    path = Path(path) if path is not None else PRESETS_DIR / "materials.toml"
    r = _Reader(path)
    data = _read_toml(path)
    out: dict[str, MaterialPreset] = {}
    for name, tbl in data.items():
        if not _LIBRARY_NAME.match(name):
            r.fail(name, "a material name of lower-case letters, digits and _", got=name)
        r.table(tbl, name)
        r.keys(tbl, name, {"description", *_MATERIAL_VALUE_KEYS, *PRINCIPLED_INPUTS})
        for key in ("base_color", "metalness", "roughness"):
            r.get(tbl, key, name, required=True)
        values = _material_values(r, tbl, name)
        values["principled"] = _principled(values.get("principled", {}))
        out[name] = MaterialPreset(name=name, description=r.string(tbl, "description", name, ""),
                                   preset=name, **values)
    if not out:
        r.fail("(file)", "at least one [material] table")
    return out


# --- scenes ------------------------------------------------------------------------------------

def _scene_path(path_or_name: str | Path) -> Path:
    if isinstance(path_or_name, Path):
        return path_or_name
    text = str(path_or_name)
    if _NAME.match(text):
        path = PRESETS_DIR / f"{text}.toml"
        if not path.is_file():
            names = scene_preset_names()
            close = difflib.get_close_matches(text, names, n=1, cutoff=0.6)
            hint = f' (did you mean "{close[0]}"?)' if close else ""
            raise PresetError(_display(PRESETS_DIR), "(name)", "one of " + ", ".join(names), got=text,
                              note="no such scene preset" + hint)
        return path
    return Path(text)


def scene_preset_names(directory: Path | None = None) -> list[str]:
    """Names of the scene presets in ``directory`` (default: the shipped ones)."""
    directory = directory or PRESETS_DIR
    return sorted(p.stem for p in directory.glob("*.toml") if p.stem != "materials")


class _Library:
    """The material library a scene refers to, read on first use."""

    def __init__(self, r: _Reader, where: str, relative: str):
        self.r, self.where, self.relative = r, where, relative
        self._presets: dict[str, MaterialPreset] | None = None

    def get(self, name: Any, where: str) -> MaterialPreset:
        if self._presets is None:
            path = self._library_path()
            self._presets = load_material_presets(path)
        if not isinstance(name, str) or name not in self._presets:
            names = sorted(self._presets)
            close = difflib.get_close_matches(str(name), names, n=1, cutoff=0.6)
            self.r.fail(where, "a material preset: one of " + ", ".join(names), got=name,
                        note=f'did you mean "{close[0]}"?' if close else "")
        return self._presets[name]

    def _library_path(self) -> Path:
        r = self.r
        root = r.path.parent.resolve()
        text = self.relative
        parts = re.split(r"[\\/]+", text)
        expected = "a relative path to a .toml file inside the presets folder"
        if PurePosixPath(text).is_absolute() or PureWindowsPath(text).drive or ".." in parts:
            r.fail(self.where, expected, got=text)
        full = (root / Path(*[p for p in parts if p not in ("", ".")])).resolve()
        if not full.is_relative_to(root) or full.suffix != ".toml":
            r.fail(self.where, expected, got=text)
        if not full.is_file():
            r.fail(self.where, expected, got=text, note="no such file")
        return full


_OBJECT_COMMON = {"name", "primitive", "file", "object", "location", "rotation", "scale", "smooth",
                  "material"}
_OBJECT_PARAMS = {
    "plane": {"size"},
    "cube": {"size"},
    "uv_sphere": {"radius", "segments"},
    "ico_sphere": {"radius", "subdivisions"},
    "cylinder": {"radius", "depth", "segments"},
    "torus": {"radius", "minor_radius", "segments"},
}
_ALL_OBJECT_PARAMS = set().union(*_OBJECT_PARAMS.values())


def _label(values: dict) -> str:
    """A short name suffix for changed material values: ``roughness 0.25 f0 0.04``."""
    parts = []
    for key, v in values.items():
        if isinstance(v, float):
            parts.append(f"{key} {v:.3g}")
        elif isinstance(v, tuple):
            parts.append(key)
    return " ".join(parts)


def _material(r: _Reader, value: Any, path: str, library: _Library, default_name: str) -> MaterialPreset:
    tbl = r.table(value, path)
    r.keys(tbl, path, {"preset", *_MATERIAL_VALUE_KEYS, *PRINCIPLED_INPUTS})
    values = _material_values(r, tbl, path)
    principled = values.get("principled", {})
    if "preset" in tbl:
        base = library.get(tbl["preset"], r.join(path, "preset"))
        if not values:
            return base
        label = _label({**{k: v for k, v in values.items() if k != "principled"}, **principled})
        values["principled"] = _principled(dict(base.principled), principled)
        return replace(base, name=f"{base.name} {label}", **values)
    values["principled"] = _principled(principled)
    return MaterialPreset(name=default_name, **values)


def _object(r: _Reader, value: Any, path: str, library: _Library, index: int) -> ObjectPreset:
    tbl = r.table(value, path)
    has_primitive, has_file = "primitive" in tbl, "file" in tbl
    if has_primitive == has_file:
        r.fail(r.join(path, "primitive"),
               f"exactly one of primitive = {' | '.join(PRIMITIVES)} or file = \"path.blend|.glb\"",
               note="both given" if has_primitive else "neither given")
    fields: dict = {}
    if has_primitive:
        primitive = r.string(tbl, "primitive", path, choices=PRIMITIVES)
        allowed = (_OBJECT_COMMON - {"file", "object"}) | _OBJECT_PARAMS[primitive]
        elsewhere = {k: f"not used by a {primitive}" for k in _ALL_OBJECT_PARAMS | {"file", "object"}}
        r.keys(tbl, path, allowed, elsewhere)
        fields["primitive"] = primitive
        default_name = primitive.replace("_", " ").title()
        params = _OBJECT_PARAMS[primitive]
        if "size" in params:
            fields["size"] = r.number(tbl, "size", path, 2.0, lo=0.0, lo_open=True)
        if "radius" in params:
            fields["radius"] = r.number(tbl, "radius", path, 1.0, lo=0.0, lo_open=True)
        if "depth" in params:
            fields["depth"] = r.number(tbl, "depth", path, 2.0, lo=0.0, lo_open=True)
        if "minor_radius" in params:
            fields["minor_radius"] = r.number(tbl, "minor_radius", path, 0.25, lo=0.0, lo_open=True)
        if "segments" in params:
            fields["segments"] = r.integer(tbl, "segments", path, 48 if primitive == "torus" else 32,
                                           lo=3, hi=512)
        if "subdivisions" in params:
            fields["subdivisions"] = r.integer(tbl, "subdivisions", path, 3, lo=1, hi=6)
        smooth_default = primitive not in ("plane", "cube")
    else:
        r.keys(tbl, path, _OBJECT_COMMON - {"primitive", "smooth"},
               {**{k: "not used by a file object" for k in _ALL_OBJECT_PARAMS},
                "smooth": "a file object keeps its own shading"})
        fields["file"] = r.model_file(tbl["file"], r.join(path, "file"))
        blend = fields["file"].suffix.lower() == ".blend"
        fields["object_name"] = r.string(tbl, "object", path, _MISSING if blend else None)
        default_name = fields["object_name"] or fields["file"].stem
        smooth_default = False
    name = r.string(tbl, "name", path, f"{default_name} {index + 1}")
    fields["smooth"] = r.boolean(tbl, "smooth", path, smooth_default)
    fields["location"] = r.vec3(tbl, "location", path, (0.0, 0.0, 0.0))
    fields["rotation"] = r.vec3(tbl, "rotation", path, (0.0, 0.0, 0.0), what="3 numbers (degrees, XYZ Euler)")
    fields["scale"] = r.scale(tbl, "scale", path)
    if "material" in tbl:
        fields["material"] = _material(r, tbl["material"], r.join(path, "material"), library, name)
    return ObjectPreset(name=name, **fields)


def _arrays(r: _Reader, value: Any, library: _Library, first_index: int) -> list[ObjectPreset]:
    out: list[ObjectPreset] = []
    for i, tbl in enumerate(r.table_list(value, "arrays")):
        path = f"arrays[{i}]"
        r.keys(tbl, path, {"count", "step", "ramp", "object"})
        count = r.integer(tbl, "count", path, lo=1, hi=MAX_ARRAY_COUNT)
        step = r.vec3(tbl, "step", path, (1.0, 0.0, 0.0))
        template = _object(r, r.get(tbl, "object", path, True), f"{path}.object", library,
                           first_index + len(out))
        ramps: dict[str, tuple[float, float]] = {}
        if "ramp" in tbl:
            ramp = r.table(tbl["ramp"], f"{path}.ramp")
            r.keys(ramp, f"{path}.ramp", RAMP_KEYS)
            if template.material is None:
                r.fail(f"{path}.ramp", f"a material on {path}.object to ramp", note="the object has none")
            for key, ends in ramp.items():
                lo, hi = _MATERIAL_RANGES[key]
                where = f"{path}.ramp.{key}"
                if not isinstance(ends, list) or len(ends) != 2:
                    r.fail(where, f"[from, to]: 2 numbers in [{_fmt(lo)}, {_fmt(hi)}]", got=ends)
                ramps[key] = (r.check_number(ends[0], where, lo, hi), r.check_number(ends[1], where, lo, hi))
            if "f0" in ramps and "ior" in ramps:
                r.fail(f"{path}.ramp.ior", "either f0 or ior, not both", got=ramp["ior"])
        base_name = tbl["object"].get("name") or template.name.rsplit(" ", 1)[0]
        for k in range(count):
            t = k / (count - 1) if count > 1 else 0.0
            location = tuple(template.location[j] + k * step[j] for j in range(3))
            material = template.material
            if ramps:
                values = {key: a + (b - a) * t for key, (a, b) in ramps.items()}
                if "f0" in ramps:
                    values["ior"] = None
                if "ior" in ramps:
                    values["f0"] = None
                material = replace(material, name=f"{material.name} {_label(values)}", **values)
            out.append(replace(template, name=f"{base_name} {k + 1}", location=location, material=material))
    return out


_LIGHT_COMMON = {"name", "kind", "location", "rotation", "direction", "look_at", "color"}
_LIGHT_PARAMS = {
    "point": {"power"},
    "spot": {"power", "spot_size", "spot_blend"},
    "sun": {"strength"},
    "area": {"power", "size"},
}
_LIGHT_WHY = {
    "power": "sun lights take strength (W/m^2), not power",
    "strength": "point, spot and area lights take power (W), not strength",
    "spot_size": "only spot lights have a cone",
    "spot_blend": "only spot lights have a cone",
    "size": "only area lights have a size (point and spot lights are points)",
}


def _light(r: _Reader, value: Any, path: str, index: int) -> LightPreset:
    tbl = r.table(value, path)
    kind = r.string(tbl, "kind", path, choices=LIGHT_KINDS)
    r.keys(tbl, path, _LIGHT_COMMON | _LIGHT_PARAMS[kind], _LIGHT_WHY)
    fields: dict = {"kind": kind}
    if kind == "sun":
        fields["energy"] = r.number(tbl, "strength", path, lo=0.0)
        fields["location"] = r.vec3(tbl, "location", path, (0.0, 0.0, 10.0))
    else:
        fields["energy"] = r.number(tbl, "power", path, lo=0.0)
        fields["location"] = r.vec3(tbl, "location", path)
    given = [k for k in ("rotation", "direction", "look_at") if k in tbl]
    if len(given) > 1:
        r.fail(r.join(path, given[1]), "one of rotation, direction or look_at",
               note=f"{given[0]} is also set")
    if "rotation" in tbl:
        fields["rotation"] = r.vec3(tbl, "rotation", path, what="3 numbers (degrees, XYZ Euler)")
    if "direction" in tbl:
        d = r.vec3(tbl, "direction", path, what="3 numbers (the direction the light travels)")
        if not any(d):
            r.fail(r.join(path, "direction"), "a non-zero vector", got=list(d))
        fields["direction"] = d
    if "look_at" in tbl:
        target = r.vec3(tbl, "look_at", path, what="3 numbers (a point)")
        if target == fields["location"]:
            r.fail(r.join(path, "look_at"), "a point other than the light's location", got=list(target))
        fields["look_at"] = target
    fields["color"] = r.color(tbl, "color", path, (1.0, 1.0, 1.0), hi=None)
    if kind == "spot":
        fields["spot_size"] = r.number(tbl, "spot_size", path, 45.0, lo=1.0, hi=180.0)
        fields["spot_blend"] = r.number(tbl, "spot_blend", path, 0.15, lo=0.0, hi=1.0)
    if kind == "area":
        fields["size"] = r.number(tbl, "size", path, 1.0, lo=0.0, lo_open=True)
    name = r.string(tbl, "name", path, f"{kind.title()} {index + 1}")
    return LightPreset(name=name, **fields)


def _lights(r: _Reader, value: Any, path: str) -> tuple[LightPreset, ...]:
    return tuple(_light(r, tbl, f"{path}[{i}]", i) for i, tbl in enumerate(r.table_list(value, path)))


def _camera(r: _Reader, value: Any) -> CameraPreset:
    tbl = r.table(value, "camera")
    kind = r.string(tbl, "type", "camera", "perspective", choices=CAMERA_TYPES)
    common = {"type", "location", "rotation", "look_at", "clip_start", "clip_end"}
    specific = {"lens"} if kind == "perspective" else {"ortho_scale"}
    r.keys(tbl, "camera", common | specific,
           {"lens": "an orthographic camera has ortho_scale, not lens",
            "ortho_scale": "a perspective camera has lens, not ortho_scale"})
    fields: dict = {"type": kind, "location": r.vec3(tbl, "location", "camera")}
    if ("rotation" in tbl) == ("look_at" in tbl):
        r.fail("camera.rotation", "exactly one of rotation (degrees) or look_at (a point)",
               note="both given" if "rotation" in tbl else "neither given")
    if "rotation" in tbl:
        fields["rotation"] = r.vec3(tbl, "rotation", "camera", what="3 numbers (degrees, XYZ Euler)")
    else:
        target = r.vec3(tbl, "look_at", "camera", what="3 numbers (a point)")
        if target == fields["location"]:
            r.fail("camera.look_at", "a point other than camera.location", got=list(target))
        fields["look_at"] = target
    if kind == "perspective":
        fields["lens"] = r.number(tbl, "lens", "camera", 50.0, lo=1.0, hi=5000.0)
    else:
        fields["ortho_scale"] = r.number(tbl, "ortho_scale", "camera", 6.0, lo=0.0, lo_open=True)
    fields["clip_start"] = r.number(tbl, "clip_start", "camera", 0.1, lo=0.0, lo_open=True)
    fields["clip_end"] = r.number(tbl, "clip_end", "camera", 1000.0, lo=fields["clip_start"], lo_open=True)
    return CameraPreset(**fields)


def load_scene_preset(path_or_name: str | Path) -> ScenePreset:
    """A scene preset: a shipped name (``"fresnel"``) or a path to a ``.toml`` file. Objects may
    refer to the material library (``materials.toml`` beside the file unless ``[scene] materials``
    names another) and to ``.blend``/``.glb`` files inside the file's folder."""
    path = _scene_path(path_or_name)
    data = _read_toml(path)
    r = _Reader(path)
    r.keys(data, "", {"scene", "camera", "lights", "objects", "arrays", "variants"})
    scene = r.table(r.get(data, "scene", "", True), "scene")
    r.keys(scene, "scene", {"name", "description", "resolution", "model", "ambient", "ambient_source",
                            "world_color",
                            "world_image", "world_strength", "world_rotation", "materials", "lobe"})
    name = r.string(scene, "name", "scene")
    description = r.string(scene, "description", "scene")
    resolution = scene.get("resolution", [960, 540])
    expected = f"[width, height]: 2 integers in [1, {MAX_RESOLUTION}]"
    if (not isinstance(resolution, list) or len(resolution) != 2
            or any(isinstance(x, bool) or not isinstance(x, int) or not 1 <= x <= MAX_RESOLUTION
                   for x in resolution)):
        r.fail("scene.resolution", expected, got=resolution)
    model = MODELS[r.string(scene, "model", "scene", "pbr", choices=tuple(MODELS))]
    ambient = r.number(scene, "ambient", "scene", 0.2, lo=0.0)
    ambient_source = r.string(scene, "ambient_source", "scene", "constant",
                              choices=("constant", "world")).upper()
    world_color = r.color(scene, "world_color", "scene", (0.0, 0.0, 0.0), hi=None)
    world = _world_image(r, scene, "scene")
    materials = r.string(scene, "materials", "scene", "materials.toml")
    library = _Library(r, "scene.materials", materials)

    camera = _camera(r, r.get(data, "camera", "", True))
    lights = _lights(r, data["lights"], "lights") if "lights" in data else ()
    variants: list[LightingVariant] = []
    for i, tbl in enumerate(r.table_list(data.get("variants", []), "variants")):
        path_i = f"variants[{i}]"
        r.keys(tbl, path_i, {"name", "description", "lights", "world_color", "world_image",
                             "world_strength", "world_rotation"})
        vname = r.string(tbl, "name", path_i)
        if vname in (v.name for v in variants):
            r.fail(r.join(path_i, "name"), "a name no other variant has", got=vname)
        vworld = _world_image(r, tbl, path_i)
        vlights = _lights(r, tbl["lights"], f"{path_i}.lights") if "lights" in tbl else ()
        if not vlights and vworld is None:
            r.fail(f"{path_i}.lights", "at least one [[variants.lights]] table, or a world_image", got=[])
        variants.append(LightingVariant(
            name=vname, lights=vlights, description=r.string(tbl, "description", path_i, ""),
            world_color=r.color(tbl, "world_color", path_i, None, hi=None), world=vworld))
    if not lights and not variants and world is None:
        r.fail("lights", "at least one [[lights]] table (or [[variants]] with lights, or a world_image)",
               note="the scene is unlit")

    objects = [_object(r, tbl, f"objects[{i}]", library, i)
               for i, tbl in enumerate(r.table_list(data.get("objects", []), "objects"))]
    if "arrays" in data:
        objects += _arrays(r, data["arrays"], library, len(objects))
    if not objects:
        r.fail("objects", "at least one [[objects]] or [[arrays]] table", note="the scene is empty")
    lobe = None
    if "lobe" in scene:
        lobe = r.string(scene, "lobe", "scene", choices=tuple(n.lower() for n in LOBE_NAMES)).upper()
        if not any(o.material is not None and lobe in o.material.lobes for o in objects):
            r.fail("scene.lobe", f"a material with {lobe.lower()} on (one of {lobe.lower()}'s inputs "
                   f"{', '.join(lobe_off(lobe))} off its default)", got=scene["lobe"],
                   note="no object's material has it")
    return ScenePreset(
        name=name, description=description, path=path.resolve(), camera=camera, lights=lights,
        objects=tuple(objects), variants=tuple(variants), resolution=(resolution[0], resolution[1]),
        model=model, ambient=ambient, ambient_source=ambient_source, world_color=world_color, world=world,
        lobe=lobe)


def _world_image(r, tbl: dict, path: str) -> WorldPreset | None:
    """``world_image`` (a bundled world's name), ``world_strength`` and ``world_rotation``."""
    if "world_image" not in tbl:
        for key in ("world_strength", "world_rotation"):
            if key in tbl:
                r.fail(r.join(path, key), "a world_image beside it", got=tbl[key])
        return None
    image = r.string(tbl, "world_image", path, choices=BUNDLED_WORLDS)
    return WorldPreset(image=image, strength=r.number(tbl, "world_strength", path, 1.0, lo=0.0),
                       rotation=r.number(tbl, "world_rotation", path, 0.0, lo=-360.0, hi=360.0))
