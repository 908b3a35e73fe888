"""[materials.NAME.calibration]: what a material was calibrated against (issue 44).

A scene that claims a real material says what it was calibrated against: the record
``taichi-dem calibrate`` writes (its bench tests with their targets and the values achieved,
the calibrated parameters, the sphere size it holds for), given inline or as ``record``, the
calibrated_material.toml the command wrote. ``taichi-dem check`` prints it, and ``check`` and
``run`` note where the scene departs from it: another sphere size (another material), a
calibrated value the scene changes, or a record that missed its targets. A note, not an error:
a study of what the material's values move (``--set``) is a deliberate departure.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any, Optional

from ...errors import SceneError
from ..keys import Key, Section, register
from ..keys import suggest as _suggest
from ..keys import type_name as _type_name
from .common import control_character
from ..model import CalibratedValue, Calibration, CalibrationTest

def _number(what: str) -> dict:
    return {"type": "number", "description": what}


def _integer(what: str) -> dict:
    return {"type": "integer", "description": what}


def _text(what: str) -> dict:
    return {"type": "string", "description": what}


def _flag(what: str) -> dict:
    return {"type": "boolean", "description": what}


def _numbers(what: str) -> dict:
    return {"type": "array", "items": {"type": "number"}, "description": what}


def _value(what: str) -> dict:
    return {"anyOf": [{"type": "number"}, {"type": "string", "minLength": 1},
                      {"type": "boolean"}], "description": what}


def _pair(what: str) -> dict:
    return {"type": "array", "items": {"type": "string", "minLength": 1}, "minItems": 2,
            "maxItems": 2, "description": what}


def _strict(properties: dict, required=(), what: str = "") -> dict:
    out = {"type": "object", "properties": properties, "additionalProperties": False}
    if required:
        out["required"] = list(required)
    if what:
        out["description"] = what
    return out


# the schemas of a record's parts, as `taichi-dem calibrate` writes them (scene/schema.py:
# each property described; built afresh each time, as the schema's builder adds to what it is
# given). The loader checks a record against these same schemas (``_conform``).
def _test_item() -> dict:
    return _strict({
        "name": {**_text("the test's name"), "minLength": 1},
        "kind": _text("the bench test (angle_of_repose, ...)"),
        "unit": _text("the unit of its targets"),
        "scene": _text("its base scene"),
        "duration": _number("s simulated per run"),
        "measured": _numbers("the measured values"),
        "target": _number("the measured mean"),
        "target_sd": _number("the measured scatter (standard deviation)"),
        "achieved": _numbers("each verification run's value"),
        "achieved_mean": _number("the calibrated material's mean over fresh runs"),
        "achieved_sd": _number("their standard deviation"),
        "achieved_sem": _number("their mean's standard error"),
        "within_scatter": _flag("the mean within the measured scatter"),
        "reachable": _numbers("the response's reach inside the ranges"),
        "target_reachable": _flag("the target inside that reach"),
        "fit": _strict({"model": _text("constant, linear or quadratic"),
                        "points": _integer("design points fitted"),
                        "r2": _number("R^2"), "residual_sd": _number("the residuals' sd"),
                        "loo_rmse": _number("leave-one-out prediction error")},
                       what="the response surface fitted"),
    }, required=("name",))


def _parameter_item() -> dict:
    return _strict({
        "key": {**_text("the spec's scene key"), "minLength": 1},
        "range": _numbers("the range searched"),
        "value": _value("the calibrated value"),
        "prefer": _number("the value preferred among equal optima"),
        "pair": _pair("the interaction's pair of materials it sets"),
        "field": _text("the interaction's key it sets"),
        "material": _text("the material it sets"),
    }, required=("key", "value"))


def _factor_item() -> dict:
    return _strict({
        "name": _text("the factor's name"),
        "keys": {"type": "array", "items": {"type": "string", "minLength": 1}, "minItems": 1,
                 "description": "the spec's scene keys set together"},
        "levels": {"type": "array", "items": _value("a level"), "description": "its levels"},
        "value": _value("the chosen level"),
        "pairs": {"type": "array", "items": _pair("a pair"),
                  "description": "the interactions' pairs of materials they set"},
        "field": _text("the interactions' key they set"),
    }, required=("keys", "value"))


def _round_item() -> dict:
    return _strict({
        "round": _integer("the round's number"),
        "optimum": {"type": "object", "additionalProperties": _value("a value"),
                    "description": "the round's optimum, by spec key"},
        "passed": _flag("its verification passed"),
        "achieved_mean": _numbers("each test's achieved mean"),
        "achieved_sem": _numbers("their standard errors"),
    })


def _design() -> dict:
    return _strict({k: _integer(w) for k, w in (
        ("points", "Latin-hypercube points per level"), ("seed", "the hypercube's seed"),
        ("seeds", "placement seeds per point"), ("verify_seeds", "fresh seeds at the optimum"),
        ("rounds", "rounds at most"), ("augment", "points added at an edge"),
        ("design_points", "points run"))} | {
        "kind": _text("latin_hypercube or full_factorial"),
        "levels": {"type": "array", "items": {"type": "integer"},
                   "description": "full factorial: levels per parameter"},
        "timeout": _number("s per run")}, what="the design of experiments")


# the keys of a record as ``taichi-dem calibrate`` writes it
RECORD_KEYS = ("date", "command", "spec", "sphere_radius", "within_scatter", "design",
               "parameters", "factors", "tests", "rounds")

CALIBRATION = register(Section("materials.*.calibration", "What the material was calibrated "
                               "against: the record `taichi-dem calibrate` writes, inline or "
                               "as the file it wrote (`record`)", (
    Key("record", "string", "a calibrated_material.toml written by `taichi-dem calibrate` "
        "(relative to the scene): its [materials.NAME.calibration] is this material's record",
        default=None),
    Key("material", "string", "with record: the material's name in that file (default: this "
        "material's)", default=None),
    Key("against", "string", "what it was calibrated against, in words (a calibration made by "
        "hand: the tests, targets and values achieved)", default=None),
    Key("date", "string", "when it was calibrated", default=None),
    Key("command", "string", "the command that calibrated it", default=None),
    Key("spec", "string", "the calibration spec it ran", default=None),
    Key("sphere_radius", "any", "the sphere radii (m) it holds for: another size is another "
        "material", default=None, schema={"type": "array", "minItems": 1, "items": {
            "type": "number", "exclusiveMinimum": 0}}),
    Key("within_scatter", "boolean", "every test's achieved mean within the measured scatter",
        default=None),
    Key("design", "table", "the design of experiments it ran", default=None, schema=_design()),
    Key("parameters", "tables", "the calibrated parameters: { key, value, range, pair, field, ... }",
        default=None, schema={"type": "array", "items": _parameter_item()}),
    Key("factors", "tables", "the calibrated choices: { keys, levels, value, pairs, field, ... }",
        default=None, schema={"type": "array", "items": _factor_item()}),
    Key("tests", "tables", "the bench tests: { name, unit, target, target_sd, achieved_mean, "
        "achieved_sd, achieved_sem, within_scatter, ... }", default=None,
        schema={"type": "array", "items": _test_item()}),
    Key("rounds", "tables", "the rounds of the sequential design", default=None,
        schema={"type": "array", "items": _round_item()}),
), owner=__name__))

# the schema's rule for the table (scene/schema.py _rules): it says what it was calibrated
# against, and a record file is not mixed with an inline record
SCHEMA_RULES = [
    {"anyOf": [{"required": ["record"]}, {"required": ["against"]}, {"required": ["tests"]}]},
    {"if": {"required": ["record"]},
     "then": {"not": {"anyOf": [{"required": [k]} for k in RECORD_KEYS]}},
     "else": {"not": {"required": ["material"]}}},
]


class CalibrationSection:
    """Read by the loader's parser with the materials (MaterialSections)."""

    def parse_calibration(self, value: Any, key: str, material: str) -> Calibration:
        """[materials.NAME.calibration]: the record, inline or from ``record``."""
        t = self.table(value, key, "a table ([materials.NAME.calibration])")
        CALIBRATION.check(t, self.source, key)
        plain = CALIBRATION.read(t, self.source, key)
        for k in ("record", "material", "against", "date", "command", "spec"):
            if k in plain and not plain[k].strip():
                raise self.err(f"{key}.{k}", "must not be empty")
        if not any(k in t for k in ("record", "against", "tests")):
            raise self.err(key, "says nothing of what the material was calibrated against: give "
                                "record (the calibrated_material.toml `taichi-dem calibrate` "
                                "wrote), tests (its record inline) or against (in words)")
        if "record" in t:
            inline = [k for k in RECORD_KEYS if k in t]
            if inline:
                raise self.err(f"{key}.{inline[0]}", "with record the record comes from that "
                                                     "file: give it there, or drop record")
            return self._record_file(plain, key, material)
        if "material" in t:
            raise self.err(f"{key}.material", "names the material in a record file: only "
                                              "with record")
        return self._record(t, key, self.source, plain.get("against", ""))

    def _record_file(self, plain: dict, key: str, material: str) -> Calibration:
        path = Path(plain["record"]).expanduser()
        if not path.is_absolute():
            path = self.base_dir / path
        name = plain.get("material", material)
        try:
            doc = tomllib.loads(path.read_text(encoding="utf-8-sig"))
        except FileNotFoundError:
            raise self.err(f"{key}.record", f"file not found: {path}") from None
        except (OSError, UnicodeDecodeError) as e:
            raise self.err(f"{key}.record", f"cannot read {path}: {e}") from None
        except tomllib.TOMLDecodeError as e:
            raise self.err(f"{key}.record", f"cannot read {path}: not TOML ({e})") from None
        rec = doc.get("materials", {}).get(name, {}) if isinstance(doc.get("materials"), dict) \
            else {}
        rec = rec.get("calibration") if isinstance(rec, dict) else None
        if not isinstance(rec, dict):
            raise self.err(f"{key}.record", f"{path} holds no [materials.{name}.calibration] "
                                            "table (the record `taichi-dem calibrate` writes)")
        where = f"{path}: materials.{name}.calibration"
        unknown = [k for k in rec if k not in RECORD_KEYS]
        if unknown:
            raise self.err(f"{key}.record", f"{where}.{unknown[0]}: the file holds an unknown "
                                            f"record key (known: {', '.join(RECORD_KEYS)})")
        # the file's own values are checked as an inline record would be, named by the file
        scene_source, self.source = self.source, str(path)
        try:
            CALIBRATION.read(rec, self.source, f"materials.{name}.calibration")
            return self._record(rec, f"materials.{name}.calibration", self.source,
                                plain.get("against", ""))
        finally:
            self.source = scene_source

    def _record(self, t: dict, key: str, source: str, against: str) -> Calibration:
        radii = ()
        if "sphere_radius" in t:
            v = t["sphere_radius"]
            if not isinstance(v, list) or not v:
                raise self.err(f"{key}.sphere_radius", f"expected an array of radii (m), got "
                                                       f"{_type_name(v)}")
            radii = tuple(self._positive_number(x, f"{key}.sphere_radius[{i}]")
                          for i, x in enumerate(v))
        # the structured parts against the schemas the scene schema publishes for them
        for name in ("design", "parameters", "factors", "tests", "rounds"):
            if name in t:
                self._conform(t[name], CALIBRATION[name].schema, f"{key}.{name}")
        tests = tuple(CalibrationTest(
            name=x["name"], unit=x.get("unit", ""), scene=x.get("scene", ""),
            runs=len(x.get("achieved", [])), within_scatter=x.get("within_scatter"),
            **{k: float(x[k]) for k in ("target", "target_sd", "achieved_mean", "achieved_sd",
                                        "achieved_sem") if k in x})
            for x in t.get("tests", []))
        values = [CalibratedValue(key=x["key"], value=x["value"],
                                  pair=tuple(x["pair"]) if "pair" in x else None,
                                  field=x.get("field", ""), material=x.get("material", ""))
                  for x in t.get("parameters", [])]
        for x in t.get("factors", []):
            pairs = [tuple(q) for q in x.get("pairs", [])]
            pairs = (pairs + [None] * len(x["keys"]))[:len(x["keys"])]
            values += [CalibratedValue(key=k, value=x["value"], pair=q,
                                       field=x.get("field", "") if q else "")
                       for k, q in zip(x["keys"], pairs)]
        return Calibration(source=source, against=against, date=t.get("date", ""),
                           command=t.get("command", ""), spec=t.get("spec", ""),
                           sphere_radius=radii, within_scatter=t.get("within_scatter"),
                           tests=tests, values=tuple(values))

    def _positive_number(self, v: Any, key: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.err(key, f"expected a finite number, got {_type_name(v)}")
        if not v > 0:
            raise self.err(key, f"must be > 0, got {v:g}")
        return float(v)

    def _conform(self, v: Any, schema: dict, key: str) -> None:
        """``v`` as ``schema`` (the subset of JSON Schema the record's parts use: type, anyOf,
        items, minItems, maxItems, minLength, properties, required, additionalProperties)
        allows it, or a SceneError naming ``key`` and the reason: the loader and the published
        schema agree by construction."""
        if "anyOf" in schema:
            for option in schema["anyOf"]:
                try:
                    self._conform(v, option, key)
                    return
                except SceneError:
                    continue
            kinds = " or ".join(_WORDS[o.get("type", "")] for o in schema["anyOf"])
            raise self.err(key, f"expected {kinds}, got {_type_name(v)}")
        kind = schema.get("type")
        ok = {"number": lambda x: (not isinstance(x, bool) and isinstance(x, (int, float))
                                   and math.isfinite(x)),
              "integer": lambda x: isinstance(x, int) and not isinstance(x, bool),
              "string": lambda x: isinstance(x, str), "boolean": lambda x: isinstance(x, bool),
              "object": lambda x: isinstance(x, dict), "array": lambda x: isinstance(x, list)}
        if kind is not None and not ok[kind](v):
            word = ("an array of tables" if kind == "array" and
                    schema.get("items", {}).get("type") == "object" else _WORDS[kind])
            raise self.err(key, f"expected {word}, got {_type_name(v)}")
        if kind == "string":
            if len(v) < schema.get("minLength", 0):
                raise self.err(key, "must not be empty")
            char = control_character(v)
            if char:
                raise self.err(key, f"contains the control character {char}")
        if kind == "array":
            if not schema.get("minItems", 0) <= len(v) <= schema.get("maxItems", len(v)):
                raise self.err(key, f"expected {schema.get('minItems', 0)}"
                               + (f" to {schema['maxItems']}" if "maxItems" in schema and
                                  schema["maxItems"] != schema.get("minItems") else "")
                               + f" items, got {len(v)}")
            for i, x in enumerate(v):
                self._conform(x, schema.get("items", {}), f"{key}[{i}]")
        if kind == "object":
            props = schema.get("properties", {})
            extra = schema.get("additionalProperties", True)
            for k, x in v.items():
                if k in props:
                    self._conform(x, props[k], f"{key}.{k}")
                elif extra is False:
                    raise self.err(f"{key}.{k}", f"unknown key '{k}'; {_suggest(k, props)}"
                                                 f"allowed keys here: {', '.join(props)}")
                elif isinstance(extra, dict):
                    self._conform(x, extra, f"{key}.{k}")
            for k in schema.get("required", ()):
                if k not in v:
                    raise self.err(f"{key}.{k}", "required key is missing")


_WORDS = {"number": "a finite number", "integer": "an integer", "string": "a string",
          "boolean": "true or false", "object": "a table", "array": "an array", "": "a value"}


# -------------------------------------------------------------------------------- reports
def _mm(r: float) -> str:
    return f"{2e3 * r:.4g} mm"


def _pm(mean: Optional[float], sd: Optional[float], unit: str) -> str:
    if mean is None:
        return "?"
    return f"{mean:.4g}" + (f" +- {sd:.2g}" if sd is not None else "") + (f" {unit}" if unit else "")


def _calibrated(scene) -> list:
    """(name, Calibration) of each material of ``scene`` with a calibration record."""
    return [(name, m.calibration) for name, m in scene.materials.items()
            if m.calibration is not None]


def describe_calibration(scene) -> list[str]:
    """The lines ``taichi-dem check`` prints for each material with a calibration record."""
    lines = []
    for name, c in _calibrated(scene):
        head = f"material {name}: calibrated"
        if c.date:
            head += f" {c.date}"
        if c.command:
            head += f" by `{c.command}`"
        lines.append(head + (f" (record: {c.source})" if c.source != scene.source else ""))
        if c.against:
            lines.append(f"  against: {c.against}")
        for t in c.tests:
            verdict = ("" if t.within_scatter is None else
                       " -> within the measured scatter" if t.within_scatter else
                       " -> NOT within the measured scatter")
            runs = f" ({t.runs} runs" + (f", standard error {t.achieved_sem:.2g}"
                                         if t.achieved_sem is not None else "") + ")" if t.runs else ""
            lines.append(f"  test {t.name}" + (f" ({t.scene})" if t.scene else "") +
                         f": target {_pm(t.target, t.target_sd, t.unit)}, achieved "
                         f"{_pm(t.achieved_mean, t.achieved_sd, t.unit)}{runs}{verdict}")
        for v in c.values:
            where = (f"{v.pair[0]}-{v.pair[1]} {v.field}" if v.pair and v.field else v.key)
            lines.append(f"  calibrated {where} = {v.value!r}")
        if c.sphere_radius:
            lines.append("  for spheres of diameter " + ", ".join(_mm(r) for r in c.sphere_radius)
                         + " only (another size is another material)")
    return lines


def calibration_notes(scene) -> list[tuple[str, str]]:
    """(key, reason) for each way the scene departs from a material's calibration record:
    a record that missed its targets, spheres of another size, a calibrated value changed."""
    notes = []
    for name, c in _calibrated(scene):
        key = f"materials.{name}.calibration"
        if c.within_scatter is False:
            notes.append((key, "the record says the calibration missed a target by more than "
                               "its measured scatter: the material is not calibrated"))
        if c.sphere_radius:
            radii = set()
            for f in list(scene.fills) + list(scene.factories):
                if f.material != name:
                    continue
                for r in _radii_of(f):
                    radii.add(round(r, 9))
            other = sorted(r for r in radii
                           if not any(abs(r - c_r) <= 0.01 * c_r for c_r in c.sphere_radius))
            if other:
                notes.append((key, "calibrated for spheres of diameter "
                              + ", ".join(_mm(r) for r in c.sphere_radius) + "; this scene's "
                              + ", ".join(_mm(r) for r in other) + " spheres are another "
                              "material until calibrated at their size (taichi-dem calibrate)"))
        for v in c.values:
            if not (v.pair and v.field):
                continue
            inter = scene.interactions.get(frozenset(v.pair))
            if inter is None:
                continue
            attr = {"model": "rolling_model"}.get(v.field, v.field)
            given = getattr(inter, attr, None)
            if given is None:
                continue
            same = (given == v.value if isinstance(v.value, str) or isinstance(given, str)
                    else isinstance(v.value, (int, float)) and
                    math.isclose(float(given), float(v.value), rel_tol=1e-9, abs_tol=1e-12))
            if not same:
                notes.append((key, f"calibrated {v.pair[0]}-{v.pair[1]} {v.field} = "
                                   f"{v.value!r}, and the scene gives {given!r}: the "
                                   "calibration does not hold for it"))
    return notes


def _radii_of(fill) -> list[float]:
    """The sphere radii (m) a fill or factory places: its constant radius, its size mix, or
    the mean of a distribution."""
    if getattr(fill, "sizes", None):
        return [r for r, _ in fill.sizes]
    if getattr(fill, "radii", None) is not None:
        import numpy as np
        return [float(r) for r in np.unique(np.round(fill.radii, 9))[:20]]
    if fill.radius is not None:
        return [fill.radius.mean]
    return []
