"""A seeded generator of malformed scenes for ``taichi-dem check`` and ``taichi-dem run``.

Every case starts from a scene known to be valid (the demos, the scenes of the test suite, a
few built here to reach the mesh-file, CSV-fill and process keys) and breaks it in exactly one
way that is invalid *by construction*. The case records what the error must name: the dotted
key (``particles[0].region.box``; the reported key must be it or lie beneath it) or, for a file
that is not TOML at all, a fragment such as ``line 7``. Mutations that might leave a valid
scene (a changed positive number, a cut at the end of a line) are never generated.

Categories (``CATEGORIES``): wrong_type, missing_key, bad_number (NaN, inf, zero, negative,
out of range, beyond the 1e-30 .. 1e30 SI magnitudes), wrong_unit, unknown_key, bad_choice
(a near miss of an enum or a reference), bad_name, empty_region, absurd_size, overfull (more
spheres than a region packs: refused by the placement, not the loader), broken_mesh,
broken_csv, truncated, duplicate_key, garbage, non_utf8, and schema: mutations drawn from
``taichi-dem schema`` (scene/schema.py) rather than from the lists here, so a key is fuzzed the
day it is declared. For a value anywhere in a base scene, its schema (the quantity's range,
SI magnitudes and unit pattern, an integer's bounds, an enum, a name's pattern, a vector's
length, a table's required and allowed keys, a builder parameter's kind) gives the breakages:
a bound crossed just (the next float past it), the wrong type, NaN / inf / 1e308, a unit of
another dimension, a float for an integer (3000.0), a near miss of a choice, a control
character in a name, an unknown key beside a declared one, a required key removed. A mutation
is kept only when the schema refuses the mutated scene (invalid by construction); the loader
must refuse it too, naming the key (tests/fuzz/test_schema_agrees.py compares the two).

Offline, many more cases than the suite keeps::

    python tests/fuzz/scene_fuzz.py --cases 5000 --seed 7 [--command run] [--show 20]

prints every case that did not exit 2 with the file and the key named, and a count per
category. Only the standard library's ``random`` is used, so a seed always gives the same
corpus.
"""
from __future__ import annotations

import copy
import functools
import importlib.util
import json
import math
import random
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from taichi_dem.geometry.builders import BUILDERS, COMMON, REQUIRED  # noqa: E402
from taichi_dem.scene import loader as _loader  # noqa: E402
from taichi_dem.scene.keys import registered as _registered  # noqa: E402
from taichi_dem.scene.sections.regions import CYLINDER as _CYLINDER  # noqa: E402
from taichi_dem.thermal.settings import PLUG_FLOW_REQUIRED as _PLUG_FLOW_REQUIRED  # noqa: E402

CATEGORIES = ("wrong_type", "missing_key", "bad_number", "wrong_unit", "unknown_key",
              "bad_choice", "bad_name", "empty_region", "absurd_size", "overfull", "broken_mesh",
              "broken_csv", "truncated", "duplicate_key", "garbage", "non_utf8", "schema")
# relative frequency of each category in a generated corpus
WEIGHTS = {"wrong_type": 12, "missing_key": 10, "bad_number": 14, "wrong_unit": 10,
           "unknown_key": 8, "bad_choice": 6, "bad_name": 4, "empty_region": 6,
           "absurd_size": 8, "overfull": 2, "broken_mesh": 7, "broken_csv": 3, "truncated": 7,
           "duplicate_key": 2, "garbage": 3,
           "non_utf8": 3, "schema": 40}


@dataclass
class Case:
    ident: str                    # category/base/what, unique within a corpus
    category: str
    base: str
    text: bytes                   # the scene file's bytes
    # the reported key must equal one of these or lie beneath it ("a.b" covers "a.b.c", "a.b[0]")
    expect_keys: tuple = ()
    # fragments the message must contain (file-level errors: "line 7", "UTF-8")
    expect_fragments: tuple = ()
    files: dict = field(default_factory=dict)   # beside the scene: name -> bytes (None: a folder)
    # the file the message must name, relative to the case folder (default: the scene)
    names_file: Optional[str] = None


# ---------------------------------------------------------------------------------- TOML writer
def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):        # TOML's basic strings: JSON's escapes, and DEL escaped too
        return json.dumps(v, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k, ensure_ascii=False)


