"""The JSON Schema of every scene key, generated from the declarations (scene/keys.py): the
scene's own sections (scene/sections/), the effects' (``effects/*/settings.py``,
``thermal/settings.py``) and the mesh builders' parameters (geometry/builders.py).

Each key carries ``description``, ``default`` (SI), ``x-unit`` (the SI unit of its value;
"1" when dimensionless), ``x-dimension`` (the quantity it is, for the unit strings the loader
accepts, e.g. "15 mm"), ``x-effect`` where a section serves several effects, and its range.

The schema is as strict as the loader wherever JSON Schema can say it:

- a quantity is a number (SI) or a string with a unit, ``["number", "string"]``: a string
  must match ``pattern``, which accepts exactly the spellings the loader reads for the key's
  dimension (scene/units.py's tables; a minus only where the key allows one); a number lies
  within the key's range and within the SI magnitudes the loader accepts (0, or 1e-30 to
  1e30 either sign). A string's value after unit conversion cannot be checked (JSON Schema
  has no units): "1e40 m" matches the length pattern and the loader refuses it;
- vectors are three such quantities, directions three dimensionless ones, not all zero;
- an integer is a TOML integer: ``count = 3000.0`` is refused, as the loader refuses it.
  JSON does not tell 3000 from 3000.0, so the keyword is ``"type": "integer"`` with
  ``"x-toml-type": "integer"``; :func:`validator` checks it on data read from TOML, where
  the difference exists;
- no string holds a control character (Unicode category Cc: below U+0020, U+007F to U+009F),
  nor does a material's name, as the loader refuses them anywhere (sections/common.py);
  names name HDF5 groups: a wall's or body's is not empty, has no '/' and no blanks at its
  ends, a factory's, outlet's or sensor's is letters, digits, '_', '-', '.'; neither is '.'
  or '..';
- a table's conditional keys (a fill's file or count + region + radius, a factory's
  pattern, a sensor's kind, the plug-flow gas, the thermal switches) are ``allOf`` rules;
- mesh builder parameters are typed by their kind (geometry/registry.py): lengths, angles,
  counts, points, directions, choices, with the builders' own unit strings.

Checks that need more than one value's shape stay with the loader: cross-references (a
material a pair names, a sensor's factory), files (existence, content), geometry (a region
inside the domain, max above min, a fill that fits), sums and orders (mass fractions, schedule
times), physical sanity (the time step). ``tests/fuzz/test_schema_agrees.py`` lists them.

TOML has nan and inf, JSON does not: :func:`json_compatible` turns a TOML document into JSON
data, non-finite floats and dates into an object no key accepts. ``taichi-dem schema``
prints the schema. Plain Python (no Taichi).
"""
from __future__ import annotations

import datetime
import json
import math
import re
from typing import Any

from taichi_dem.geometry import registry as _builders
from taichi_dem.geometry.builders import (BUILDERS, COMMON, KINDS as BUILDER_KINDS,
                                         PARAMETER_RANGES, REQUIRED as BUILDER_REQUIRED)

from .keys import (REQUIRED, Key, Section, table_sections, equals, given, none_of, registered,
                   unless)
from .units import ABSOLUTE, DIMENSIONS, MAX_MAGNITUDE, MIN_MAGNITUDE, quantity_pattern, units_for

DIALECT = "https://json-schema.org/draft/2020-12/schema"

# no characters below U+0020 and no U+007F; "(?![\s\S])" ends the string (Python's "$"
# would also match before a final newline)
_END = r"(?![\s\S])"
_CONTROL = r"\x00-\x1f\x7f-\x9f"
# a string without control characters (sections/common.py refuses them in every string)
PRINTABLE = rf"(?![\s\S]*[{_CONTROL}])"
# a wall's or body's name (sections/common.py group_name): it names a results group, so no
# '/', not '.' or '..', no blanks at its ends, not empty
NAME_PATTERN = rf"^(?!\.{{1,2}}{_END})(?=\S)[^/{_CONTROL}]*(?<=\S){_END}"
# a factory's, outlet's or sensor's name (sections/process.py): letters, digits, _ - .
GROUP_NAME_PATTERN = rf"^(?!\.{{1,2}}{_END})[A-Za-z0-9_.-]+{_END}"
NON_BLANK_PATTERN = r"\S"                            # a path: not empty, not only spaces
AUTO_PATTERN = r"^\s*[aA][uU][tT][oO]\s*$"            # Key.read: value.strip().lower()
# what json_compatible puts for a TOML value JSON cannot hold (nan, inf, a date)
NOT_JSON = "x-toml-only"
# nonzero numbers smaller than this are refused (units.MIN_MAGNITUDE)
_TINY = {"type": "number", "exclusiveMinimum": -MIN_MAGNITUDE,
         "exclusiveMaximum": MIN_MAGNITUDE, "not": {"const": 0}}


