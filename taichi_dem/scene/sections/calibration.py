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

from ..keys import Key, Section, register
from ..keys import type_name as _type_name
from ..model import CalibratedValue, Calibration, CalibrationTest

def _number(what: str) -> dict:
    return {"type": "number", "description": what}


def _text(what: str) -> dict:
    return {"type": "string", "description": what}


def _value(what: str) -> dict:
    return {"type": ["number", "string", "boolean"], "description": what}


def _pair(what: str) -> dict:
    return {"type": "array", "items": {"type": "string", "minLength": 1}, "minItems": 2,
            "maxItems": 2, "description": what}


# the schemas of a record's entries (scene/schema.py: each property described; built afresh
# each time, as the schema's builder adds to what it is given)
def _test_item() -> dict:
    return {"type": "object", "required": ["name"], "properties": {
        "name": {**_text("the test's name"), "minLength": 1},
        "unit": _text("the unit of its targets"),
        "scene": _text("its base scene"),
        "target": _number("the measured mean"),
        "target_sd": _number("the measured scatter (standard deviation)"),
        "achieved_mean": _number("the calibrated material's mean over fresh runs"),
        "achieved_sd": _number("their standard deviation"),
        "achieved_sem": _number("their mean's standard error"),
        "within_scatter": {"type": "boolean", "description": "the mean within the scatter"},
        "achieved": {"type": "array", "items": {"type": "number"},
                     "description": "each run's value"}}}


def _parameter_item() -> dict:
    return {"type": "object", "required": ["key", "value"], "properties": {
        "key": {**_text("the spec's scene key"), "minLength": 1},
        "value": _value("the calibrated value"),
        "pair": _pair("the interaction's pair of materials it sets"),
        "field": _text("the interaction's key it sets"),
        "material": _text("the material it sets")}}


