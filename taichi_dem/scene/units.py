"""Quantity strings -> SI floats, table-driven (no pint).

A scene value is either a TOML number, taken as already SI, or a string ``"<number> <unit>"``
such as ``"13 t/h"``, ``"10 rpm"``, ``"150 C"``, ``"15 mm"``. :func:`parse_quantity` converts it
to SI for the dimension the key expects; anything else is a :class:`~taichi_dem.scene.SceneError`
naming the file, the key and what was wrong.
"""
from __future__ import annotations

import math
import re
from typing import Any

from ..errors import SceneError

# dimension -> (SI unit, phrase used in messages)
DIMENSIONS: dict[str, tuple[str, str]] = {
    "dimensionless": ("1", "a dimensionless number"),
    "length": ("m", "a length"),
    "time": ("s", "a time"),
    "speed": ("m/s", "a speed"),
    "angular_speed": ("rad/s", "an angular speed"),
    "mass": ("kg", "a mass"),
    "mass_rate": ("kg/s", "a mass flow rate"),
    "density": ("kg/m^3", "a density"),
    "pressure": ("Pa", "a pressure (or modulus)"),
    "acceleration": ("m/s^2", "an acceleration"),
    "angle": ("rad", "an angle"),
    "force": ("N", "a force"),
    "torque": ("N m", "a torque"),
    "power": ("W", "a power"),
    "energy": ("J", "an energy"),
    "viscosity": ("Pa s", "a dynamic viscosity"),
    "area": ("m^2", "an area"),
    "specific_energy": ("J/kg", "a specific energy (e.g. a latent heat)"),
}

# Nonzero SI values outside this range are refused: no DEM quantity comes near them, and the
# derived figures (a Hertz contact time is (m^2 / (R E^2 v))^(1/5)) would overflow or underflow
# to a time step of 0 s.
MIN_MAGNITUDE = 1e-30
MAX_MAGNITUDE = 1e30

_RPM = 2.0 * math.pi / 60.0
_DEG = math.pi / 180.0

# unit (normalised: no spaces, no '^', '²'->'2', '³'->'3', '·'->'*') -> (dimension, factor, offset)
# SI value = number * factor + offset
_UNITS: dict[str, tuple[str, float, float]] = {}


def _add(dimension: str, table: dict[str, float], offset: float = 0.0) -> None:
    for unit, factor in table.items():
        assert unit not in _UNITS, unit
        _UNITS[unit] = (dimension, factor, offset)


_add("dimensionless", {"%": 0.01, "1": 1.0})
_add("length", {"m": 1.0, "km": 1e3, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6,
                "μm": 1e-6})
_add("time", {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6, "min": 60.0,
              "h": 3600.0, "d": 86400.0})
_add("speed", {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "m/min": 1.0 / 60.0,
               "km/h": 1.0 / 3.6})
_add("angular_speed", {"rad/s": 1.0, "rpm": _RPM, "rev/min": _RPM, "1/min": _RPM,
                       "rev/s": 2.0 * math.pi, "rps": 2.0 * math.pi, "deg/s": _DEG,
                       "°/s": _DEG, "1/s": 1.0, "s-1": 1.0})
_add("mass", {"kg": 1.0, "g": 1e-3, "mg": 1e-6, "t": 1e3})
_add("mass_rate", {"kg/s": 1.0, "kg/min": 1.0 / 60.0, "kg/h": 1.0 / 3600.0,
                   "g/s": 1e-3, "t/s": 1e3, "t/min": 1e3 / 60.0, "t/h": 1e3 / 3600.0,
                   "t/d": 1e3 / 86400.0})
_add("density", {"kg/m3": 1.0, "g/cm3": 1e3, "g/ml": 1e3, "g/mL": 1e3, "kg/l": 1.0,
                 "kg/L": 1.0, "t/m3": 1e3, "kg/dm3": 1e3})
_add("pressure", {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "bar": 1e5, "mbar": 1e2,
                  "N/m2": 1.0, "N/mm2": 1e6})
_add("acceleration", {"m/s2": 1.0, "mm/s2": 1e-3, "cm/s2": 1e-2})
_add("angle", {"rad": 1.0, "deg": _DEG, "°": _DEG, "mrad": 1e-3})
_add("force", {"N": 1.0, "kN": 1e3, "MN": 1e6, "mN": 1e-3})
_add("torque", {"Nm": 1.0, "N*m": 1.0, "kNm": 1e3, "kN*m": 1e3, "mNm": 1e-3, "mN*m": 1e-3})
_add("power", {"W": 1.0, "kW": 1e3, "MW": 1e6, "mW": 1e-3})
_add("energy", {"J": 1.0, "kJ": 1e3, "MJ": 1e6, "Wh": 3600.0, "kWh": 3.6e6})
_add("viscosity", {"Pas": 1.0, "Pa*s": 1.0, "mPas": 1e-3, "mPa*s": 1e-3, "cP": 1e-3})
_add("area", {"m2": 1.0, "cm2": 1e-4, "mm2": 1e-6})
_add("specific_energy", {"J/kg": 1.0, "kJ/kg": 1e3, "MJ/kg": 1e6})