def _printable(pattern: str) -> str:
    """``pattern`` that also refuses a string holding a control character."""
    if pattern.startswith("^"):
        return "^" + PRINTABLE + pattern[1:]
    return "^" + PRINTABLE + r"[\s\S]*?(?:" + pattern + ")"


def _only_printable(node: Any, seen: set) -> None:
    """Every string of ``node`` (a schema) without control characters, as the loader wants."""
    if id(node) in seen:
        return
    seen.add(id(node))
    if isinstance(node, dict):
        types = node.get("type", [])
        if "string" in (types if isinstance(types, list) else [types]):
            node["pattern"] = _printable(node.get("pattern", "^"))
        for v in node.values():
            _only_printable(v, seen)
    elif isinstance(node, list):
        for v in node:
            _only_printable(v, seen)


def _sections() -> dict[str, Section]:
    """Every declared section (importing the modules that declare them)."""
    from . import loader as _loader  # noqa: F401 (the scene's own and the effects' sections)
    return registered()


def _json_default(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_json_default(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


# ---------------------------------------------------------------------------------- values
def _sign(minimum, exclusive_minimum) -> str:
    if minimum is None or minimum < 0:
        return "any"
    return "positive" if (minimum > 0 or exclusive_minimum) else "nonnegative"


def quantity(dimension: str, minimum=None, maximum=None, exclusive_minimum=False,
             exclusive_maximum=False) -> dict:
    """A quantity of ``dimension``: a number in SI within the range (and the SI magnitudes
    the loader accepts) or a string with a unit of that dimension (``pattern``)."""
    if dimension in ABSOLUTE and minimum is None:
        minimum = 0.0                   # parse_quantity refuses values below absolute zero
    sign = _sign(minimum, exclusive_minimum)
    out: dict[str, Any] = {"type": ["number", "string"],
                           "pattern": quantity_pattern(dimension, sign)}
    if minimum is None:
        out["minimum"] = -MAX_MAGNITUDE
    else:
        out["exclusiveMinimum" if exclusive_minimum else "minimum"] = minimum
    if maximum is None or not math.isfinite(maximum) or maximum > MAX_MAGNITUDE:
        out["maximum"] = MAX_MAGNITUDE
    else:
        out["exclusiveMaximum" if exclusive_maximum else "maximum"] = maximum
    if minimum is None or minimum < MIN_MAGNITUDE:
        out["not"] = _TINY
    return out


def _key_quantity(key: Key, **override) -> dict:
    kw = dict(minimum=key.minimum, maximum=key.maximum, exclusive_minimum=key.exclusive_minimum,
              exclusive_maximum=key.exclusive_maximum)
    kw.update(override)
    return quantity(key.unit, **kw)


def vector(dimension: str) -> dict:
    """Three quantities of ``dimension`` (no range but the SI magnitudes)."""
    return {"type": "array", "items": quantity(dimension), "minItems": 3, "maxItems": 3}


def direction() -> dict:
    """Three dimensionless quantities, not all zero (normalised on load)."""
    zero = {"anyOf": [{"type": "number", "const": 0},
                      {"type": "string", "pattern": quantity_pattern("dimensionless", "zero")}]}
    return {"type": "array", "items": quantity("dimensionless"), "minItems": 3, "maxItems": 3,
            "not": {"items": zero}}


def integer(minimum=None, maximum=None) -> dict:
    """A TOML integer (3000, not 3000.0: ``x-toml-type``, checked by :func:`validator`)."""
    out: dict[str, Any] = {"type": "integer", "x-toml-type": "integer"}
    if minimum is not None:
        out["minimum"] = minimum
    if maximum is not None and math.isfinite(maximum):
        out["maximum"] = maximum
    return out


def _pair(first: dict, second: dict) -> dict:
    return {"type": "array", "prefixItems": [first, second], "items": False, "minItems": 2}


def _schedule(value: dict, start: dict) -> dict:
    """A value, or a schedule [[start time, value], ...] of at least one entry."""
    return {"anyOf": [value, {"type": "array", "minItems": 1, "items": _pair(start, value)}]}


def _radius(sections: dict[str, Section]) -> dict:
    """A positive length, or the distribution table { mean, std, min, max } (min and max
    required when std > 0)."""
    table = section_schema(sections["radius"], sections)
    positive = {"anyOf": [{"type": "number", "exclusiveMinimum": 0},
                          {"type": "string", "pattern": quantity_pattern("length", "positive")}]}
    table["allOf"] = [{"if": {"properties": {"std": positive}, "required": ["std"]},
                       "then": {"required": ["min", "max"]}}]
    return {"anyOf": [quantity("length", 0.0, exclusive_minimum=True), table]}


# structured values (keys of kind table / tables / any) that scene/sections reads itself:
# (section path, key) -> their schema
def _domain_corner() -> dict:
    """A corner of the domain: three lengths within MAX_COORDINATE of the origin (where the
    loader has that bound, sections/simulation.py)."""
    from taichi_dem.scene.sections import simulation
    out = vector("length")
    limit = getattr(simulation, "MAX_COORDINATE", None)
    if limit is not None:
        out["items"].update(minimum=-limit, maximum=limit)
    return out


_STRUCTURED = {
    ("particles[]", "radius"): _radius,
    ("factories[]", "radius"): _radius,
    ("factories[]", "sizes"): lambda _: {"type": "array", "minItems": 1, "items": _pair(
        quantity("length", 0.0, exclusive_minimum=True),
        quantity("dimensionless", 0.0, exclusive_minimum=True))},
    ("factories[]", "mass_rate"): lambda _: _schedule(quantity("mass_rate", 0.0),
                                                      quantity("time", 0.0)),
    ("bodies[].motion.rotate", "speed"): lambda _: _schedule(quantity("angular_speed"),
                                                             quantity("time", 0.0)),
    ("domain", "min"): lambda _: _domain_corner(),
    ("domain", "max"): lambda _: _domain_corner(),
}


_given, _none_of, _is, _unless = given, none_of, equals, unless


def _rules() -> dict[str, list[dict]]:
    """Conditional keys of a table, as the sections' code checks them: section path -> the
    ``allOf`` rules of its schema."""
    from taichi_dem.scene.sections.process import RANDOM_ONLY_KEYS, SENSOR_KEYS, SHEET_ONLY_KEYS
    fill_keys = ("count", "region", "radius")
    h5 = rf"\.[hH]5${_END}|\.[hH][dD][fF]5${_END}"
    nonzero = {"anyOf": [{"type": "number", "exclusiveMinimum": 0},
                         {"type": "string", "pattern": quantity_pattern("length", "positive")}]}
    sensors = []
    for kind, allowed in SENSOR_KEYS.items():
        need = {"mass_flow": ("plane",), "residence_time": ("from", "to"),
                "contact_count": ("body",), "contact_statistics": ()}[kind]
        sensors.append({"if": _is("kind", kind),
                        "then": {"propertyNames": {"enum": list(allowed)},
                                 "required": ["name", *need]}})
    sensors.append({"not": _given("radius", "box")})
    from taichi_dem.scene.sections.calibration import SCHEMA_RULES as calibration_rules
    return {
        "materials.*.calibration": calibration_rules,
        "particles[]": [
            {"if": _given("file"), "then": _none_of(*fill_keys),
             "else": {"required": list(fill_keys), **_none_of("frame")}},
            {"if": _given("frame"), "then": {"properties": {"file": {"pattern": h5}}}},
        ],
        "factories[]": [
            {"if": _is("pattern", "sheet"),
             "then": {"required": ["name", "material", "face", "velocity", "mass_rate", "radius"],
                      **_none_of(*RANDOM_ONLY_KEYS)},
             "else": {"required": ["name", "material", "region", "mass_rate"],
                      "allOf": [_none_of(*SHEET_ONLY_KEYS),
                                {"oneOf": [_given("radius"), _given("sizes")]}]}},
        ],
        "factories[].face": [
            {"anyOf": [{"required": ["point", "width", "depth"],
                        "propertyNames": {"enum": ["point", "width", "depth"]}},
                       {"required": ["min", "max"], "propertyNames": {"enum": ["min", "max"]}}]},
        ],
        "sensors[]": sensors,
        "region": [{"minProperties": 1, "maxProperties": 1}],
        "materials.*": [
            {"if": {"anyOf": [_given("surface_slope"), _given("microhardness")]},
             "then": {"required": ["surface_slope", "microhardness", "surface_roughness"],
                      "properties": {"surface_roughness": nonzero}}},
        ],
    }


# names: (section path, key) -> pattern
_NAMES = {("walls[]", "name"): NAME_PATTERN, ("bodies[]", "name"): NAME_PATTERN,
          ("factories[]", "name"): GROUP_NAME_PATTERN, ("outlets[]", "name"): GROUP_NAME_PATTERN,
          ("sensors[]", "name"): GROUP_NAME_PATTERN, ("output", "rrd"): NON_BLANK_PATTERN,
          ("output", "h5"): NON_BLANK_PATTERN}


def key_schema(key: Key, sections: dict[str, Section], owner: Section) -> dict:
    """The JSON Schema of one key."""
    make = _STRUCTURED.get((owner.path, key.name))
    structured = make(sections) if make is not None else None
    if structured is not None:
        out: dict[str, Any] = structured
    elif key.kind == "quantity":
        out = _key_quantity(key)
    elif key.kind == "vector":
        out = vector(key.unit)
    elif key.kind == "direction":
        out = direction()
    elif key.kind == "boolean":
        out = {"type": "boolean"}
    elif key.kind == "integer":
        out = integer(key.minimum, key.maximum)
    elif key.kind == "string":
        out = {"type": "string", "minLength": 1}
        if (owner.path, key.name) in _NAMES:
            out["pattern"] = _NAMES[(owner.path, key.name)]
    elif key.kind == "choice":
        out = {"enum": list(key.choices)}
    elif key.name in owner.nested and key.kind == "table":
        out = section_schema(owner.nested[key.name], sections)
    elif key.name in owner.nested:      # a number with a unit, or that table
        out = {"anyOf": [_key_quantity(key), section_schema(owner.nested[key.name], sections)]}
    elif key.kind == "table":
        out = {"type": "object"}
    elif key.kind == "tables":
        out = {"type": "array", "items": {"type": "object"}}
    else:
        out = {}
    if key.schema and structured is None and key.name not in owner.nested:
        out.update(key.schema)
    if key.auto:
        out = {"anyOf": [out, {"type": "string", "pattern": AUTO_PATTERN}]}
    out["description"] = key.description
    if key.default is not None and key.default is not REQUIRED:
        out["default"] = _json_default(key.default)
    if key.default_words:
        out["x-default"] = key.default_words        # (where another key changes it)
    if key.unit or key.kind == "direction":
        out["x-unit"] = key.si_unit
        out["x-dimension"] = key.unit or "dimensionless"
    if key.effect:
        out["x-effect"] = key.effect
    if key.required:
        out["x-required"] = True
    return out


def section_schema(section: Section, sections: dict[str, Section]) -> dict:
    """The JSON Schema of one table: its keys, none other, the required ones named, its
    conditional keys (``allOf``)."""
    out = {"type": "object", "description": section.description,
           "properties": {k.name: key_schema(k, sections, section) for k in section.keys},
           "additionalProperties": False, "x-declared-in": section.owner}
    required = [k.name for k in section.keys if k.required]
    if required:
        out["required"] = required
    rules = _rules().get(section.path)
    if section.schema_rules is not None:
        # a section's own (an effect's: thermal/settings.py, effects/*/settings.py)
        rules = (rules or []) + list(section.schema_rules())
    if rules:
        out["allOf"] = rules
    return out


# ---------------------------------------------------------------------------------- builders
def _builder_number(sign: str) -> str:
    body = r"(?:\d+\.?\d*|\.\d+)"
    exp = r"(?:[eE][-+]?\d+)?"
    if sign == "positive":
        return rf"\+?(?=[\d.]*[^\D0]){body}{exp}"
    if sign == "nonnegative":
        return rf"(?:\+?{body}|-(?:0+\.?0*|\.0+)){exp}"
    return rf"[-+]?{body}{exp}"


def builder_quantity_pattern(units, sign: str = "any") -> str:
    """The strings a builder parameter reads (geometry/registry.py ``_quantity``): a number
    and one of ``units`` spelled exactly ("" for a bare number)."""
    words = sorted((u for u in units if u), key=len, reverse=True)
    unit = r"\s*(?:" + "|".join(re.escape(u) for u in words) + ")" if words else ""
    bare = "" in units
    return rf"^\s*{_builder_number(sign)}{unit}{'?' if bare and unit else ''}\s*$"


def builder_param_schema(kind: str, choices=()) -> dict:
    """The JSON Schema of a builder parameter of ``kind`` (geometry/registry.py KINDS)."""
    lengths, angles = _builders._LENGTH_UNITS, _builders._ANGLE_UNITS_DEG
    if kind in ("length", "length0", "coord"):
        sign = {"length": "positive", "length0": "nonnegative", "coord": "any"}[kind]
        out: dict[str, Any] = {"type": ["number", "string"],
                               "pattern": builder_quantity_pattern(lengths, sign)}
        if kind == "length":
            out["exclusiveMinimum"] = 0
        elif kind == "length0":
            out["minimum"] = 0
        return out
    if kind == "angle":
        return {"type": ["number", "string"], "pattern": builder_quantity_pattern(angles)}
    if kind in ("count", "count0"):
        # the builders take a whole float too (4.0): registry._parse
        return {"type": "number", "multipleOf": 1, "minimum": 1 if kind == "count" else 0,
                "maximum": _builders.MAX_COUNT}
    if kind == "bool":
        return {"type": "boolean"}
    if kind == "choice":
        return {"enum": list(choices)}
    if kind == "point":
        item = {"type": ["number", "string"], "pattern": builder_quantity_pattern(lengths)}
        return {"type": "array", "items": item, "minItems": 3, "maxItems": 3}
    if kind == "direction":
        item = {"type": ["number", "string"], "pattern": builder_quantity_pattern({"": 1.0})}
        zero_text = r"^\s*[-+]?(?:0+\.?0*|\.0+)(?:[eE][-+]?\d+)?\s*$"
        zero = {"anyOf": [{"type": "number", "const": 0},
                          {"type": "string", "pattern": zero_text}]}
        return {"type": "array", "items": item, "minItems": 3, "maxItems": 3,
                "not": {"items": zero}}
    if kind == "factor":
        return {"type": "number", "exclusiveMinimum": 0}
    if kind == "path":
        return {"type": "string", "minLength": 1}
    raise AssertionError(kind)


def builder_schema() -> dict:
    """The mesh builders' parameters (geometry/builders.py), one schema per builder, each
    parameter typed by its kind."""
    variants = []
    for name, b in BUILDERS.items():
        props: dict[str, Any] = {"builder": {"const": name, "description": b.description}}
        for p in b.params + COMMON:
            unit = BUILDER_KINDS[p.kind][0]
            entry: dict[str, Any] = builder_param_schema(p.kind, p.choices)
            lo, hi, exclusive = PARAMETER_RANGES.get((name, p.name), (None, None, False))
            if lo is not None:
                entry.pop("minimum", None)
                entry["exclusiveMinimum" if exclusive else "minimum"] = lo
            if hi is not None:
                entry["exclusiveMaximum" if exclusive else "maximum"] = hi
            entry.update({"description": p.description, "x-unit": "1" if unit == "-" else unit,
                          "x-builder-kind": p.kind})
            if p.default is not BUILDER_REQUIRED and p.default is not None:
                entry["default"] = _json_default(p.default)
            props[p.name] = entry
        for alias, target in b.aliases:
            props[alias] = dict(props[target], description=f"alias of {target}")
        required = ["builder"] + [p.name for p in b.params if p.default is BUILDER_REQUIRED]
        if name == "file":          # { file = "part.stl" } needs no builder key
            required.remove("builder")
        variant = {"type": "object", "properties": props, "required": required,
                   "additionalProperties": False}
        for alias, target in b.aliases:
            variant.setdefault("allOf", []).append({"not": _given(alias, target)})
        if name == "file":
            variant["allOf"] = [{"if": {"not": _given("builder")},
                                 "then": {"propertyNames": {"not": {"const": "builder"}}}}]
        variants.append(variant)
    return {"anyOf": variants}


# where each built-in top-level section is declared (an array of tables "x[]", named tables
# "x.*"); an effect's own sections (scene/catalog.py) are added as they are
_TOP = {"simulation": "simulation", "domain": "domain", "output": "output",
        "materials": "materials.*", "interactions": "interactions[]", "particles": "particles[]",
        "walls": "walls[]", "bodies": "bodies[]", "factories": "factories[]",
        "outlets": "outlets[]", "sensors": "sensors[]"}


def scene_schema() -> dict:
    """The JSON Schema of a scene file (every section the loader accepts)."""
    sections = _sections()
    props: dict[str, Any] = {}
    top = dict(_TOP)
    top.update({p: p for p in table_sections() if p not in top})
    for name, path in top.items():
        s = section_schema(sections[path], sections)
        if path.endswith("[]"):
            props[name] = {"type": "array", "items": s, "description": s["description"]}
        elif path.endswith(".*"):
            props[name] = {"type": "object", "additionalProperties": s,
                           "description": s["description"]}
        else:
            props[name] = s
    mesh = props["bodies"]["items"]["properties"]["mesh"]
    mesh.pop("type", None)
    one = builder_schema()
    mesh["anyOf"] = [one, {"type": "array", "minItems": 1, "items": one}]
    props["materials"]["propertyNames"] = {"pattern": "^" + PRINTABLE}
    _only_printable(props, set())
    return {"$schema": DIALECT, "$id": "https://taichi-dem.org/schema/scene.json",
            "title": "taichi_dem scene", "type": "object", "properties": props,
            "required": ["domain"], "additionalProperties": False,
            "x-units": {d: {"si": si, "accepted": units_for(d)} for d, (si, _) in DIMENSIONS.items()}}


# ---------------------------------------------------------------------------------- checking
def json_compatible(value: Any) -> Any:
    """A TOML document (tomllib's data) as JSON data: tables, arrays, strings, booleans and
    numbers as they are; a nan, an inf or a date or time (TOML has them, JSON does not) as
    ``{NOT_JSON: "nan"}``, an object no key of the schema accepts, as the loader refuses
    them everywhere."""
    if isinstance(value, dict):
        return {k: json_compatible(v) for k, v in value.items()}
    if isinstance(value, list):
        return [json_compatible(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return {NOT_JSON: repr(value)}
    if isinstance(value, (datetime.date, datetime.time)):
        return {NOT_JSON: value.isoformat()}
    return value


def validator(schema: dict | None = None):
    """A ``jsonschema`` Draft 2020-12 validator of the scene schema whose "integer" is a
    TOML integer (a Python int; 3000.0 is a float, refused as the loader refuses it). Needs
    the ``jsonschema`` package (the test extras)."""
    import jsonschema

    base = jsonschema.Draft202012Validator
    checker = base.TYPE_CHECKER.redefine(
        "integer", lambda _, x: isinstance(x, int) and not isinstance(x, bool))
    cls = jsonschema.validators.extend(base, type_checker=checker)
    return cls(schema or scene_schema())


def every_key(schema: dict | None = None) -> list[tuple[str, dict]]:
    """(dotted path, schema) of every leaf key of the scene schema (for references, tests)."""
    schema = schema or scene_schema()
    out: list[tuple[str, dict]] = []

    def walk(node: dict, path: str) -> None:
        if node.get("type") == "array" and isinstance(node.get("items"), dict) and "properties" in node["items"]:
            return walk(node["items"], path + "[]")
        if isinstance(node.get("additionalProperties"), dict):
            return walk(node["additionalProperties"], path + ".NAME")
        props = node.get("properties")
        if props is None:
            out.append((path, node))
            return
        for k, v in props.items():
            walk(v, f"{path}.{k}" if path else k)

    for name, node in schema["properties"].items():
        walk(node, name)
    return out


def dumps() -> str:
    return json.dumps(scene_schema(), indent=2, ensure_ascii=False)
