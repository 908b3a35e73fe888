"""The JSON Schema of every scene key, generated from the declarations (scene/keys.py): the
scene's own sections (scene/sections/), the effects' (``effects/*/settings.py``,
``thermal/settings.py``) and the mesh builders' parameters (geometry/builders.py).

Each key carries ``description``, ``default`` (SI), ``x-unit`` (the SI unit of its value;
"1" when dimensionless), ``x-dimension`` (the quantity it is, for the unit strings the loader
accepts, e.g. "15 mm"), ``x-effect`` where a section serves several effects, and its range
(``minimum`` / ``exclusiveMinimum`` ...). A quantity is a number (SI) or a string with a unit,
so its JSON type is ``["number", "string"]``: the range applies to numbers only, as JSON
Schema has no units. ``taichi-dem schema`` prints it. Plain Python (no Taichi).
"""
from __future__ import annotations

import json
import math
from typing import Any

from taichi_dem.geometry.builders import BUILDERS, COMMON, KINDS as BUILDER_KINDS, REQUIRED as BUILDER_REQUIRED

from .keys import REQUIRED, Key, Section, effect_sections, registered
from .units import DIMENSIONS, units_for

DIALECT = "https://json-schema.org/draft/2020-12/schema"


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


def key_schema(key: Key, sections: dict[str, Section], owner: Section) -> dict:
    """The JSON Schema of one key."""
    quantity = {"type": ["number", "string"]}
    if key.kind == "quantity":
        out: dict[str, Any] = dict(quantity)
    elif key.kind == "vector":
        out = {"type": "array", "items": quantity, "minItems": 3, "maxItems": 3}
    elif key.kind == "direction":
        out = {"type": "array", "items": {"type": ["number", "string"]}, "minItems": 3,
               "maxItems": 3}
    elif key.kind == "boolean":
        out = {"type": "boolean"}
    elif key.kind == "integer":
        out = {"type": "integer"}
    elif key.kind == "string":
        out = {"type": "string"}
    elif key.kind == "choice":
        out = {"enum": list(key.choices)}
    elif key.name in owner.nested and key.kind == "table":
        out = section_schema(owner.nested[key.name], sections)
    elif key.name in owner.nested:      # a number with a unit, or that table
        out = {"anyOf": [dict(quantity), section_schema(owner.nested[key.name], sections)]}
    elif key.kind == "table":
        out = {"type": "object"}
    elif key.kind == "tables":
        out = {"type": "array", "items": {"type": "object"}}
    else:
        out = {}
    if key.schema and key.name not in owner.nested:
        out.update(key.schema)
    if key.auto:
        out = {"anyOf": [out, {"const": "auto"}]}
    if key.kind in ("quantity", "integer"):
        target = out if "anyOf" not in out else out["anyOf"][0]
        if key.minimum is not None:
            target["exclusiveMinimum" if key.exclusive_minimum else "minimum"] = key.minimum
        if key.maximum is not None and math.isfinite(key.maximum):
            target["exclusiveMaximum" if key.exclusive_maximum else "maximum"] = key.maximum
    out["description"] = key.description
    if key.default is not None and key.default is not REQUIRED:
        out["default"] = _json_default(key.default)
    if key.unit or key.kind == "direction":
        out["x-unit"] = key.si_unit
        out["x-dimension"] = key.unit or "dimensionless"
    if key.effect:
        out["x-effect"] = key.effect
    if key.required:
        out["x-required"] = True
    return out


def section_schema(section: Section, sections: dict[str, Section]) -> dict:
    """The JSON Schema of one table: its keys, none other, the required ones named."""
    out = {"type": "object", "description": section.description,
           "properties": {k.name: key_schema(k, sections, section) for k in section.keys},
           "additionalProperties": False, "x-declared-in": section.owner}
    required = [k.name for k in section.keys if k.required]
    if required:
        out["required"] = required
    return out


def builder_schema() -> dict:
    """The mesh builders' parameters (geometry/builders.py), one schema per builder."""
    variants = []
    for name, b in BUILDERS.items():
        props: dict[str, Any] = {"builder": {"const": name, "description": b.description}}
        for p in b.params + COMMON:
            unit = BUILDER_KINDS[p.kind][0]
            entry: dict[str, Any] = {"description": p.description,
                                     "x-unit": "1" if unit == "-" else unit}
            if p.choices:
                entry["enum"] = list(p.choices)
            if p.default is not BUILDER_REQUIRED and p.default is not None:
                entry["default"] = _json_default(p.default)
            props[p.name] = entry
        for alias, target in b.aliases:
            props[alias] = {"description": f"alias of {target}"}
        required = ["builder"] + [p.name for p in b.params if p.default is BUILDER_REQUIRED]
        variants.append({"type": "object", "properties": props, "required": required,
                         "additionalProperties": False})
    return {"anyOf": variants}


# where each built-in top-level section is declared (an array of tables "x[]", named tables
# "x.*"); an effect's own sections (effects/catalog.py) are added as they are
_TOP = {"simulation": "simulation", "domain": "domain", "output": "output",
        "materials": "materials.*", "interactions": "interactions[]", "particles": "particles[]",
        "walls": "walls[]", "bodies": "bodies[]", "factories": "factories[]",
        "outlets": "outlets[]", "sensors": "sensors[]", "thermal": "thermal",
        "mobility": "mobility", "gas": "gas"}


def scene_schema() -> dict:
    """The JSON Schema of a scene file (every section the loader accepts)."""
    sections = _sections()
    props: dict[str, Any] = {}
    top = dict(_TOP)
    top.update({p: p for p in effect_sections() if p not in top})
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
    one = {"anyOf": [builder_schema(), {"type": "object", "required": ["file"]}]}
    mesh["anyOf"] = [one, {"type": "array", "items": one}]
    return {"$schema": DIALECT, "$id": "https://taichi-dem.org/schema/scene.json",
            "title": "taichi_dem scene", "type": "object", "properties": props,
            "required": ["domain"], "additionalProperties": False,
            "x-units": {d: {"si": si, "accepted": units_for(d)} for d, (si, _) in DIMENSIONS.items()}}


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