def dumps(doc: dict) -> str:
    """TOML text for ``doc``: [table] and [[array of tables]] at the top, inline below."""
    head, body = [], []
    for k, v in doc.items():
        if isinstance(v, dict):
            body.append(f"\n[{_key(k)}]")
            body += [f"{_key(kk)} = {_value(vv)}" for kk, vv in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                body.append(f"\n[[{_key(k)}]]")
                body += [f"{_key(kk)} = {_value(vv)}" for kk, vv in item.items()]
        else:
            head.append(f"{_key(k)} = {_value(v)}")
    return "\n".join(head + body).lstrip("\n") + "\n"


# ---------------------------------------------------------------------------------- key paths
def dotted(path) -> str:
    out = ""
    for p in path:
        if isinstance(p, int):
            out += f"[{p}]"
        else:
            out += ("." if out else "") + p
    return out


def get(doc, path):
    for p in path:
        doc = doc[p]
    return doc


def put(doc, path, value):
    get(doc, path[:-1])[path[-1]] = value


def delete(doc, path):
    parent = get(doc, path[:-1])
    if isinstance(parent, list):
        parent.pop(path[-1])
    else:
        del parent[path[-1]]


def nodes(doc, path=()):
    """Every (path, value) below ``doc`` (not the root), depth first."""
    items = doc.items() if isinstance(doc, dict) else \
        enumerate(doc) if isinstance(doc, list) else ()
    for k, v in items:
        yield path + (k,), v
        yield from nodes(v, path + (k,))


def key_matches(reported: str, expected: str) -> bool:
    return (reported == expected or reported.startswith(expected + ".")
            or reported.startswith(expected + "["))


# ---------------------------------------------------------------------------------- base scenes
@dataclass
class Base:
    name: str
    doc: dict
    text: str                          # the original text (comments and all)
    files: dict = field(default_factory=dict)


def _module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _obj_box(lo, hi) -> str:
    """A closed box as OBJ text (outward normals)."""
    c = [(hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
         for i in range(8)]
    quads = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    lines = ["# a box"] + [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in c]
    for a, b, cc, d in quads:
        lines += [f"f {a + 1} {b + 1} {cc + 1}", f"f {a + 1} {cc + 1} {d + 1}"]
    return "\n".join(lines) + "\n"


PART_OBJ = _obj_box((-0.02, -0.01, -0.005), (0.02, 0.06, 0.0))

MESH_FILE_SCENE = """
[simulation]
end_time = 0.5
precision = "f64"

[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5

[[bodies]]
name = "paddle"
material = "steel"
mesh = { file = "part.obj", scale = 1.0, units = "m" }
motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "6 rpm" } }

[[particles]]
material = "glass"
radius = 0.004
count = 3
region = { box = { min = [-0.01, 0.03, 0.001], max = [0.01, 0.05, 0.03] } }
"""

CSV_SCENE = """
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]

[materials.ash]
density = 870.0
youngs_modulus = 1.1e7
poisson_ratio = 0.25

[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5

[[particles]]
material = "ash"
file = "fill.csv"
velocity = [0.0, 0.0, -1.0]
"""
FILL_CSV = "x,y,z,radius,vx,vy,vz\n0.5,0.5,0.5,0.01,0,0,0\n0.2,0.2,0.2,0.02,0,0,1\n" \
           "0.7,0.3,0.4,0.015,1,0,0\n"

# factories with sizes, a fixed gas with every key, sensors of every kind, a translating body
PROCESS_SCENE = """
[simulation]
end_time = 2.0
dt = "auto"
rayleigh_fraction = 0.2
skin = "1 mm"
max_particles = 5000

[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
periodic = ["y"]

[materials.ash]
density = "870 kg/m3"
youngs_modulus = "11 MPa"
poisson_ratio = 0.25
thermal_conductivity = 0.3
heat_capacity = 800.0
emissivity = 0.9
real_youngs_modulus = 1.1e10

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = 45.0

[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.05
model = "epsd"
rolling_damping = 0.3

[[interactions]]
pair = ["ash", "steel"]
restitution = 0.6
friction = 0.5

[[walls]]
name = "floor"
plane = { point = [0, 0, 0], normal = [0, 0, 1] }
material = "steel"
temperature = "30 C"

[[bodies]]
name = "pusher"
material = "steel"
mesh = { builder = "box", min = [0.05, 0.1, 0.05], max = [0.1, 0.9, 0.2], normals = "outward" }
motion = { translate = { velocity = ["1 cm/s", 0, 0] } }

[[particles]]
material = "ash"
radius = { mean = "10 mm", std = "1 mm", min = "8 mm", max = "12 mm" }
count = 50
region = { box = { min = [0.3, 0.1, 0.05], max = [0.9, 0.9, 0.4] } }
temperature = 300.0
moisture = 0.02
fixed = false
angular_velocity = [0, 0, "1 rpm"]

[[factories]]
name = "inlet"
material = "ash"
sizes = [["8 mm", 0.3], ["12 mm", 0.7]]
region = { cylinder = { axis_point = [0.5, 0.5, 0.6], axis_direction = [0, 0, 1], radius = 0.2, length = 0.2 } }
velocity = [0.0, 0.0, -0.5]
temperature = "450 C"
moisture = 0.05
mass_rate = [[0.0, "0.5 t/h"], [1.0, "1 t/h"]]
interval = 0.05

[[outlets]]
name = "drain"
region = { box = { min = [0.0, 0.0, 0.0], max = [0.05, 1.0, 1.0] } }

[[sensors]]
kind = "mass_flow"
name = "plane"
plane = { point = [0.5, 0, 0], normal = [1, 0, 0] }
box = { min = [0.4, 0.0, 0.0], max = [0.6, 1.0, 0.5] }

[[sensors]]
kind = "residence_time"
name = "res"
from = "inlet"
to = "drain"

[[sensors]]
kind = "contact_count"
name = "touching"
body = "pusher"

[thermal]
conduction = true
wall_conduction = true
radiation = true
radiation_to = "floor"
contact_radius_correction = "collision"
evaporation_temperature = "100 C"
latent_heat = "2.26 MJ/kg"
water_heat_capacity = 4186.0

[thermal.gas]
model = "fixed"
temperature = "80 C"
velocity = [0.0, 0.0, 1.0]
correlation = "gunn"
porosity = 0.4
density = 1.0
viscosity = 2e-5
conductivity = 0.03
heat_capacity = 1010.0

[output]
interval = 0.1
rrd = "out/p.rrd"
h5 = "out/p.h5"
checkpoint_interval = 1.0
"""

# every builder the demos do not use, each with its required keys and some optional ones
BUILDERS_SCENE = """
[simulation]
end_time = 1.0

[domain]
min = [-0.5, -1.0, -1.0]
max = [3.0, 1.0, 1.0]

[materials.ash]
density = 870.0
youngs_modulus = 1.1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5

[[interactions]]
pair = ["ash", "steel"]
restitution = 0.6
friction = 0.5

[[bodies]]
name = "screw"
material = "steel"
mesh = [
  { builder = "paddle_shaft", length = 2.0, shaft_radius = 0.05, start = 1.0, rows = 4, paddles_per_row = 2, paddle_length = 0.2, paddle_width = 0.1, paddle_thickness = 0.01, segments = 16 },
  { builder = "screw", length = 0.8, shaft_radius = 0.05, outer_radius = 0.3, pitch = 0.2, handedness = "left", include_shaft = false, segments_per_turn = 24, starts = 2 },
]
motion = { rotate = { speed = [[0.0, "0 rpm"], [0.5, "30 rpm"]] } }

[[bodies]]
name = "hopper"
material = "steel"
mesh = { builder = "hopper", kind = "wedge", height = 0.3, top_width = 0.4, orifice_width = 0.1, depth = 0.2, spout_length = 0.05, origin = [2.5, 0, 0.2], axis_direction = [0, 0, 1] }

[[bodies]]
name = "chute"
material = "steel"
mesh = { builder = "chute", length = 0.5, width = 0.2, incline_deg = "20 deg", wall_height = "5 cm", back_wall = true, origin = [2.0, 0.4, -0.5] }

[[particles]]
material = "ash"
radius = 0.01
count = 20
region = { cylinder = { axis_point = [2.5, 0.0, 0.3], axis_direction = [0, 0, 1], radius = 0.1, length = 0.1 } }
velocity = ["1 cm/s", 0, 0]
"""


def base_scenes() -> list[Base]:
    """The valid scenes the corpus starts from (each is checked to load by the test suite)."""
    out: list[Base] = []
    for p in sorted((ROOT / "demos").glob("*.toml")):
        text = p.read_text(encoding="utf-8")
        doc = tomllib.loads(text)
        # mesh and particle files a demo refers to travel with it
        files = {v: (p.parent / v).read_bytes() for path, v in nodes(doc)
                 if path[-1] == "file" and isinstance(v, str) and (p.parent / v).is_file()}
        out.append(Base(f"demo_{p.stem}", doc, text, files))
    conftest = _module(ROOT / "tests" / "conftest.py", "_fuzz_conftest")
    small = conftest.SMALL_SCENE.format(precision="f64", rolling=0.05, count=20)
    out.append(Base("small_scene", tomllib.loads(small), small))
    out.append(Base("plate_scene", tomllib.loads(conftest.PLATE_SCENE), conftest.PLATE_SCENE))
    sys.path.insert(0, str(ROOT / "tests" / "unit"))
    try:
        test_loader = _module(ROOT / "tests" / "unit" / "test_loader.py", "_fuzz_test_loader")
    finally:
        sys.path.remove(str(ROOT / "tests" / "unit"))
    contract = test_loader.CONTRACT_SCENE
    out.append(Base("contract_scene", tomllib.loads(contract), contract))
    loader_base = test_loader.dumps(test_loader.base())
    out.append(Base("loader_base", tomllib.loads(loader_base), loader_base))
    for name, text, files in (("mesh_file", MESH_FILE_SCENE, {"part.obj": PART_OBJ.encode()}),
                              ("csv_fill", CSV_SCENE, {"fill.csv": FILL_CSV.encode()}),
                              ("process", PROCESS_SCENE, {}),
                              ("builders", BUILDERS_SCENE, {})):
        out.append(Base(name, tomllib.loads(text), text, files))
    return out


# ---------------------------------------------------------------------------------- the schema
# what the loader expects of each key, as far as the mutations need to know
QUANTITY = {  # key -> (dimension, constraint)
    "end_time": ("time", "pos"), "dt": ("time", "pos"), "skin": ("length", "pos"),
    "rayleigh_fraction": ("dimensionless", "(0,1]"),
    "density": ("density", "pos"), "youngs_modulus": ("pressure", "pos"),
    "real_youngs_modulus": ("pressure", "pos"), "poisson_ratio": ("dimensionless", "(-1,0.5)"),
    "thermal_conductivity": ("thermal_conductivity", "pos"),
    "heat_capacity": ("specific_heat", "pos"), "emissivity": ("dimensionless", "[0,1]"),
    "restitution": ("dimensionless", "(0,1]"), "friction": ("dimensionless", "nonneg"),
    "rolling_friction": ("dimensionless", "nonneg"), "rolling_damping": ("dimensionless", "[0,1]"),
    "temperature": ("temperature", "pos"), "moisture": ("dimensionless", "nonneg"),
    "interval": ("time", "pos"), "checkpoint_interval": ("time", "pos"),
    "evaporation_temperature": ("temperature", "pos"),
    "latent_heat": ("specific_energy", "pos"), "water_heat_capacity": ("specific_heat", "nonneg"),
    "porosity": ("dimensionless", "(0,1)"), "viscosity": ("viscosity", "pos"),
    "conductivity": ("thermal_conductivity", "pos"), "mass_flow": ("mass_rate", "pos"),
    "inlet_temperature": ("temperature", "pos"), "flow_area": ("area", "pos"),
    "length": ("length", "pos"), "radius": ("length", "pos"), "mean": ("length", "pos"),
    "std": ("length", "nonneg"), "speed": ("angular_speed", "any"),
    "mass_rate": ("mass_rate", "nonneg"), "radiation_to": ("temperature", "pos"),
}
VEC3 = {"gravity": "acceleration", "min": "length", "max": "length", "point": "length",
        "axis_point": "length", "origin": "length", "normal": "direction",
        "axis_direction": "direction", "velocity": "speed", "angular_velocity": "angular_speed"}
INTEGER = {"count": "nonneg", "seed": ">=0", "max_particles": ">=1", "cells": "1..10000"}
BOOLS = ("fixed", "conduction", "wall_conduction", "radiation")
ENUMS = ("precision", "model", "correlation", "flow", "contact_radius_correction", "kind",
         "material", "from", "to", "body", "file", "dt", "radiation_to")
FREE_STRINGS = ("name", "rrd", "h5")
TABLE_ARRAYS = ("interactions", "particles", "walls", "bodies", "factories", "outlets", "sensors")
# builder parameter kind -> (leaf kind, dimension, constraint)
BUILDER_KINDS = {
    "length": ("quantity", "length", "pos"), "length0": ("quantity", "length", "nonneg"),
    "coord": ("quantity", "length", "any"), "angle": ("quantity", "angle", "any"),
    "count": ("bcount", None, ">=1"), "count0": ("bcount", None, ">=0"),
    "bool": ("bool", None, None), "choice": ("enum", None, None),
    "point": ("vec3", "length", None), "direction": ("vec3", "direction", None),
    "factor": ("factor", None, "pos"), "path": ("enum", None, None),
}

# every key some section declares (scene/keys.py): an unknown-key mutation must not land on one
ALL_KEYS = set(_loader.SECTIONS) | set(_loader.PLANNED_SECTIONS)
for _section in _registered().values():
    ALL_KEYS |= set(_section.names)
ALL_KEYS |= {"builder", "file", "box", "cylinder", "sizes"}
for _b in BUILDERS.values():
    ALL_KEYS |= {p.name for p in _b.params + COMMON} | {a for a, _ in _b.aliases}


# every word some enum key accepts: a near miss must not land on one
VALID_WORDS = {"f32", "f64", "auto", "gas", "x", "y", "z"} | \
    {c for _section in _registered().values() for _k in _section.keys for c in _k.choices} | \
    {"fixed", "axial_plug_flow", "ranz_marshall", "gunn",
     "along_axis", "against_axis", "static", "collision", "none"} | \
    set(BUILDERS) | {c for _b in BUILDERS.values() for p in _b.params for c in p.choices}


@dataclass(frozen=True)
class Leaf:
    kind: str                     # quantity vec3 integer bcount factor bool enum free_string
    #                               table tables schedule pair periodic sizes meshlist unknown
    dim: Optional[str] = None
    cons: Optional[str] = None
    # the key the loader names for an error here (builder vector components: the parameter)
    key: Optional[tuple] = None


def mesh_context(path):
    """(spec path, rest of the path) when ``path`` lies inside a body's mesh spec."""
    for i in range(len(path) - 2):
        if path[i] == "bodies" and isinstance(path[i + 1], int) and path[i + 2] == "mesh":
            spec = path[:i + 3]
            rest = path[i + 3:]
            if rest and isinstance(rest[0], int):
                spec, rest = spec + rest[:1], rest[1:]
            return spec, rest
    return None


def builder_of(spec: dict):
    if not isinstance(spec, dict):
        return None
    name = spec.get("builder", "file" if "file" in spec else None)
    return BUILDERS.get(name) if isinstance(name, str) else None


def classify(doc, path) -> Leaf:
    v = get(doc, path)
    last = path[-1]
    parent = path[-2] if len(path) > 1 else None
    m = mesh_context(path)
    if m is not None:
        spec_path, rest = m
        if not rest:
            return Leaf("meshlist" if isinstance(v, list) else "table")
        b = builder_of(get(doc, spec_path))
        if rest[0] == "builder":
            return Leaf("enum")
        if b is None:
            return Leaf("unknown")
        pname = dict(b.aliases).get(rest[0], rest[0])
        try:
            p = b.param(pname)
        except KeyError:
            return Leaf("unknown")
        kind, dim, cons = BUILDER_KINDS[p.kind]
        if len(rest) == 1:
            return Leaf(kind, dim, cons, key=spec_path + (rest[0],))
        if len(rest) == 2 and kind == "vec3":
            return Leaf("quantity", "dimensionless" if dim == "direction" else dim, "any",
                        key=spec_path + (rest[0],))
        return Leaf("unknown")
    if isinstance(last, int):
        if parent in VEC3 and isinstance(get(doc, path[:-1]), list) and len(path) > 1 \
                and not (len(path) > 2 and path[-3] == "radius"):
            d = VEC3[parent]
            return Leaf("quantity", "dimensionless" if d == "direction" else d, "any")
        if parent in ("periodic", "pair"):
            return Leaf("enum")
        if parent in ("mass_rate", "speed", "sizes"):
            return Leaf("pair")          # one [a, b] entry of a schedule or of sizes
        if len(path) > 2 and path[-3] in ("mass_rate", "speed", "sizes") and last in (0, 1):
            what = path[-3]
            if last == 0:
                return Leaf("quantity", "length", "pos") if what == "sizes" else \
                    Leaf("quantity", "time", "nonneg")
            return {"mass_rate": Leaf("quantity", "mass_rate", "nonneg"),
                    "speed": Leaf("quantity", "angular_speed", "any"),
                    "sizes": Leaf("quantity", "dimensionless", "pos")}[what]
        if parent in TABLE_ARRAYS and isinstance(v, dict):
            return Leaf("table")
        return Leaf("unknown")
    if last in ("min", "max") and parent == "radius":
        return Leaf("quantity", "length", "pos")
    if last in VEC3 and isinstance(v, list):
        return Leaf("vec3", VEC3[last])
    if last in ("mass_rate", "speed") and isinstance(v, list):
        return Leaf("schedule")
    if last == "dt" and v == "auto":
        return Leaf("enum")
    if last == "radiation_to" and isinstance(v, str):
        return Leaf("enum")
    if last in QUANTITY and isinstance(v, (int, float, str)) and not isinstance(v, bool):
        return Leaf("quantity", *QUANTITY[last])
    if last in INTEGER and isinstance(v, int) and not isinstance(v, bool):
        return Leaf("integer", None, INTEGER[last])
    if last in BOOLS and isinstance(v, bool):
        return Leaf("bool")
    if last in ENUMS and isinstance(v, str):
        return Leaf("enum")
    if last in FREE_STRINGS:
        return Leaf("free_string")
    if last == "periodic":
        return Leaf("periodic")
    if last == "pair":
        return Leaf("pair")
    if last == "sizes":
        return Leaf("sizes")
    if isinstance(v, dict):
        return Leaf("table")
    if last in TABLE_ARRAYS and isinstance(v, list):
        return Leaf("tables")
    return Leaf("unknown")


def error_key(leaf: Leaf, path) -> tuple:
    return leaf.key if leaf.key is not None else tuple(path)


# ---------------------------------------------------------------------------------- mutations
UNIT_EXAMPLES = {
    "length": ["15 mm", "3 ft"], "time": ["2 min", "30 s"], "temperature": ["150 C", "300 K"],
    "mass": ["3 kg", "2 t"], "mass_rate": ["10 t/h", "1 kg/s"],
    "density": ["2.5 g/cm3"], "pressure": ["200 GPa"], "speed": ["2 m/s", "5 km/h"],
    "angular_speed": ["10 rpm", "1 rad/s"], "acceleration": ["9.81 m/s2"],
    "angle": ["30 deg", "0.5 rad"], "force": ["5 kN"], "power": ["2 kW"], "energy": ["3 kWh"],
    "area": ["2 cm2"], "viscosity": ["1 cP"], "thermal_conductivity": ["0.3 W/(m K)"],
    "specific_heat": ["800 J/(kg K)"], "specific_energy": ["2 MJ/kg"],
}
SI_UNIT = {"length": "m", "time": "s", "temperature": "K", "mass_rate": "kg/s",
           "density": "kg/m3", "pressure": "Pa", "speed": "m/s", "angular_speed": "rpm",
           "acceleration": "m/s2", "angle": "deg", "area": "m2", "viscosity": "Pa s",
           "thermal_conductivity": "W/(m K)", "specific_heat": "J/(kg K)",
           "specific_energy": "J/kg", "dimensionless": "%"}
GARBAGE_STRINGS = ["fast rpm", "", "   ", "ten", "1,5", "15 mm mm", "10 furlongs", "0x1F",
                   "1e999", "nan", "inf m", "++1", "1.2.3", "\u20145", "1/0", "NaN K", "-"]
BAD_TABLE = {"x_fuzz": 1}


def _typo(rng: random.Random, word: str) -> str:
    ops = ["drop", "swap", "double", "suffix"]
    w = word
    op = rng.choice(ops)
    if op == "drop" and len(w) > 2:
        i = rng.randrange(len(w))
        w = w[:i] + w[i + 1:]
    elif op == "swap" and len(w) > 2:
        i = rng.randrange(len(w) - 1)
        w = w[:i] + w[i + 1] + w[i] + w[i + 2:]
    elif op == "double" and w:
        i = rng.randrange(len(w))
        w = w[:i] + w[i] + w[i:]
    else:
        w = w + rng.choice(["s", "_", "2", "x"])
    return w


class Fuzzer:
    """Makes one case per call of :meth:`case` from a seeded ``random.Random``."""

    def __init__(self, bases: list[Base]):
        self.bases = bases
        self.by_category: dict[str, Callable] = {c: getattr(self, "m_" + c) for c in CATEGORIES}

    def corpus(self, n: int, seed: int = 0) -> list[Case]:
        """``n`` cases from ``seed``: the same for the same (n, seed), whatever ran before."""
        cats = list(WEIGHTS)
        weights = [WEIGHTS[c] for c in cats]
        out: list[Case] = []
        seen: set[str] = set()
        k = 0
        while len(out) < n:
            rng = random.Random(f"{seed}:{k}")
            k += 1
            cat = rng.choices(cats, weights)[0]
            case = self.case(rng, cat)
            if case is None:
                continue
            ident = case.ident
            j = 1
            while case.ident in seen:
                j += 1
                case.ident = f"{ident}#{j}"
            seen.add(case.ident)
            out.append(case)
        return out

    def case(self, rng: random.Random, category: str) -> Optional[Case]:
        for _ in range(50):
            base = rng.choice(self.bases)
            got = self.by_category[category](rng, base)
            if got is not None:
                return got
        return None

    # -- helpers ------------------------------------------------------------------------------
    def _case(self, category: str, base: Base, what: str, doc: dict, expect, **kw) -> Case:
        files = dict(base.files)
        files.update(kw.pop("files", {}))
        text = kw.pop("text", None)
        if text is None:
            text = dumps(doc).encode("utf-8")
        expect = tuple(dotted(e) if isinstance(e, tuple) else e for e in expect)
        return Case(ident=f"{category}/{base.name}/{what}", category=category, base=base.name,
                    text=text, expect_keys=expect, files=files, **kw)

    def _leaves(self, doc, kinds) -> list:
        out = []
        for path, _ in nodes(doc):
            leaf = classify(doc, path)
            if leaf.kind in kinds:
                out.append((path, leaf))
        return out

    # -- categories -----------------------------------------------------------------------------
    def m_wrong_type(self, rng, base):
        doc = copy.deepcopy(base.doc)
        cands = [(p, lf) for p, _ in nodes(doc) for lf in [classify(doc, p)]
                 if lf.kind != "unknown"]
        cands.append(((), Leaf("root")))
        path, leaf = rng.choice(cands)
        if leaf.kind == "root":             # a top-level section of the wrong type
            sec = rng.choice([k for k in doc])
            path, leaf = (sec,), classify(doc, (sec,))
        k = leaf.kind
        if k in ("quantity",):
            choices = [True, False, BAD_TABLE, [], ["abc"]]
        elif k == "integer":
            choices = [True, 1.5, "3", BAD_TABLE, [], [1]]
        elif k == "bcount":
            choices = [True, 2.5, "4", BAD_TABLE, []]
        elif k == "factor":
            choices = [True, "2", BAD_TABLE, []]
        elif k == "bool":
            choices = [1, 0, "true", "yes", [], BAD_TABLE]
        elif k in ("enum", "free_string"):
            choices = [True, [], BAD_TABLE, ["a", "b"]]
            if k == "free_string" or path[-1] not in ("dt", "radiation_to"):
                choices.append(3)
        elif k == "vec3":
            v = get(doc, path)
            choices = [1.0, "1 m", True, BAD_TABLE, v[:2], v + [0.0], [v], ["a", "b", "c"], []]
        elif k in ("table",):
            choices = [True, "nonsense", [], [1, 2]]
            if path[-1] != "radius":
                choices.append(5)
            if path[-1] == "mesh":
                choices.remove([])          # an empty list of meshes has its own message
                choices.append([])
        elif k in ("tables", "meshlist"):
            choices = [True, "nonsense", {}, [1], 7]
        elif k == "schedule":
            choices = [True, BAD_TABLE, [], [[0.0, 1.0, 2.0]], [["a", "b"]], [0.0, 1.0]]
        elif k == "pair":
            v = get(doc, path)
            choices = [True, "x", BAD_TABLE, v[:1], v + v[:1], []]
        elif k == "periodic":
            choices = [True, "x", BAD_TABLE, [1], [["x"]]]
        elif k == "sizes":
            choices = [True, "x", BAD_TABLE, [], [[0.01]], [0.01, 1.0]]
        else:
            return None
        value = rng.choice(choices)
        if path == ("domain",) and value == {}:
            return None
        put(doc, path, copy.deepcopy(value))
        return self._case("wrong_type", base, f"{dotted(path)}={_short(value)}", doc,
                          (error_key(leaf, path),))

    def m_missing_key(self, rng, base):
        doc = copy.deepcopy(base.doc)
        options = list(required_deletions(doc))
        if not options:
            return None
        path, expect = rng.choice(options)
        delete(doc, path)
        return self._case("missing_key", base, f"del {dotted(path)}", doc, expect)

    def m_bad_number(self, rng, base):
        doc = copy.deepcopy(base.doc)
        cands = self._leaves(doc, ("quantity", "integer", "bcount", "factor", "vec3"))
        cands = [(p, lf) for p, lf in cands if lf.kind != "vec3" or lf.dim == "direction"]
        if not cands:
            return None
        path, leaf = rng.choice(cands)
        v = get(doc, path)
        in_mesh = mesh_context(path) is not None
        nonfinite = [math.nan, math.inf, -math.inf]
        if leaf.kind == "vec3":          # a direction
            choices = [[0, 0, 0], [0.0, -0.0, 0.0]]
        elif leaf.kind == "integer":
            choices = {"nonneg": [-1, -10 ** 6, math.nan], ">=0": [-1, -2 ** 40, math.nan, 1.5],
                       ">=1": [0, -1, math.nan, 2 ** 31, 10 ** 18],
                       "1..10000": [0, 10001, -3, 10 ** 9]}[leaf.cons]
        elif leaf.kind == "bcount":
            choices = ([0, -2] if leaf.cons == ">=1" else [-1]) + nonfinite + [2.5]
        elif leaf.kind == "factor":
            choices = [0, -1.0, -1e-300] + nonfinite
        else:
            cons = leaf.cons
            choices = list(nonfinite)
            if not in_mesh:                 # nonzero SI magnitudes beyond 1e-30 .. 1e30
                choices += [1e31, -1e300, 1e-31, -1e-300]
            if cons == "pos":
                choices += [0, 0.0, -1.0, -1e-20]
                if isinstance(v, (int, float)) and v:
                    choices.append(-abs(v))
            elif cons == "nonneg":
                choices += [-1.0, -1e-20]
            elif cons == "(0,1]":
                choices += [0.0, 1.5, -0.5, 1.0000001]
            elif cons == "[0,1]":
                choices += [1.01, -0.1]
            elif cons == "(-1,0.5)":
                choices += [0.5, -1.0, 0.7, -3.0]
            elif cons == "(0,1)":
                choices += [0.0, 1.0, 1.2]
            unit = SI_UNIT.get(leaf.dim)
            if unit and leaf.dim != "dimensionless" and \
                    (not in_mesh or leaf.dim in ("length", "angle")):
                choices.append(f"1e999 {unit}")
                if cons in ("pos", "nonneg"):
                    choices.append(f"-5 {unit}")
                if cons == "pos":
                    choices.append(f"0 {unit}")
                if leaf.dim == "temperature":
                    choices += ["-300 C", "-1 K", "-500 F"]
        value = rng.choice(choices)
        put(doc, path, value)
        return self._case("bad_number", base, f"{dotted(path)}={_short(value)}", doc,
                          (error_key(leaf, path),))

    def m_wrong_unit(self, rng, base):
        doc = copy.deepcopy(base.doc)
        cands = self._leaves(doc, ("quantity", "integer", "bcount", "factor"))
        if not cands:
            return None
        path, leaf = rng.choice(cands)
        choices = list(GARBAGE_STRINGS)
        if leaf.kind == "quantity":
            inside_mesh = mesh_context(path) is not None
            for dim, examples in UNIT_EXAMPLES.items():
                if dim == leaf.dim or (inside_mesh and dim in ("length", "angle")):
                    continue
                choices += examples
        else:
            choices += ["3 kg", "10 t/h", "4", "2.0"]
        value = rng.choice(choices)
        put(doc, path, value)
        return self._case("wrong_unit", base, f"{dotted(path)}={_short(value)}", doc,
                          (error_key(leaf, path),))

    def m_unknown_key(self, rng, base):
        doc = copy.deepcopy(base.doc)
        tables = [((), doc)] + [(p, v) for p, v in nodes(doc) if isinstance(v, dict)]
        path, table = rng.choice(tables)
        siblings = [k for k in table if isinstance(k, str)]
        for _ in range(20):
            if siblings and rng.random() < 0.7:
                new = _typo(rng, rng.choice(siblings))
            else:
                new = "x_fuzz_" + rng.choice(["colour", "speed", "radius2", "unit", "notes"])
            if new not in ALL_KEYS and new not in table and new:
                break
        else:
            return None
        table[new] = rng.choice([1.0, "x", True, [1, 2]])
        return self._case("unknown_key", base, f"{dotted(path + (new,))}", doc,
                          (path + (new,),))

    def m_bad_choice(self, rng, base):
        """An enum or reference string replaced by a near miss or nonsense."""
        doc = copy.deepcopy(base.doc)
        cands = self._leaves(doc, ("enum",))
        if not cands:
            return None
        path, leaf = rng.choice(cands)
        old = get(doc, path)
        strings = {v for _, v in nodes(doc) if isinstance(v, str)} | VALID_WORDS
        for _ in range(20):
            new = _typo(rng, old) if rng.random() < 0.7 else rng.choice(
                ["x_fuzz", "f16", "cpu", "K", "?"])
            if new not in strings and new.strip().lower() != "auto" and new:
                break
        else:
            return None
        put(doc, path, new)
        return self._case("bad_choice", base, f"{dotted(path)}={_short(new)}", doc,
                          (error_key(leaf, path),))

    def m_bad_name(self, rng, base):
        doc = copy.deepcopy(base.doc)
        opts = []
        for sec in ("factories", "outlets", "sensors", "walls", "bodies"):
            items = doc.get(sec, [])
            for i, it in enumerate(items):
                if "name" not in it:
                    continue
                bad = ["", "  "] if sec in ("walls", "bodies") else \
                    ["", "in let", "a/b", "caf\u00e9", "x:y", "tab\tname"]
                for b in bad:
                    opts.append(((sec, i, "name"), b, (sec, i, "name")))
                for j in range(i + 1, len(items)):
                    opts.append(((sec, j, "name"), it["name"], (sec, j, "name")))
        walls = doc.get("walls", [])
        for j, b in enumerate(doc.get("bodies", [])):
            for w in walls:
                opts.append((("bodies", j, "name"), w["name"], ("bodies", j, "name")))
        inter = doc.get("interactions", [])
        for j in range(1, len(inter)):
            opts.append((("interactions", j, "pair"), list(inter[0]["pair"][::-1]),
                         ("interactions", j, "pair")))
        if not opts:
            return None
        path, value, expect = rng.choice(opts)
        put(doc, path, value)
        return self._case("bad_name", base, f"{dotted(path)}={_short(value)}", doc, (expect,))

    def m_empty_region(self, rng, base):
        doc = copy.deepcopy(base.doc)
        opts = []
        for path, v in nodes(doc):
            if not isinstance(v, dict):
                continue
            last = path[-1] if path else None
            if last in ("region", "radiation_region") and len(v) == 1:
                kind = next(iter(v))
                opts += [("squash", path + (kind,), path + (kind,)),
                         ("outside", path + (kind,), path + (kind,)),
                         ("empty", path, path), ("both", path, path)]
            elif last == "box" and len(path) >= 2 and path[0] == "sensors":
                opts.append(("squash", path, path))
            elif mesh_context(path) and not mesh_context(path)[1] and v.get("builder") == "box":
                opts.append(("squash", path, path + ("max",)))
        opts.append(("squash", ("domain",), ("domain", "max")))
        how, path, expect = rng.choice(opts)
        t = get(doc, path)
        if how == "squash":
            lo, hi = t.get("min"), t.get("max")
            if not (isinstance(lo, list) and isinstance(hi, list) and
                    all(isinstance(x, (int, float)) for x in lo + hi)):
                return None
            a = rng.randrange(3)
            hi[a] = lo[a] - rng.choice([0.0, 0.0, 1e-9, 0.5, 1e6])
            what = f"{dotted(path)}.max[{a}]={hi[a]:g}"
        elif how == "outside":
            span = [h - l for l, h in zip(doc["domain"]["min"], doc["domain"]["max"])]
            a = rng.randrange(3)
            shift = (3.0 * span[a] + 1.0) * rng.choice([1, -1])
            keys = ("min", "max") if "min" in t else ("axis_point",)
            for k in keys:
                if not all(isinstance(x, (int, float)) for x in t[k]):
                    return None
                t[k][a] += shift
            what = f"{dotted(path)} moved {shift:g} m along {'xyz'[a]}"
        elif how == "empty":
            t.clear()
            what = f"{dotted(path)}={{}}"
        else:
            t["cylinder" if "box" in t else "box"] = {"min": [0, 0, 0], "max": [1, 1, 1]} \
                if "box" not in t else {"axis_point": [0, 0, 0], "axis_direction": [1, 0, 0],
                                        "radius": 0.1, "length": 0.1}
            what = f"{dotted(path)} box and cylinder"
        return self._case("empty_region", base, what, doc, (expect,))

    def m_absurd_size(self, rng, base):
        doc = copy.deepcopy(base.doc)
        opts = []
        for i, f in enumerate(doc.get("particles", [])):
            if "file" in f or "region" not in f:
                continue
            opts += [("count", i), ("radius", i)]
        opts.append(("tiny_domain", None))
        if "max_particles" not in doc.get("simulation", {}):
            opts += [("factory_rate", i) for i in range(len(doc.get("factories", [])))]
        opts.append(("max_particles", None))
        for path, v in nodes(doc):
            m = mesh_context(path)
            if m and not m[1] and isinstance(v, dict):
                b = builder_of(v)
                if b is None:
                    continue
                if b.name == "file":
                    opts.append(("scale", path))
                else:
                    opts += [("builder_length", path), ("builder_count", path)]
        how, where = rng.choice(opts)
        if how == "count":
            f = doc["particles"][where]
            volume = _region_volume(f["region"])
            r = _smallest_radius(f["radius"])
            if volume is None or r is None:
                return None
            need = math.ceil(volume / (4.0 / 3.0 * math.pi * r ** 3)) + 1
            count = max(need * rng.choice([1, 2, 10]), 10 ** rng.randint(7, 18))
            if count >= 2 ** 63:
                return None
            f["count"] = count
            return self._case("absurd_size", base, f"particles[{where}].count={count:.3g}", doc,
                              (("particles", where, "count"),))
        if how == "radius":
            f = doc["particles"][where]
            ext = _region_extent(f["region"])
            if ext is None or f.get("count", 0) == 0:
                return None
            f["radius"] = ext * rng.choice([0.51, 1.0, 3.0, 1e3, 1e6, 1e30])
            return self._case("absurd_size", base, f"particles[{where}].radius="
                                                   f"{f['radius']:.3g}", doc,
                              (("particles", where, "radius"),))
        if how == "factory_rate":
            doc["factories"][where]["mass_rate"] = rng.choice(["1e29 kg/s", "1e25 t/h", 1e30])
            doc.setdefault("simulation", {})["end_time"] = 1e6
            return self._case("absurd_size", base, f"factories[{where}].mass_rate huge", doc,
                              (("factories", where, "mass_rate"),))
        if how == "max_particles":
            n = rng.choice([2 ** 31, 10 ** 12, 2 ** 62])
            doc.setdefault("simulation", {})["max_particles"] = n
            return self._case("absurd_size", base, f"max_particles={n:.3g}", doc,
                              (("simulation", "max_particles"),))
        if how == "tiny_domain":
            lo = doc["domain"]["min"]
            if not all(isinstance(x, (int, float)) for x in lo):
                return None
            size = rng.choice([1e-12, 1e-9, 1e-7])
            doc["domain"]["max"] = [x + size for x in lo]
            return self._case("absurd_size", base, f"domain {size:g} m", doc, (("domain",),))
        spec = get(doc, where)
        b = builder_of(spec)
        if how == "scale":
            spec["scale"] = rng.choice([1e30, 1e6, 1e-9, 1e-30])
            return self._case("absurd_size", base, f"{dotted(where)}.scale={spec['scale']:g}",
                              doc, (where,))
        if how == "builder_length":
            names = [k for k in spec if k in {p.name for p in b.params}
                     and b.param(k).kind in ("length", "point")
                     and k not in ("shell_radius", "pitch")]
            if not names:
                return None
            k = rng.choice(names)
            factor = rng.choice([1e6, 1e9, 1e30])
            if b.param(k).kind == "point":
                if not all(isinstance(x, (int, float)) for x in spec["min"] + spec["max"]):
                    return None
                spec["min"] = [x * factor for x in spec["min"]]
                spec["max"] = [x * factor for x in spec["max"]]
                k = "min,max"
            else:
                x = spec[k]
                if not isinstance(x, (int, float)):
                    return None
                spec[k] = max(abs(x) * factor, 1e4)
            return self._case("absurd_size", base, f"{dotted(where)}.{k} x{factor:g}", doc,
                              (where,))
        counts = [p.name for p in b.params if p.kind in ("count", "count0")]
        if not counts:
            return None
        k = rng.choice(counts)
        spec[k] = 10 ** rng.randint(7, 15)
        return self._case("absurd_size", base, f"{dotted(where)}.{k}={spec[k]:.0e}", doc,
                          (where,))

    def m_overfull(self, rng, base):
        """More spheres than a region can pack (solid fraction 0.78 to 1, beyond the densest
        packing, 0.74) yet within its volume: the loader accepts it, the placement (run by
        ``check`` and by the Simulation) refuses it."""
        doc = copy.deepcopy(base.doc)
        opts = [i for i, f in enumerate(doc.get("particles", []))
                if "region" in f and "file" not in f]
        if not opts:
            return None
        i = rng.choice(opts)
        f = doc["particles"][i]
        volume = _region_volume(f["region"])
        r = _smallest_radius(f["radius"])
        if volume is None or r is None:
            return None
        count = math.floor(rng.uniform(0.78, 0.99) * volume / (4.0 / 3.0 * math.pi * r ** 3))
        if not 1 <= count <= 20000:
            return None
        f["count"] = count
        return self._case("overfull", base, f"particles[{i}].count={count}", doc,
                          (("particles", i, "count"),))

    def m_broken_mesh(self, rng, base):
        if "part.obj" not in base.files:
            return None
        doc = copy.deepcopy(base.doc)
        where = ("bodies", 0, "mesh")
        spec = get(doc, where)
        obj = base.files["part.obj"].decode()
        vlines = [ln for ln in obj.splitlines() if ln.startswith("v ")]
        flines = [ln for ln in obj.splitlines() if ln.startswith("f ")]
        how = rng.choice(["missing", "folder", "empty", "no_faces", "cut_vertices", "bad_index",
                          "collinear", "one_point", "nan_vertex", "garbage_stl", "tiny_stl",
                          "ascii_stl_cut", "extension", "only_faces", "huge"])
        files: dict = {}
        name = "part.obj"
        if how == "missing":
            name = rng.choice(["nope.obj", "sub/part.obj", "part.OBJ.stl"])
        elif how == "folder":
            name = "meshes.obj"
            files[name] = None
        elif how == "empty":
            files[name] = b""
        elif how == "no_faces":
            files[name] = ("\n".join(vlines) + "\n").encode()
        elif how == "cut_vertices":
            text = "\n".join(vlines)
            files[name] = text[:rng.randrange(1, len(text))].encode()
        elif how == "bad_index":
            n = len(vlines)
            bad = [f"f {rng.randint(n + 1, n + 99)} {rng.randint(n + 1, n + 99)} "
                   f"{rng.randint(n + 1, n + 99)}" for _ in flines]
            files[name] = ("\n".join(vlines + bad) + "\n").encode()
        elif how == "collinear":
            vs = [f"v {0.01 * i:.3f} {0.02 * i:.3f} 0" for i in range(len(vlines))]
            files[name] = ("\n".join(vs + flines) + "\n").encode()
        elif how == "one_point":
            vs = ["v 0.01 0.02 0.0"] * len(vlines)
            files[name] = ("\n".join(vs + flines) + "\n").encode()
        elif how == "nan_vertex":
            vs = ["v nan nan nan"] + vlines[1:]
            files[name] = ("\n".join(vs + flines) + "\n").encode()
        elif how == "garbage_stl":
            name = "part.stl"
            files[name] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 83)))
        elif how == "tiny_stl":
            name = "part.stl"
            files[name] = b"solid x\nendsolid x\n"
        elif how == "ascii_stl_cut":
            name = "part.stl"
            text = ("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.05 0 0\n"
                    "vertex 0 0.05 0\nendloop\nendfacet\nendsolid x\n")
            files[name] = text[:rng.randint(10, text.index("vertex 0 0.05"))].encode()
        elif how == "extension":
            name = "part.xyz_unknown"
            files[name] = base.files["part.obj"]
        elif how == "only_faces":
            files[name] = ("\n".join(flines) + "\n").encode()
        elif how == "huge":
            vs = [" ".join(["v"] + [f"{float(c) * 1e30:g}" for c in ln.split()[1:]])
                  for ln in vlines]
            files[name] = ("\n".join(vs + flines) + "\n").encode()
        spec["file"] = name
        return self._case("broken_mesh", base, how, doc, (where,), files=files)

    def m_broken_csv(self, rng, base):
        if "fill.csv" not in base.files:
            return None
        doc = copy.deepcopy(base.doc)
        rows = base.files["fill.csv"].decode().splitlines()
        header, data = rows[0], rows[1:]
        how = rng.choice(["cell", "radius", "outside", "header", "short_row", "empty",
                          "non_utf8", "missing"])
        text = None
        r = rng.randrange(len(data))
        cells = data[r].split(",")
        if how == "cell":
            c = rng.randrange(len(cells))
            cells[c] = rng.choice(["abc", "nan", "inf", "-inf", "", "1e999", "0x1", "1e-300",
                                   "1e300"])
        elif how == "radius":
            cells[3] = rng.choice(["0", "-0.01", "-1e-300"])
        elif how == "outside":
            cells[rng.randrange(3)] = rng.choice(["1.5", "-0.2", "1e30"])
        elif how == "short_row":
            cells = cells[:rng.randint(1, len(cells) - 1)]
        if how in ("cell", "radius", "outside", "short_row"):
            data[r] = ",".join(cells)
            text = "\n".join([header] + data) + "\n"
        elif how == "header":
            names = header.split(",")
            opt = rng.choice(["drop_z", "unknown", "dup", "half_v"])
            if opt == "drop_z":
                names[2] = "w"
            elif opt == "unknown":
                names.append("colour")
                data = [d + ",1" for d in data]
            elif opt == "dup":
                names[1] = "x"
            else:
                names = names[:5]
                data = [",".join(d.split(",")[:5]) for d in data]
            text = "\n".join([",".join(names)] + data) + "\n"
        elif how == "empty":
            text = rng.choice(["", "\n\n", "# only a comment\n"])
        if how == "missing":
            doc["particles"][0]["file"] = "nope.csv"
            return self._case("broken_csv", base, how, doc, (("particles", 0, "file"),))
        data_bytes = text.encode() if text is not None else \
            ("x,y,z,radius\n0.5,0.5,0.5,0.01 # caf\xe9\n").encode("latin-1")
        return self._case("broken_csv", base, f"{how}", doc, (("particles", 0, "file"),),
                          files={"fill.csv": data_bytes}, names_file="fill.csv")

    # -- file-level ----------------------------------------------------------------------------
    def m_truncated(self, rng, base):
        text = base.text if rng.random() < 0.6 else dumps(base.doc)
        cuts = truncation_points(text)
        if not cuts:
            return None
        pos = rng.choice(cuts)
        cut = text[:pos]
        try:
            tomllib.loads(cut)
        except tomllib.TOMLDecodeError:
            pass
        else:
            raise AssertionError(f"the cut at {pos} of {base.name} parses: {cut[-40:]!r}")
        line = cut.count("\n") + 1
        return self._case("truncated", base, f"cut at byte {pos} (line {line})", {}, (),
                          text=cut.encode("utf-8"),
                          expect_fragments=("TOML syntax error", f"line {line}"))

    def m_duplicate_key(self, rng, base):
        """A key given twice in one table, or a [table] header repeated: TOML refuses both."""
        lines = dumps(base.doc).split("\n")
        keyed = [i for i, ln in enumerate(lines) if re.match(r"^[A-Za-z0-9_\"-]+ = ", ln)]
        headers = [i for i, ln in enumerate(lines) if re.match(r"^\[[^\[]", ln)]
        if rng.random() < 0.7 or not headers:
            i = rng.choice(keyed)
            value = rng.choice([lines[i].split(" = ", 1)[1], "1.0", '"x"'])
            lines.insert(i + 1, lines[i].split(" = ", 1)[0] + " = " + value)
            line = i + 2
        else:
            i = rng.choice(headers)
            lines.append(lines[i])
            line = len(lines)
        text = "\n".join(lines)
        try:
            tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            pass
        else:
            raise AssertionError(f"the duplicate at line {line} of {base.name} parses")
        return self._case("duplicate_key", base, f"line {line}", {}, (), text=text.encode(),
                          expect_fragments=("TOML syntax error", f"line {line}"))

    # -- scenes whose keys are each valid but do not work together (issue 33 item 7) -----------
    # (an output interval longer than the run is valid: CONTRACT.md, a benchmark wants it)
    INCONSISTENT = ("frame_interval", "behind_wall", "flipped_wall", "h5")

    def inconsistent_cases(self, n: int, seed: int = 0) -> list[Case]:
        """``n`` cases, each kind of INCONSISTENT in turn, from ``seed``."""
        out, k = [], 0
        while len(out) < n and k < 50 * n:
            rng = random.Random(f"inconsistent:{seed}:{k}")
            kind = self.INCONSISTENT[len(out) % len(self.INCONSISTENT)]
            k += 1
            case = self.m_inconsistent(rng, rng.choice(self.bases), kind)
            if case is not None and case.ident not in {c.ident for c in out}:
                out.append(case)
        return out

    def m_inconsistent(self, rng, base, kind):
        doc = copy.deepcopy(base.doc)
        if kind == "frame_interval":
            # frames are taken at samples: a frame interval that is not a whole multiple of
            # the sample interval (each valid alone) would drift
            out = doc.setdefault("output", {})
            interval = out.get("interval", 0.05)
            if not isinstance(interval, (int, float)) or isinstance(interval, bool):
                return None
            out["frame_interval"] = float(interval) * rng.choice([0.5, 1.5, 2.25, 3.7])
            return self._case("inconsistent", base, "frame_interval between samples", doc,
                              ("output.frame_interval",))
        if kind == "h5":
            doc.setdefault("output", {})["h5"] = "/etc/passwd/results.h5"
            return self._case("inconsistent", base, "h5 under a file", doc, ("output.h5",))
        # a box region of a fill or factory, and a plane wall
        walls = doc.get("walls", [])
        lo, hi = doc.get("domain", {}).get("min"), doc.get("domain", {}).get("max")
        if not walls or not (isinstance(lo, list) and isinstance(hi, list)):
            return None
        regions = [(sec, i) for sec in ("particles", "factories")
                   for i, f in enumerate(doc.get(sec, []))
                   if isinstance(f.get("region"), dict) and "box" in f["region"]]
        if not regions:
            return None
        sec, i = rng.choice(regions)
        box = doc[sec][i]["region"]["box"]
        j = rng.randrange(len(walls))
        w = walls[j]
        try:
            p = [float(x) for x in w["plane"]["point"]]
            nrm = [float(x) for x in w["plane"]["normal"]]
            corners = [[(box["min"], box["max"])[a][0], (box["min"], box["max"])[b][1],
                        (box["min"], box["max"])[c][2]] for a in (0, 1) for b in (0, 1)
                       for c in (0, 1)]
            side = [sum((x - q) * m for x, q, m in zip(cr, p, nrm)) for cr in corners]
            centre = sum((0.5 * (float(a) + float(b)) - q) * m
                         for a, b, q, m in zip(lo, hi, p, nrm))
        except (KeyError, TypeError, ValueError):
            return None
        if kind == "flipped_wall":
            # a wall with the region wholly in front of it and the domain's centre too
            if min(side) <= 0.0 or centre <= 0.0:
                return None
            w["plane"]["normal"] = [-x for x in nrm]
            return self._case("inconsistent", base, f"walls[{j}] normal flipped", doc,
                              (("walls", j, "normal"),))
        # behind_wall: the region moved to just behind a wall facing the domain's centre
        if centre <= 0.0 or max(abs(x) for x in nrm) < 1.0 - 1e-12:
            return None
        a = max(range(3), key=lambda k: abs(nrm[k]))
        width = float(box["max"][a]) - float(box["min"][a])
        if nrm[a] > 0:
            box["max"][a], box["min"][a] = p[a] - 1e-3, p[a] - 1e-3 - width
        else:
            box["min"][a], box["max"][a] = p[a] + 1e-3, p[a] + 1e-3 + width
        return self._case("inconsistent", base, f"{sec}[{i}] region behind walls[{j}]", doc,
                          ((sec, i, "region"),))

    # -- drawn from the schema (taichi-dem schema) -----------------------------------------------
    SCHEMA_KINDS = ("bound", "nonfinite", "wrong_type", "wrong_unit", "integer_float",
                    "bad_enum", "bad_string", "bad_length", "unknown_key", "missing_key")

    def m_schema(self, rng, base):
        """One breakage of one value (or table) of ``base``, drawn from its schema; kept
        only when the schema refuses the result."""
        doc = copy.deepcopy(base.doc)
        if base.name not in _SPOTS:
            _SPOTS[base.name] = list(schema_spots(base.doc))
        options = [o for path, node in _SPOTS[base.name]
                   for o in schema_mutations(rng, node, get(doc, path) if path else doc, path)]
        for _ in range(20):
            kind = rng.choice(sorted({o[0] for o in options}))
            _, what, apply, expect = rng.choice([o for o in options if o[0] == kind])
            new = copy.deepcopy(doc)
            apply(new)
            if schema_valid(new):
                continue             # not invalid by construction: draw again
            return self._case("schema", base, f"{kind} {what}", new, expect)
        return None

    def m_garbage(self, rng, base):
        how = rng.choice(["bytes", "ascii", "nul", "utf16", "binary_prefix"])
        if how == "bytes":
            data = bytes([rng.choice([0xff, 0xfe, 0xc0, 0x80])]) + \
                bytes(rng.randrange(256) for _ in range(rng.randint(0, 400)))
            frags = ("not a UTF-8 text file",)
        elif how == "ascii":
            alphabet = "=[]{}\"',.#\n\t abc123"
            junk = "".join(rng.choice(alphabet) for _ in range(rng.randint(0, 300)))
            data = ("=" + junk).encode()
            frags = ("TOML syntax error", "line 1")
        elif how == "nul":
            lines = base.text.split("\n")
            i = rng.randrange(len(lines))
            j = rng.randint(0, len(lines[i]))
            lines[i] = lines[i][:j] + "\x00" + lines[i][j:]
            data = "\n".join(lines).encode()
            frags = ("TOML syntax error", f"line {i + 1}")
        elif how == "utf16":
            data = base.text.encode("utf-16")
            frags = ("not a UTF-8 text file",)
        else:
            data = b"\x89PNG\r\n\x1a\n" + base.text.encode()
            frags = ("not a UTF-8 text file",)
        return self._case("garbage", base, how, {}, (), text=data, expect_fragments=frags)

    def m_non_utf8(self, rng, base):
        lines = base.text.split("\n")
        i = rng.randrange(len(lines))
        j = rng.randint(0, len(lines[i]))
        junk = rng.choice(["\xb0C", "caf\xe9", "\xb5m", "\xff", "\xa0"]).encode("latin-1")
        data = b"\n".join(ln.encode() for ln in lines[:i]) + (b"\n" if i else b"") + \
            lines[i][:j].encode() + junk + lines[i][j:].encode() + \
            b"".join(b"\n" + ln.encode() for ln in lines[i + 1:])
        return self._case("non_utf8", base, f"line {i + 1}", {}, (), text=data,
                          expect_fragments=("not a UTF-8 text file", f"line {i + 1}"))


