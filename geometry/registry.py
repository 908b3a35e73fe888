"""The mesh builders' registry: how a builder declares its parameters (``Param``: kind, unit,
default, description, choices), how values are parsed and checked, and how a builder is
placed and built (``Builder.build``, ``build``, ``build_mesh``, ``describe_builders``).

The builders themselves are registered by geometry/builders.py (import that module, as
``geometry`` does, before looking one up in ``BUILDERS``).
"""
from __future__ import annotations

import difflib
import inspect
import math
import re
import textwrap
from dataclasses import dataclass
from typing import Any, Callable, Optional

import numpy as np

from . import _shapes as sh
from .mesh import GeometryError, ParameterError, TriMesh

REQUIRED = inspect.Parameter.empty

# ------------------------------------------------------------------------------ parameters
# kind -> (unit shown in the table, phrase for messages)
KINDS = {
    "length": ("m", "a positive length"),
    "length0": ("m", "a length >= 0"),
    "coord": ("m", "a coordinate (m)"),
    "angle": ("deg", "an angle"),
    "count": ("-", "a whole number >= 1"),
    "count0": ("-", "a whole number >= 0"),
    "bool": ("-", "true or false"),
    "choice": ("-", "one of the listed words"),
    "point": ("m", "a point [x, y, z]"),
    "direction": ("-", "a direction [x, y, z]"),
    "factor": ("-", "a positive number"),
    "path": ("-", "a file path"),
}

_LENGTH_UNITS = {"m": 1.0, "km": 1e3, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6,
                 "μm": 1e-6, "in": 0.0254, "inch": 0.0254, "ft": 0.3048}
_ANGLE_UNITS_DEG = {"deg": 1.0, "°": 1.0, "rad": 180.0 / math.pi, "mrad": 0.18 / math.pi}
_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S.*?)?\s*$")


@dataclass(frozen=True)
class Param:
    name: str
    kind: str
    default: Any                  # REQUIRED, None (optional, derived) or a value
    description: str
    choices: tuple = ()

    @property
    def unit(self) -> str:
        return KINDS[self.kind][0]

    @property
    def default_text(self) -> str:
        if self.default is REQUIRED:
            return "required"
        if self.default is None:
            return "optional"
        if isinstance(self.default, bool):
            return "true" if self.default else "false"
        if isinstance(self.default, str):
            return f'"{self.default}"'
        if isinstance(self.default, tuple):
            return "[" + ", ".join(f"{c:g}" for c in self.default) + "]"
        return f"{self.default:g}"


_Bad = ParameterError        # the builders' short name for it