_LOWER: dict[str, list[str]] = {}
for _u in _UNITS:
    _LOWER.setdefault(_u.lower(), []).append(_u)

# the dimensions whose SI values are never negative (an absolute temperature): a value below
# 0 is refused, and a bare number or a unit without offset takes no minus
ABSOLUTE: set[str] = set()


def add_dimension(dimension: str, si: str, phrase: str, spellings: tuple, *,
                  absolute: bool = False) -> None:
    """A dimension an effect brings (the heat transfer's temperature): its SI unit, the phrase
    of messages, its ``spellings`` ((``{unit: factor}``, offset), ...: SI value = number x
    factor + offset) and whether its SI values are never negative. Declared once, before
    the keys that use it; a second declaration of the same is a no-op."""
    if dimension in DIMENSIONS:
        assert DIMENSIONS[dimension] == (si, phrase), dimension
        return
    DIMENSIONS[dimension] = (si, phrase)
    for table, offset in spellings:
        _add(dimension, table, offset)
        for unit in table:
            _LOWER.setdefault(unit.lower(), []).append(unit)
    if absolute:
        ABSOLUTE.add(dimension)


def _known(dimension: str) -> None:
    """ValueError unless ``dimension`` is declared, here or by an effect: an effect's
    dimensions are declared when its settings are imported (scene/catalog.py imports them
    all; the loader imports the catalog, and so does a command that reads a quantity of an
    effect's dimension before any scene)."""
    if dimension not in DIMENSIONS:
        raise ValueError(f"unknown dimension {dimension!r}; known: {', '.join(DIMENSIONS)} "
                         "(an effect's are declared by its settings: scene/catalog.py)")

_NUMBER = re.compile(r"^\s*([+-]?(?:\d+(?:_\d+)*\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*?)\s*$")


def _normalise_unit(unit: str) -> str:
    return (unit.replace(" ", "").replace("\t", "").replace("^", "").replace("²", "2")
            .replace("³", "3").replace("·", "*").replace("⋅", "*"))


def _lookup(unit: str):
    u = _normalise_unit(unit)
    if u in _UNITS:
        return _UNITS[u]
    candidates = _LOWER.get(u.lower(), [])
    if len(candidates) == 1:
        return _UNITS[candidates[0]]
    return None


def units_for(dimension: str) -> list[str]:
    """The unit spellings accepted for ``dimension`` (for messages and documentation)."""
    return [u for u, (d, _, _) in _UNITS.items() if d == dimension]


def _phrase(dimension: str) -> str:
    return DIMENSIONS[dimension][1]


def _expected(dimension: str) -> str:
    si = DIMENSIONS[dimension][0]
    if dimension == "dimensionless":
        return "a dimensionless number"
    examples = ", ".join(f"'{u}'" for u in units_for(dimension)[:6])
    return f"{_phrase(dimension)} (a number in {si}, or a string with a unit: {examples})"


def _type_name(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, (list, tuple)):
        return "an array"
    return type(value).__name__


def parse_quantity(value: Any, dimension: str, *, file: str = "<string>", key: str = "") -> float:
    """Convert a TOML number (already SI) or a quantity string to an SI float.

    Raises :class:`SceneError` for a wrong type, an unparseable string, an unknown unit, a unit
    of another dimension, a non-finite number, a nonzero magnitude outside MIN_MAGNITUDE to
    MAX_MAGNITUDE or an ABSOLUTE dimension's value below zero (below absolute zero).
    """
    _known(dimension)
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise SceneError(file, key, f"expected {_expected(dimension)}, got {_type_name(value)}")
    if isinstance(value, str):
        text = value
        m = _NUMBER.match(text)
        if not m:
            raise SceneError(file, key, f"cannot read {text!r}: expected {_expected(dimension)}")
        number = float(m.group(1).replace("_", ""))
        unit = m.group(2)
        if unit == "":
            result = number
        else:
            found = _lookup(unit)
            if found is None:
                raise SceneError(
                    file, key,
                    f"unknown unit {unit!r} in {text!r}; {_phrase(dimension)} may be given in "
                    f"{', '.join(units_for(dimension)) or DIMENSIONS[dimension][0]}")
            dim, factor, offset = found
            if dim != dimension:
                raise SceneError(file, key,
                                 f"{text!r} is {_phrase(dim)}, expected {_expected(dimension)}")
            result = number * factor + offset
    else:
        result = float(value)
    if not math.isfinite(result):
        raise SceneError(file, key, f"{value!r} is not a finite number")
    if result != 0.0 and not MIN_MAGNITUDE <= abs(result) <= MAX_MAGNITUDE:
        si = DIMENSIONS[dimension][0]
        size = f"{abs(result):.3g}" + (f" {si}" if si != "1" else "")
        raise SceneError(file, key, f"{value!r} is absurd for {_phrase(dimension)}: {size} "
                                    f"in SI, outside {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g} "
                                    "(wrong units?)")
    if dimension in ABSOLUTE and result < 0.0:
        raise SceneError(file, key, f"{value!r} is below absolute zero ({result:g} "
                                    f"{DIMENSIONS[dimension][0]})")
    return result