# ---------------------------------------------------------------------------------- from the schema
_SCHEMA: dict = {}
_SPOTS: dict = {}        # base name -> schema_spots(base.doc)


def scene_schema():
    """(schema, validator) of ``taichi-dem schema``, made once."""
    if not _SCHEMA:
        from taichi_dem.scene import schema as _schema_module
        _SCHEMA["schema"] = _schema_module.scene_schema()
        _SCHEMA["validator"] = _schema_module.validator(_SCHEMA["schema"])
        _SCHEMA["module"] = _schema_module
    return _SCHEMA["schema"], _SCHEMA["validator"]


def schema_valid(doc) -> bool:
    """Whether the schema accepts ``doc`` (TOML data: nan, inf as json_compatible says)."""
    _, v = scene_schema()
    return v.is_valid(_SCHEMA["module"].json_compatible(doc))


def _branch(node: dict, value):
    """The branch of an anyOf / oneOf that ``value`` satisfies (the node itself without
    one); None when none does."""
    _, v = scene_schema()
    for key in ("anyOf", "oneOf"):
        if key in node:
            for b in node[key]:
                b = _branch(b, value)
                if b is not None and v.evolve(schema=b).is_valid(
                        _SCHEMA["module"].json_compatible(value)):
                    return b
            return None
    return node