def _number(value, what: str, param: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _Bad(param, f"expected {what}, got {_type_name(value)} {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise _Bad(param, f"expected {what}, got {value!r}")
    return x


def _type_name(v) -> str:
    return {bool: "a boolean", str: "a string", int: "a number", float: "a number",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


def _quantity(value, units: dict, what: str, param: str) -> float:
    if isinstance(value, str):
        m = _QUANTITY.match(value)
        if not m:
            raise _Bad(param, f"expected {what}, got {value!r}")
        unit = (m.group(2) or "").strip()
        if unit not in units:
            raise _Bad(param, f"unknown or wrong unit {unit!r} in {value!r} for {what}; "
                              f"use one of: {', '.join(units)}")
        x = float(m.group(1)) * units[unit]
        if not math.isfinite(x):
            raise _Bad(param, f"expected {what}, got {value!r}: not a finite number")
        return x
    return _number(value, what, param)


def _parse(p: Param, value):
    what = KINDS[p.kind][1]
    name = p.name
    if p.kind in ("length", "length0", "coord"):
        x = _quantity(value, _LENGTH_UNITS, what, name)
        if p.kind == "length" and x <= 0.0:
            raise _Bad(name, f"must be a positive length, got {x:g} m")
        if p.kind == "length0" and x < 0.0:
            raise _Bad(name, f"must be >= 0, got {x:g} m")
        return x
    if p.kind == "angle":
        return _quantity(value, _ANGLE_UNITS_DEG, "an angle (a number of degrees or a "
                                                  "string such as \"0.5 rad\")", name)
    if p.kind in ("count", "count0"):
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value) or value != int(value):
            raise _Bad(name, f"expected {what}, got {value!r}")
        lo = 1 if p.kind == "count" else 0
        if int(value) < lo:
            raise _Bad(name, f"must be {'>= 1' if lo else '>= 0'}, got {int(value)}")
        if int(value) > MAX_COUNT:
            raise _Bad(name, f"{int(value):,} is absurd for a mesh (at most {MAX_COUNT:,})")
        return int(value)
    if p.kind == "bool":
        if not isinstance(value, bool):
            raise _Bad(name, f"expected true or false, got {value!r}")
        return value
    if p.kind == "choice":
        if not isinstance(value, str) or value not in p.choices:
            raise _Bad(name, f"expected one of {', '.join(repr(c) for c in p.choices)}, got "
                             f"{value!r}" + _suggest(str(value), p.choices))
        return value
    if p.kind in ("point", "direction"):
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 3:
            raise _Bad(name, f"expected {what}, got {value!r}")
        units = _LENGTH_UNITS if p.kind == "point" else {"": 1.0}
        v = tuple(_quantity(c, units, what, name) for c in value)
        if p.kind == "direction" and math.hypot(*v) == 0.0:
            raise _Bad(name, "the direction must not be zero")
        return v
    if p.kind == "factor":
        x = _number(value, what, name)
        if x <= 0.0:
            raise _Bad(name, f"must be positive, got {x:g}")
        return x
    if p.kind == "path":
        if not isinstance(value, str) or not value:
            raise _Bad(name, f"expected a file path, got {value!r}")
        return value
    raise AssertionError(p.kind)


def _suggest(word: str, options) -> str:
    options = list(options)
    lower = {o.lower(): o for o in options}
    close = difflib.get_close_matches(word.lower(), list(lower), n=1, cutoff=0.5)
    return f" (did you mean {lower[close[0]]!r}?)" if close else ""


# ------------------------------------------------------------------------------ registry
COMMON = (
    Param("origin", "point", (0.0, 0.0, 0.0), "where the builder's x = 0 point goes"),
    Param("axis_direction", "direction", (1.0, 0.0, 0.0),
          "the builder's +x axis is turned onto this (no roll: builder +z stays upward)"),
    Param("roll_deg", "angle", 0.0, "turn about the builder's own +x axis first"),
    Param("max_edge", "length", None, "subdivide until no triangle edge is longer (m); "
                                      "default: the builder's own resolution"),
)
_COMMON_NAMES = {p.name for p in COMMON}
# the most a count parameter (segments, rows, flights, ...) may be
MAX_COUNT = 10_000


@dataclass(frozen=True)
class Builder:
    """A registered mesh builder: ``function`` makes the shape in builder coordinates from
    parsed parameters; :meth:`build` parses, checks, places and validates."""
    name: str
    function: Callable[..., TriMesh]
    description: str
    params: tuple[Param, ...]
    aliases: tuple[tuple[str, str], ...] = ()     # (alias, parameter)

    def param(self, name: str) -> Param:
        for p in self.params + COMMON:
            if p.name == name:
                return p
        raise KeyError(name)

    def build(self, params: dict, *, key: str = "", base_dir=None) -> TriMesh:
        key = key or self.name
        given = dict(params)
        aliases = dict(self.aliases)
        written: dict[str, str] = {}          # parameter -> the alias the scene used
        for alias, target in self.aliases:
            if alias in given:
                if target in given:
                    raise GeometryError(f"{key}.{alias}", f"{alias!r} and {target!r} are the "
                                                          "same parameter; give one")
                given[target] = given.pop(alias)
                written[target] = alias
        known = {p.name: p for p in self.params + COMMON}
        for name in given:
            if name not in known:
                options = list(known) + list(aliases)
                raise GeometryError(f"{key}.{name}", f"unknown parameter for builder "
                                    f"{self.name!r}{_suggest(name, options)}; it takes: "
                                    f"{', '.join(p.name for p in self.params)} (and "
                                    f"{', '.join(p.name for p in COMMON)})")
        values = {}
        try:
            for p in self.params + COMMON:
                if p.name in given and given[p.name] is not None:
                    values[p.name] = _parse(p, given[p.name])
                elif p.default is REQUIRED:
                    raise _Bad(p.name, f"missing: builder {self.name!r} needs {p.name}: "
                                       f"{p.description}")
                else:
                    values[p.name] = p.default
            common = {n: values.pop(n) for n in _COMMON_NAMES}
            if self.name == "file":
                values["base_dir"] = base_dir
            with sh.triangle_budget():
                mesh = self.function(**values)
                # a builder's incline is applied here, after roll_deg and before axis_direction
                mesh = place(mesh, incline_deg=values.get("incline_deg", 0.0), **common)
        except _Bad as e:
            raise GeometryError(f"{key}.{written.get(e.key, e.key)}", e.reason) from None
        except GeometryError as e:
            if e.key:
                raise
            raise GeometryError(key, e.reason) from None
        return mesh.validate(key)

    def __call__(self, **params) -> TriMesh:
        """Python use: ``geometry.builders.drum(radius=1.0, length=3.0)``."""
        base_dir = params.pop("base_dir", None)
        return self.build(params, key=self.name, base_dir=base_dir)


BUILDERS: dict[str, Builder] = {}


def _register(name: str, description: str, spec: dict, aliases: dict | None = None):
    """Declare a builder: defaults and required-ness come from the function's signature,
    kind and description (and choices) from ``spec[name] = (kind, description[, choices])``."""

    def deco(fn):
        params = []
        sig = inspect.signature(fn)
        names = [n for n in sig.parameters if n != "base_dir"]
        assert set(names) == set(spec), (name, set(names) ^ set(spec))
        for n in names:
            kind, desc, *rest = spec[n]
            default = sig.parameters[n].default
            params.append(Param(n, kind, default, desc, tuple(rest[0]) if rest else ()))
        b = Builder(name, fn, description, tuple(params), tuple((aliases or {}).items()))
        BUILDERS[name] = b
        return b
    return deco


def place(mesh: TriMesh, *, origin=(0.0, 0.0, 0.0), axis_direction=(1.0, 0.0, 0.0),
          roll_deg: float = 0.0, incline_deg: float = 0.0,
          max_edge: Optional[float] = None) -> TriMesh:
    """Apply the common keys: turn by ``roll_deg`` about +x, tilt +x down by ``incline_deg``
    (about +y, for the builders that take an incline), turn +x onto ``axis_direction``,
    translate by ``origin``, then subdivide to ``max_edge``."""
    r = (sh.align_x_to(axis_direction) @ sh.rotation_y(math.radians(incline_deg))
         @ sh.rotation_x(math.radians(roll_deg)))
    mesh = mesh.transformed(r, np.asarray(origin, dtype=np.float64))
    if max_edge is not None:
        mesh = subdivided(mesh, max_edge)
    return mesh


def subdivided(mesh: TriMesh, max_edge: float) -> TriMesh:
    """Split triangles (conformingly, no cracks) until no edge exceeds ``max_edge``."""
    from trimesh.remesh import subdivide_to_size
    extent = mesh.extent
    if extent / max_edge > 1e4:
        raise _Bad("max_edge", f"{max_edge:g} m is too small for a mesh {extent:.3g} m across "
                               "(it would make more than 1e8 triangles)")
    tri = mesh.vertices[mesh.faces]
    longest = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    splits = np.ceil(np.log2(np.maximum(longest / max_edge, 1.0)))
    sh.afford(float(np.sum(4.0 ** splits)), "triangles after subdivision to max_edge")
    iters = max(10, int(math.ceil(math.log2(max(1.0, extent / max_edge)))) + 4)
    v, f, idx = subdivide_to_size(mesh.vertices, mesh.faces, max_edge, max_iter=iters,
                                  return_index=True)
    return TriMesh(v, f, mesh.two_sided[idx])


def body_axis(spec, *, key: str = "mesh") -> tuple[np.ndarray, np.ndarray]:
    """``(point, unit direction)`` of a mesh spec's placed +x axis (origin, axis_direction and
    incline_deg applied), without building it: the natural ``rotate`` axis of a drum or shaft.
    For a list of meshes, the first one's."""
    if isinstance(spec, (list, tuple)):
        spec = spec[0] if spec else {}
    if not isinstance(spec, dict):
        raise GeometryError(key, f"expected a mesh table, got {_type_name(spec)}")
    name = spec.get("builder", "file")
    b = BUILDERS.get(name)
    if b is None:
        return build(name, {}, key=key)       # raises the unknown-builder error
    values = {}
    try:
        for p in COMMON + tuple(q for q in b.params if q.name == "incline_deg"):
            v = spec.get(p.name)
            values[p.name] = _parse(p, v) if v is not None else p.default
    except _Bad as e:
        raise GeometryError(f"{key}.{e.key}", e.reason) from None
    r = (sh.align_x_to(values["axis_direction"])
         @ sh.rotation_y(math.radians(values.get("incline_deg", 0.0))))
    return np.asarray(values["origin"], dtype=np.float64), r[:, 0].copy()


def build(name: str, params: dict, *, key: str = "", base_dir=None) -> TriMesh:
    """Build mesh ``name`` from ``params``; errors name ``key`` + "." + the parameter."""
    if name not in BUILDERS:
        raise GeometryError(f"{key}.builder" if key else "builder",
                            f"unknown builder {name!r}{_suggest(str(name), BUILDERS)}; "
                            f"known: {', '.join(BUILDERS)}")
    return BUILDERS[name].build(params, key=key or name, base_dir=base_dir)


def load_mesh(path, *, scale: float = 1.0, units: str = "m", repair: bool = False,
              flip_normals: bool = False, two_sided: Optional[bool] = None,
              base_dir=None, key: str = "mesh", origin=(0.0, 0.0, 0.0),
              axis_direction=(1.0, 0.0, 0.0), roll_deg: float = 0.0,
              max_edge: Optional[float] = None) -> TriMesh:
    """Read a mesh file into a validated :class:`TriMesh` in metres (the ``file`` builder).

    Coordinates are multiplied by the ``units`` factor and by ``scale``. A relative ``path``
    is taken from ``base_dir`` (the scene file's folder) when given. Errors are
    :class:`~geometry.mesh.GeometryError` naming ``key.file``, ``key.units`` ... .
    """
    params = {"file": str(path), "scale": scale, "units": units, "repair": repair,
              "flip_normals": flip_normals, "two_sided": two_sided, "origin": origin,
              "axis_direction": axis_direction, "roll_deg": roll_deg, "max_edge": max_edge}
    return build("file", params, key=key, base_dir=base_dir)


def build_mesh(spec, *, key: str = "mesh", base_dir=None) -> TriMesh:
    """A scene's ``mesh`` value: ``{builder = "drum", ...}``, ``{file = "part.stl", ...}``, or
    a list of those, merged into one body (e.g. a paddle shaft plus a screw flight)."""
    if isinstance(spec, (list, tuple)):
        if not spec:
            raise GeometryError(key, "an empty list of meshes")
        return TriMesh.concatenate(build_mesh(s, key=f"{key}[{i}]", base_dir=base_dir)
                                   for i, s in enumerate(spec))
    if not isinstance(spec, dict):
        raise GeometryError(key, f"expected a table {{ builder = \"...\", ... }} or "
                                 f"{{ file = \"part.stl\" }}, got {_type_name(spec)}")
    params = dict(spec)
    name = params.pop("builder", None)
    if name is None:
        if "file" not in params:
            raise GeometryError(key, "give builder = \"...\" (one of "
                                     f"{', '.join(BUILDERS)}) or file = \"part.stl\"")
        name = "file"
    elif not isinstance(name, str):
        raise GeometryError(f"{key}.builder", f"expected a builder name, got {name!r}")
    return build(name, params, key=key, base_dir=base_dir)


def describe_builders() -> str:
    """The table printed by ``taichi-dem check --builders``."""
    lines = ["Mesh builders ([[bodies]] mesh = { builder = \"NAME\", ... }). Each places its axis "
             "along +x from x = 0, centred on y = z = 0. Lengths in m, angles in degrees; a "
             "quantity string such as \"15 mm\" also works. Normals point to the particle side; "
             "zero-thickness plates are single-layer and two-sided. A list of meshes makes "
             "one body."]
    lines = [textwrap.fill(lines[0], 100)]
    width = max(len(p.name) for b in BUILDERS.values() for p in b.params + COMMON) + 2

    def rows(params):
        for p in params:
            desc = p.description
            if p.choices:
                desc += " (" + " | ".join(f'"{c}"' for c in p.choices) + ")"
            head = f"    {p.name:<{width}}{p.unit:<5}{p.default_text:<12}"
            yield textwrap.fill(desc, 100, initial_indent=head,
                                subsequent_indent=" " * len(head))

    for b in BUILDERS.values():
        lines += ["", textwrap.fill(f"{b.name}: {b.description}", 100, initial_indent="  ",
                                    subsequent_indent="    ")]
        lines += rows(b.params)
        for alias, target in b.aliases:
            lines.append(f"    ({alias} = {target})")
    lines += ["", "  common to every builder (applied in this order: roll_deg, the builder's "
              "incline_deg, axis_direction, origin, max_edge):"]
    lines += rows(COMMON)
    return "\n".join(lines)