def parse_vec3(value: Any, dimension: str, *, file: str = "<string>",
               key: str = "") -> tuple[float, float, float]:
    """A 3-vector: an array of three numbers or quantity strings (each converted to SI)."""
    if not isinstance(value, (list, tuple)) or isinstance(value, str):
        raise SceneError(file, key,
                         f"expected an array of 3 values ({_phrase(dimension)} each), "
                         f"got {_type_name(value)}")
    if len(value) != 3:
        raise SceneError(file, key, f"expected an array of 3 values ({_phrase(dimension)} each), "
                                    f"got {len(value)} values")
    return tuple(parse_quantity(v, dimension, file=file, key=f"{key}[{i}]")
                 for i, v in enumerate(value))  # type: ignore[return-value]


# ---------------------------------------------------------------------------------- patterns
# Regular expressions that accept exactly the strings parse_quantity reads, per dimension (for
# the JSON Schema, scene/schema.py). They follow _NUMBER and _lookup: the number as _NUMBER
# reads it (greedy, so a unit that starts with a digit needs a space or '^' before it), then
# the unit with spaces, tabs and '^' anywhere in it, '²' '³' '·' for 2 3 *, and any letter
# case where the lower-case spelling names one unit only. What a pattern cannot check is the
# value after conversion (its range, its SI magnitude): JSON Schema has no units.
_NUM_BODY = r"(?:\d+(?:_\d+)*\.?\d*|\.\d+)"
_ZERO_BODY = r"(?:0+(?:_0+)*\.?0*|\.0+)"
_EXPONENT = r"(?:[eE][+-]?\d+)?"
_UNIT_SEP = r"[ \t^]*"
_UNIT_CHARS = {"2": "[2²]", "3": "[3³]", "*": "[*·⋅]"}
SIGNS = ("any", "nonnegative", "positive", "zero")


def number_pattern(sign: str = "any") -> str:
    """A regex (no anchors) for the number of a quantity string: any, nonnegative (a minus
    only before a zero), positive (a nonzero digit, no minus) or zero."""
    if sign == "any":
        return rf"[+-]?{_NUM_BODY}{_EXPONENT}"
    if sign == "nonnegative":
        return rf"(?:\+?{_NUM_BODY}|-{_ZERO_BODY}){_EXPONENT}"
    if sign == "positive":
        return rf"\+?(?=[\d_.]*[^\D0]){_NUM_BODY}{_EXPONENT}"
    if sign == "zero":
        return rf"[+-]?{_ZERO_BODY}{_EXPONENT}"
    raise ValueError(f"unknown sign {sign!r}; known: {', '.join(SIGNS)}")


def _unit_regex(unit: str) -> str:
    fold = _LOWER.get(unit.lower(), []) == [unit]
    parts = []
    for c in unit:
        if c in _UNIT_CHARS:
            parts.append(_UNIT_CHARS[c])
        elif fold and c.lower() != c.upper():
            variants = sorted({v for v in (c, c.lower(), c.upper()) if len(v) == 1})
            parts.append("[" + "".join(re.escape(v) for v in variants) + "]")
        else:
            parts.append(re.escape(c))
    return _UNIT_SEP + _UNIT_SEP.join(parts) + _UNIT_SEP


def quantity_pattern(dimension: str, sign: str = "any") -> str:
    """A regex (anchored) accepting exactly the quantity strings parse_quantity reads for
    ``dimension`` with the given sign (SIGNS) of the number; units with an offset (C, F)
    take any sign, since their SI value's sign is not the number's (an ABSOLUTE dimension's
    SI value is never negative)."""
    _known(dimension)
    if dimension in ABSOLUTE and sign == "any":
        sign = "nonnegative"        # in SI (or a bare number) a minus is below absolute zero
    groups: dict[str, list[str]] = {}
    for unit, (d, _, offset) in _UNITS.items():
        if d == dimension and not (offset and sign == "zero"):
            groups.setdefault("any" if offset else sign, []).append(unit)
    alts = [number_pattern(sign)]           # a bare number: SI
    for s, units in groups.items():
        plain = [_unit_regex(u) for u in units if not u[0].isdigit()]
        digit = [_unit_regex(u) for u in units if u[0].isdigit()]
        tail = []
        if plain:
            tail.append(r"\s*(?:" + "|".join(plain) + ")")
        if digit:
            tail.append(r"(?=[\s^])\s*(?:" + "|".join(digit) + ")")
        alts.append(number_pattern(s) + "(?:" + "|".join(tail) + ")")
    return r"^\s*(?:" + "|".join(alts) + r")\s*$"