def schema_spots(doc):
    """(path, schema node) of every value in ``doc`` (the root too), the node being the
    anyOf branch the value satisfies."""
    root, _ = scene_schema()

    def walk(value, node, path):
        node = _branch(node, value)
        if node is None:
            return
        yield path, node
        if isinstance(value, dict):
            props = node.get("properties", {})
            extra = node.get("additionalProperties")
            for k, v in value.items():
                sub = props.get(k, extra if isinstance(extra, dict) else None)
                if sub is not None:
                    yield from walk(v, sub, path + (k,))
        elif isinstance(value, list):
            prefix = node.get("prefixItems", [])
            items = node.get("items")
            for i, v in enumerate(value):
                sub = prefix[i] if i < len(prefix) else items
                if isinstance(sub, dict):
                    yield from walk(v, sub, path + (i,))

    yield from walk(doc, root, ())


def _types(node: dict) -> list:
    t = node.get("type", [])
    return list(t) if isinstance(t, list) else [t]


def _table_key(path) -> tuple:
    """The key the loader names for a value at ``path``: an array's items (a vector's
    components, a schedule's entries, a builder point's coordinates) under the array."""
    path = tuple(path)
    while path and isinstance(path[-1], int) and len(path) > 1 and \
            not (isinstance(path[-2], str) and path[-2] in TABLE_ARRAYS) and path[-2] != "mesh":
        path = path[:-1]
    return path