def _factor_item() -> dict:
    return {"type": "object", "required": ["keys", "value"], "properties": {
        "keys": {"type": "array", "items": {"type": "string", "minLength": 1}, "minItems": 1,
                 "description": "the spec's scene keys set together"},
        "value": _value("the chosen level"),
        "pairs": {"type": "array", "items": _pair("a pair"),
                  "description": "the interactions' pairs of materials they set"},
        "field": _text("the interactions' key they set")}}


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
    Key("design", "table", "the design of experiments it ran", default=None),
    Key("parameters", "tables", "the calibrated parameters: { key, value, range, pair, field }",
        default=None, schema={"type": "array", "items": _parameter_item()}),
    Key("factors", "tables", "the calibrated choices: { keys, levels, value, pairs, field }",
        default=None, schema={"type": "array", "items": _factor_item()}),
    Key("tests", "tables", "the bench tests: { name, unit, target, target_sd, achieved_mean, "
        "achieved_sd, achieved_sem, within_scatter, ... }", default=None,
        schema={"type": "array", "items": _test_item()}),
    Key("rounds", "tables", "the rounds of the sequential design", default=None),
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
            radii = tuple(self._number(x, f"{key}.sphere_radius[{i}]", positive=True)
                          for i, x in enumerate(v))
        for k in ("design",):
            if k in t:
                self.table(t[k], f"{key}.{k}")
        for k in ("rounds",):
            if k in t:
                self._tables(t[k], f"{key}.{k}")
        tests = tuple(self._test(x, f"{key}.tests[{i}]")
                      for i, x in enumerate(self._tables(t.get("tests", []), f"{key}.tests")))
        values = [self._parameter(x, f"{key}.parameters[{i}]")
                  for i, x in enumerate(self._tables(t.get("parameters", []), f"{key}.parameters"))]
        for i, x in enumerate(self._tables(t.get("factors", []), f"{key}.factors")):
            values += self._factor(x, f"{key}.factors[{i}]")
        return Calibration(source=source, against=against, date=t.get("date", ""),
                           command=t.get("command", ""), spec=t.get("spec", ""),
                           sphere_radius=radii, within_scatter=t.get("within_scatter"),
                           tests=tests, values=tuple(values))

    # -- the record's parts ----------------------------------------------------------------
    def _tables(self, v: Any, key: str) -> list:
        if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
            raise self.err(key, f"expected an array of tables, got {_type_name(v)}")
        return v

    def _number(self, v: Any, key: str, positive: bool = False) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.err(key, f"expected a finite number, got {_type_name(v)}")
        if positive and not v > 0:
            raise self.err(key, f"must be > 0, got {v:g}")
        return float(v)

    def _string(self, t: dict, k: str, key: str, required: bool = False) -> str:
        if k not in t:
            if required:
                raise self.err(f"{key}.{k}", "required key is missing")
            return ""
        if not isinstance(t[k], str) or (required and not t[k]):
            raise self.err(f"{key}.{k}", f"expected a string, got {_type_name(t[k])}")
        return t[k]

    def _value(self, v: Any, key: str):
        if isinstance(v, (bool, str)):
            return v
        return self._number(v, key)

    def _pair(self, v: Any, key: str) -> tuple[str, str]:
        if (not isinstance(v, list) or len(v) != 2
                or not all(isinstance(x, str) and x for x in v)):
            raise self.err(key, f"expected two material names, got {_type_name(v)}")
        return (v[0], v[1])

    def _test(self, t: dict, key: str) -> CalibrationTest:
        name = self._string(t, "name", key, required=True)
        nums = {k: self._number(t[k], f"{key}.{k}") for k in
                ("target", "target_sd", "achieved_mean", "achieved_sd", "achieved_sem") if k in t}
        runs = 0
        if "achieved" in t:
            if not isinstance(t["achieved"], list):
                raise self.err(f"{key}.achieved", f"expected an array of numbers, got "
                                                  f"{_type_name(t['achieved'])}")
            runs = len([self._number(x, f"{key}.achieved[{i}]")
                        for i, x in enumerate(t["achieved"])])
        within = t.get("within_scatter")
        if within is not None and not isinstance(within, bool):
            raise self.err(f"{key}.within_scatter", f"expected true or false, got "
                                                    f"{_type_name(within)}")
        return CalibrationTest(name=name, unit=self._string(t, "unit", key),
                               scene=self._string(t, "scene", key), runs=runs,
                               within_scatter=within, **nums)

    def _parameter(self, t: dict, key: str) -> CalibratedValue:
        k = self._string(t, "key", key, required=True)
        if "value" not in t:
            raise self.err(f"{key}.value", "required key is missing")
        pair = self._pair(t["pair"], f"{key}.pair") if "pair" in t else None
        return CalibratedValue(key=k, value=self._value(t["value"], f"{key}.value"), pair=pair,
                               field=self._string(t, "field", key),
                               material=self._string(t, "material", key))

    def _factor(self, t: dict, key: str) -> list[CalibratedValue]:
        keys = t.get("keys")
        if (not isinstance(keys, list) or not keys
                or not all(isinstance(x, str) and x for x in keys)):
            raise self.err(f"{key}.keys", f"expected an array of scene keys, got "
                                          f"{_type_name(keys)}")
        if "value" not in t:
            raise self.err(f"{key}.value", "required key is missing")
        pairs: list[Optional[tuple]] = [None] * len(keys)
        if "pairs" in t:
            if not isinstance(t["pairs"], list):
                raise self.err(f"{key}.pairs", f"expected an array of pairs, got "
                                               f"{_type_name(t['pairs'])}")
            got = [self._pair(p, f"{key}.pairs[{i}]") for i, p in enumerate(t["pairs"])]
            pairs = (got + pairs)[:len(keys)]
        field_ = self._string(t, "field", key)
        value = self._value(t["value"], f"{key}.value")
        return [CalibratedValue(key=k, value=value, pair=p, field=field_ if p else "")
                for k, p in zip(keys, pairs)]


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