def _past(bound: float, direction: int) -> float:
    """The next float past ``bound`` (in ``direction``); past 0, the smallest magnitude the
    loader reads, 1e-30, not a subnormal float (which a process that started Taichi, with
    denormals flushed to zero, compares as 0)."""
    if bound == 0:
        return direction * 1e-30
    return math.nextafter(float(bound), direction * math.inf)


def _other_units(node: dict) -> list[str]:
    """Quantity strings of another dimension than ``node``'s pattern accepts."""
    return list(_other_units_for(node["pattern"]))


@functools.lru_cache(maxsize=None)
def _other_units_for(pattern_text: str) -> tuple[str, ...]:
    """_other_units by pattern, once per pattern (the corpus asks ~20,000 times for a few
    dozen patterns: seconds of every pytest worker's collection)."""
    from taichi_dem.scene.units import DIMENSIONS, units_for
    pattern = re.compile(pattern_text)
    out = []
    for d in DIMENSIONS:
        for u in units_for(d)[:3] + ["ft", "in", "deg"]:
            text = f"3 {u}"
            if not pattern.search(text):
                out.append(text)
    return tuple(sorted(set(out)))


# strings that break a name's or a path's pattern (control characters; '/', '.', '..' and
# blanks at the ends, which cannot name a results group)
BAD_STRINGS = ["", "  ", "tab\tname", "nul\x00byte", "bell\x07", "del\x7f", "new\nline",
               "in let", "a/b", "caf\u00e9", ".", "..", " padded "]


def schema_mutations(rng, node: dict, value, path) -> list:
    """[(kind, what, apply(doc), expected keys)] that break ``value`` at ``path`` as its
    schema ``node`` says (the caller keeps those the schema refuses)."""
    out = []
    where = dotted(path) or "<root>"
    expect = (_table_key(path),) if path else ()
    if expect and expect[0][-1:] in (("min",), ("max",)):
        # a box corner: moving one may put min above max, which the loader blames on max
        expect = (expect[0][:-1],)

    def put_value(kind, new):
        def apply(doc, new=new):
            put(doc, path, copy.deepcopy(new))
        out.append((kind, f"{where}={_short(new)}", apply, expect))

    if not path:
        return out
    types = _types(node)
    numeric = "number" in types or "integer" in types
    if numeric:
        for k in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
            if k not in node:
                continue
            b = node[k]
            if "integer" in types:
                new = {"minimum": b - 1, "exclusiveMinimum": b, "maximum": b + 1,
                       "exclusiveMaximum": b}[k]
            else:
                new = {"minimum": _past(b, -1), "exclusiveMinimum": float(b),
                       "maximum": _past(b, 1), "exclusiveMaximum": float(b)}[k]
            put_value("bound", new)
        if "not" in node and "exclusiveMaximum" in node["not"]:     # the SI magnitudes
            put_value("bound", node["not"]["exclusiveMaximum"] * 0.5)
        for new in (math.nan, math.inf, -math.inf, 1e308):
            put_value("nonfinite", new)
        if "integer" in types and isinstance(value, int) and not isinstance(value, bool):
            put_value("integer_float", float(value))
            put_value("integer_float", value + 0.5)
        if "multipleOf" in node:
            put_value("integer_float", 2.5)
    if "string" in types and "pattern" in node:
        if "x-dimension" in node or numeric:
            for new in rng.sample(_other_units(node), 3):
                put_value("wrong_unit", new)
        for new in rng.sample(GARBAGE_STRINGS + BAD_STRINGS, 4):
            put_value("bad_string", new)
    elif "string" in types:
        for new in BAD_STRINGS[:2]:
            put_value("bad_string", new)
    if "enum" in node or "const" in node:
        words = [w for w in node.get("enum", [node.get("const")]) if isinstance(w, str)]
        if words:
            # a typo can leave a word as it was (swapping the two s of "mass") or make another
            # valid one: only a word outside the choices is a bad choice
            typo = next((t for t in (_typo(rng, rng.choice(words)) for _ in range(20))
                         if t not in words), None)
            if typo is not None:
                put_value("bad_enum", typo)
        put_value("wrong_type", 3)
    if types and "boolean" not in types:
        put_value("wrong_type", True)
    if types and not numeric and "boolean" in types:
        for new in (1, "true"):
            put_value("wrong_type", new)
    if "array" in types and isinstance(value, list):
        if value:
            put_value("bad_length", value[:-1])
        put_value("bad_length", value + value[:1] if value else [1.0])
        if "not" in node and "items" in node["not"]:               # a direction
            put_value("bound", [0, 0, 0])
        put_value("wrong_type", {"x_fuzz": 1})
    if "object" in types and isinstance(value, dict):
        if "string" not in types:
            put_value("wrong_type", [1.0])
        props = node.get("properties")
        if props is not None and node.get("additionalProperties") is False:
            siblings = [k for k in value if isinstance(k, str)]
            for _ in range(10):
                new = _typo(rng, rng.choice(siblings)) if siblings and rng.random() < 0.7 \
                    else "x_fuzz_" + rng.choice(["colour", "unit", "notes"])
                if new not in props and new not in ALL_KEYS:
                    def apply(doc, k=new):
                        get(doc, path)[k] = 1.0
                    out.append(("unknown_key", f"{where}.{new}", apply, (path + (new,),)))
                    break
        for k in node.get("required", []):
            if k in value:
                def apply(doc, k=k):
                    del get(doc, path)[k]
                out.append(("missing_key", f"del {where}.{k}", apply, (path + (k,), path)))
    return out


def _short(v) -> str:
    s = _value(v) if not isinstance(v, (bytes,)) else repr(v)
    return s if len(s) <= 40 else s[:37] + "..."


def _region_volume(region):
    try:
        if "box" in region:
            lo, hi = region["box"]["min"], region["box"]["max"]
            return math.prod(float(h) - float(l) for l, h in zip(lo, hi))
        c = region["cylinder"]
        return math.pi * float(c["radius"]) ** 2 * float(c["length"])
    except (TypeError, ValueError, KeyError):
        return None


def _region_extent(region):
    try:
        if "box" in region:
            lo, hi = region["box"]["min"], region["box"]["max"]
            return max(float(h) - float(l) for l, h in zip(lo, hi))
        c = region["cylinder"]
        return max(2.0 * float(c["radius"]), float(c["length"]))
    except (TypeError, ValueError, KeyError):
        return None


def _smallest_radius(radius):
    from taichi_dem.scene.units import parse_quantity
    try:
        if isinstance(radius, dict):
            return parse_quantity(radius.get("min", radius["mean"]), "length")
        return parse_quantity(radius, "length")
    except Exception:
        return None


def truncation_points(text: str) -> list[int]:
    """Cut positions that leave a prefix that is not TOML, by construction: inside a table
    header, inside a key or right after its '=', inside a string, or inside an unclosed
    inline table or array. (A cut after a complete value or at a line break could leave a
    valid scene.)"""
    out = []
    pos = 0
    depth = 0                              # open brackets of a multi-line value
    for line in text.splitlines(keepends=True):
        body = line.rstrip("\r\n")
        start = pos
        pos += len(line)
        stripped = body.strip()
        if depth == 0 and (not stripped or stripped.startswith("#")):
            continue
        i0 = len(body) - len(body.lstrip())
        if depth == 0 and stripped.startswith("["):
            end = body.find("]", i0 + (2 if stripped.startswith("[[") else 1))
            if end > i0:
                out += [start + k for k in range(i0 + 1, end)]
            continue
        k = i0
        in_str = None
        if depth == 0:
            eq = body.find("=")
            if eq < 0:
                continue
            out += [start + c for c in range(i0 + 1, eq + 1)]   # "ke", "key ", "key ="
            k = eq + 1
            while k < len(body) and body[k] == " ":
                out.append(start + k)                          # "key = " (no value yet)
                k += 1
        while k < len(body):
            ch = body[k]
            if in_str:
                if ch == "\\":
                    k += 2
                    continue
                if ch == in_str:
                    in_str = None
                else:
                    out.append(start + k + 1) if k + 1 < len(body) else None
            elif ch in "\"'":
                in_str = ch
                out.append(start + k + 1)
            elif ch == "#":
                break
            elif ch in "[{":
                depth += 1
            elif ch in "]}":
                depth -= 1
            if depth > 0 and not in_str and ch not in "\"'":
                out.append(start + k + 1)
            k += 1
    # a cut just before a closing bracket can close nothing else: still unclosed
    return sorted(set(p for p in out if 0 < p < len(text)))


def required_deletions(doc):
    """(path, expected keys) for every key whose removal makes ``doc`` invalid."""
    yield ("domain",), (("domain",),)
    for k in ("min", "max"):
        if k in doc.get("domain", {}):
            yield ("domain", k), (("domain", k),)
    for name, m in doc.get("materials", {}).items():
        for k in ("density", "youngs_modulus", "poisson_ratio"):
            if k in m:
                yield ("materials", name, k), (("materials", name, k),)
    refs = material_references(doc)
    for name in doc.get("materials", {}):
        if refs.get(name):
            yield ("materials", name), tuple(refs[name])
    if refs and "materials" in doc:
        yield ("materials",), tuple(p for ps in refs.values() for p in ps)
    for i, t in enumerate(doc.get("interactions", [])):
        for k in ("pair", "restitution", "friction"):
            if k in t:
                yield ("interactions", i, k), (("interactions", i, k),)
    needed = needed_pairs(doc)
    for i, t in enumerate(doc.get("interactions", [])):
        if frozenset(t["pair"]) in needed:
            yield ("interactions", i), (("interactions",),)
    for i, f in enumerate(doc.get("particles", [])):
        keys = ("material",) if "file" in f else ("material", "radius", "count", "region")
        for k in keys:
            yield ("particles", i, k), (("particles", i, k),)
    for i, w in enumerate(doc.get("walls", [])):
        for k in ("name", "plane", "material"):
            yield ("walls", i, k), (("walls", i, k),)
        for k in ("point", "normal"):
            yield ("walls", i, "plane", k), (("walls", i, "plane", k),)
    for i, b in enumerate(doc.get("bodies", [])):
        for k in ("name", "material", "mesh"):
            yield ("bodies", i, k), (("bodies", i, k),)
        mo = b.get("motion", {})
        if "rotate" in mo:
            yield ("bodies", i, "motion", "rotate", "speed"), \
                (("bodies", i, "motion", "rotate", "speed"),)
        if "translate" in mo:
            yield ("bodies", i, "motion", "translate", "velocity"), \
                (("bodies", i, "motion", "translate", "velocity"),)
        specs = b["mesh"] if isinstance(b["mesh"], list) else [b["mesh"]]
        for j, spec in enumerate(specs):
            sp = ("bodies", i, "mesh") + ((j,) if isinstance(b["mesh"], list) else ())
            bl = builder_of(spec)
            if bl is None:
                continue
            aliases = {a: t for a, t in bl.aliases}
            for k in spec:
                target = aliases.get(k, k)
                names_builder = k == "builder" or (k == "file" and "builder" not in spec)
                if names_builder or (target in {p.name for p in bl.params}
                                     and bl.param(target).default is REQUIRED):
                    exp = (sp,) if names_builder else (sp + (k,), sp + (target,))
                    yield sp + (k,), exp
    for path, v in nodes(doc):
        if not path or not isinstance(v, dict):
            continue
        if path[-1] in ("region", "radiation_region"):
            for kind, sub in v.items():
                keys = ("min", "max") if kind == "box" else _CYLINDER.names
                for k in keys:
                    if isinstance(sub, dict) and k in sub:
                        yield path + (kind, k), (path + (kind, k),)
        if path[-1] == "radius" and mesh_context(path) is None:
            for k in ("mean", "std"):
                if k in v:
                    yield path + (k,), (path + (k,),)
            std = v.get("std", 0)
            if std not in (0, 0.0, "0 mm", "0 m"):
                for k in ("min", "max"):
                    if k in v:
                        yield path + (k,), (path + (k,),)
    for i, f in enumerate(doc.get("factories", [])):
        sheet = f.get("pattern") == "sheet"
        for k in ("name", "material", "mass_rate") + (("face", "velocity") if sheet
                                                      else ("region",)):
            if k in f:
                yield ("factories", i, k), (("factories", i, k),)
        k = "radius" if "radius" in f else "sizes"
        yield ("factories", i, k), (("factories", i, "radius"),)
    for i, o in enumerate(doc.get("outlets", [])):
        for k in ("name", "region"):
            yield ("outlets", i, k), (("outlets", i, k),)
    for i, s in enumerate(doc.get("sensors", [])):
        extra = {"mass_flow": ("plane",), "residence_time": ("from", "to"),
                 "contact_count": ("body",)}[s["kind"]]
        for k in ("kind", "name") + extra:
            yield ("sensors", i, k), (("sensors", i, k),)
        if s["kind"] == "mass_flow":
            for k in ("point", "normal"):
                yield ("sensors", i, "plane", k), (("sensors", i, "plane", k),)
            if "box" in s:
                for k in ("min", "max"):
                    yield ("sensors", i, "box", k), (("sensors", i, "box", k),)
    # what a sensor or the radiation refers to
    for i, s in enumerate(doc.get("sensors", [])):
        ref = {"residence_time": (("from", "factories"), ("to", "outlets")),
               "contact_count": (("body", "bodies"),)}.get(s["kind"], ())
        for key, sec in ref:
            for j, it in enumerate(doc.get(sec, [])):
                if it.get("name") == s[key]:
                    users = [("sensors", q, key) for q, x in enumerate(doc["sensors"])
                             if x.get(key) == s[key]]
                    yield (sec, j), tuple(users)
    th = doc.get("thermal")
    if isinstance(th, dict):
        sources = [("particles", i, f) for i, f in enumerate(doc.get("particles", []))] + \
                  [("factories", i, f) for i, f in enumerate(doc.get("factories", []))]
        mats = {f["material"] for _, _, f in sources}
        for sec, i, f in sources:
            if "temperature" in f:
                yield (sec, i, "temperature"), ((sec, i, "temperature"),)
        for m in mats:
            for k in ("thermal_conductivity", "heat_capacity") + \
                     (("emissivity",) if th.get("radiation") else ()):
                if k in doc["materials"][m]:
                    yield ("materials", m, k), (("materials", m, k),)
        if th.get("wall_conduction", True):
            for sec in ("walls", "bodies"):
                for w in doc.get(sec, []):
                    m = w["material"]
                    if "temperature" in w and "thermal_conductivity" in doc["materials"][m] \
                            and mats:
                        yield ("materials", m, "thermal_conductivity"), \
                            (("materials", m, "thermal_conductivity"),)
        if th.get("radiation") and "radiation_to" in th:
            yield ("thermal", "radiation_to"), (("thermal", "radiation_to"),)
            to = th["radiation_to"]
            for sec in ("walls", "bodies"):
                for j, w in enumerate(doc.get(sec, [])):
                    if w.get("name") == to and not _referenced_by_sensor(doc, sec, w["name"]):
                        yield (sec, j), (("thermal", "radiation_to"),)
                        yield (sec, j, "temperature"), (("thermal", "radiation_to"),)
            if to == "gas" and "gas" in th:
                yield ("thermal", "gas"), (("thermal", "radiation_to"),)
        gas = th.get("gas")
        if isinstance(gas, dict) and gas.get("model") == "axial_plug_flow":
            for k in _PLUG_FLOW_REQUIRED:
                if k in gas:
                    yield ("thermal", "gas", k), (("thermal", "gas", k),)
            for k in ("flow_area", "radius"):
                if k in gas:
                    yield ("thermal", "gas", k), (("thermal", "gas", "flow_area"),)


def _referenced_by_sensor(doc, sec, name) -> bool:
    return sec == "bodies" and any(s.get("body") == name for s in doc.get("sensors", []))


def material_references(doc) -> dict:
    refs: dict = {}
    for i, t in enumerate(doc.get("interactions", [])):
        for j, m in enumerate(t.get("pair", [])):
            refs.setdefault(m, []).append(("interactions", i, "pair", j))
    for sec in ("walls", "bodies", "particles", "factories"):
        for i, t in enumerate(doc.get(sec, [])):
            if "material" in t:
                refs.setdefault(t["material"], []).append((sec, i, "material"))
    return refs


def needed_pairs(doc) -> set:
    pm = []
    for sec in ("particles", "factories"):
        for f in doc.get(sec, []):
            if f["material"] not in pm:
                pm.append(f["material"])
    need = set()
    for i, a in enumerate(pm):
        for b in pm[i:]:
            need.add(frozenset((a, b)))
    for sec in ("walls", "bodies"):
        for w in doc.get(sec, []):
            for a in pm:
                need.add(frozenset((a, w["material"])))
    return need


# ---------------------------------------------------------------------------------- running
class CaseTimeout(BaseException):
    """Raised by the alarm; a BaseException so that no ``except Exception`` swallows it."""


@dataclass
class Outcome:
    rc: Any                       # the exit status, or "exception"/"timeout"
    message: str                  # stderr + stdout
    seconds: float
    exception: Optional[BaseException] = None
    problems: list = field(default_factory=list)


def write_case(case: Case, folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in case.files.items():
        p = folder / name
        if data is None:
            p.mkdir(parents=True, exist_ok=True)
        else:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(data)
    scene = folder / "scene.toml"
    scene.write_bytes(case.text)
    return scene


def run_case(case: Case, folder: Path, command: str = "check", limit: float = 5.0) -> Outcome:
    """Run ``taichi-dem <command>`` in-process on the case; judge the outcome."""
    import contextlib
    import faulthandler
    import io
    import signal
    import threading
    import time

    from taichi_dem.app import cli

    scene = write_case(case, folder)
    argv = [command, str(scene)]
    if command == "run":
        argv += ["--quiet", "--out", str(folder / "out")]
    out, err = io.StringIO(), io.StringIO()

    def alarm(signum, frame):
        raise CaseTimeout(f"{case.ident}: more than {limit:g} s")

    # the alarm interrupts Python code; a hang inside C (an allocation, a kernel) is ended by
    # faulthandler, which dumps every thread's stack and exits: a failed run, not a hung CI
    main_thread = threading.current_thread() is threading.main_thread()
    if main_thread:
        old = signal.signal(signal.SIGALRM, alarm)
        signal.setitimer(signal.ITIMER_REAL, limit)
    faulthandler.dump_traceback_later(max(60.0, 6 * limit), exit=True)
    t0 = time.perf_counter()
    exc = None
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = cli.main(argv)
    except SystemExit as e:
        rc = e.code
    except CaseTimeout as e:
        rc, exc = "timeout", e
    except BaseException as e:     # noqa: BLE001 - anything else would be a traceback
        rc, exc = "exception", e
    finally:
        faulthandler.cancel_dump_traceback_later()
        if main_thread:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)
    if not main_thread and time.perf_counter() - t0 > limit and exc is None:
        rc, exc = "timeout", CaseTimeout(f"{case.ident}: more than {limit:g} s")
    seconds = time.perf_counter() - t0
    message = err.getvalue() + out.getvalue()
    o = Outcome(rc, message, seconds, exc)
    o.problems = judge(case, scene, o)
    return o


def reported_key(message: str, file: str) -> Optional[str]:
    """The key of ``taichi-dem: FILE: KEY: reason`` (None when the message has no key)."""
    head = f"taichi-dem: {file}: "
    i = message.find(head)
    if i < 0:
        return None
    rest = message[i + len(head):]
    m = re.match(r"([A-Za-z0-9_.\[\]\-\"'\u00c0-\uffff]+): ", rest)
    return m.group(1) if m else None


def judge(case: Case, scene: Path, o: Outcome) -> list[str]:
    problems = []
    if o.exception is not None:
        problems.append(f"{o.rc}: {type(o.exception).__name__}: {o.exception}")
        return problems
    if o.rc != 2:
        problems.append(f"exit status {o.rc!r}, expected 2")
    if "Traceback" in o.message:
        problems.append("a traceback in the output")
    named = scene.parent / case.names_file if case.names_file else scene
    if named.name not in o.message:
        problems.append(f"the message does not name the file {named.name}")
    for frag in case.expect_fragments:
        if frag not in o.message:
            problems.append(f"the message lacks {frag!r}")
    if case.expect_keys:
        key = reported_key(o.message, str(named)) or reported_key(o.message, str(scene))
        if key is None:
            problems.append("the message names no key")
        elif not any(key_matches(key, e) for e in case.expect_keys):
            problems.append(f"the message names the key {key!r}, expected "
                            f"{' or '.join(case.expect_keys)}")
    return problems


PROBLEM_KINDS = ("traceback", "hang", "exit 0", "other exit", "message")


def problem_kind(o: Outcome) -> str:
    """What went wrong with a judged case: a Python exception (a traceback), a hang (past
    the limit), exit 0 (accepted: a silent wrong result), another exit status, or a message
    that names the wrong key, file or line."""
    if o.rc == "timeout":
        return "hang"
    if o.exception is not None or "Traceback" in o.message:
        return "traceback"
    if o.rc == 0:
        return "exit 0"
    if o.rc != 2:
        return "other exit"
    return "message"


def main(argv=None) -> int:
    import argparse
    import collections
    import shutil
    import tempfile
    import time

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--command", default="check", choices=["check", "run"])
    ap.add_argument("--limit", type=float, default=20.0, help="seconds per case")
    ap.add_argument("--show", type=int, default=50, help="failures to print")
    ap.add_argument("--category", action="append", help="only these categories")
    args = ap.parse_args(argv)
    fz = Fuzzer(base_scenes())
    if args.category:
        global WEIGHTS
        WEIGHTS = {c: w for c, w in WEIGHTS.items() if c in args.category}
    cases = fz.corpus(args.cases, args.seed)
    tmp = Path(tempfile.mkdtemp(prefix="scene_fuzz_"))
    counts: collections.Counter = collections.Counter()
    failed: collections.Counter = collections.Counter()
    kinds: collections.Counter = collections.Counter()     # traceback, hang, exit 0, ...
    slow = []
    shown = 0
    t0 = time.perf_counter()
    for n, case in enumerate(cases):
        o = run_case(case, tmp / f"c{n:05d}", args.command, args.limit)
        counts[case.category] += 1
        slow.append((o.seconds, case.ident))
        if o.problems:
            failed[case.category] += 1
            kinds[problem_kind(o)] += 1
            if shown < args.show:
                shown += 1
                print(f"FAIL {case.ident}\n    {'; '.join(o.problems)}\n    "
                      f"{o.message.strip()[:400]}", flush=True)
    shutil.rmtree(tmp, ignore_errors=True)
    print(f"\n{len(cases)} cases in {time.perf_counter() - t0:.1f} s; "
          f"{sum(failed.values())} failed")
    for c in CATEGORIES:
        if counts[c]:
            print(f"  {c:14s} {counts[c]:5d} cases, {failed[c]:4d} failed")
    print("problems:", ", ".join(f"{kinds[k]} {k}" for k in PROBLEM_KINDS))
    slow.sort(reverse=True)
    print("slowest:", ", ".join(f"{s:.2f}s {i}" for s, i in slow[:5]))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
