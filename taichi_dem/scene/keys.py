"""Scene keys declared as data: each section's keys with their type, unit, default, allowed
range and a one-line description, in one place, next to what they configure.

A ``Section`` is declared by whatever owns it: the effect modules own theirs
(``taichi_dem/effects/mobility_settings.py`` the [mobility] table, ``effects/drag_settings.py``
the mechanics-only [gas] table, ``thermal/settings.py`` [thermal] and [thermal.gas]); the scene
structure's own sections (simulation, domain, materials, ...) live in ``scene/sections/``.
From the declarations:

- the loader checks unknown keys (with a did-you-mean suggestion) and required keys, and reads
  every plain key (quantity, vector, direction, boolean, integer, string, choice) with its
  unit and range (``Section.read``): errors are ``file: key: reason`` as everywhere;
- ``scene/schema.py`` generates the JSON Schema of every scene key (``taichi-dem schema``),
  with ``x-unit``, ``default`` and ``description``, for the documentation and the fuzzer.

Keys whose value is a structure the section's own code parses (a region, a mesh, a schedule)
are declared with ``kind = "table"`` (or ``"tables"``, ``"any"``) and a JSON Schema fragment.
Cross-key checks (one key needs another) stay with the code of the section they concern.
This module is plain Python: no Taichi.
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Optional

from ..errors import SceneError
from .units import DIMENSIONS, parse_quantity, parse_vec3


class _Required:
    def __repr__(self):
        return "REQUIRED"


REQUIRED = _Required()      # a key without which the section is refused
AUTO = "auto"               # the value of a key that also accepts "auto" (resolved by its owner)

KINDS = ("quantity", "vector", "direction", "boolean", "integer", "string", "choice",
         "table", "tables", "any")


def type_name(value: Any) -> str:
    """How a TOML value is named in messages ("the string 'x'", "a table", ...)."""
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    return type(value).__name__


def suggest(word: str, choices) -> str:
    """ "did you mean 'x'? " for the closest of ``choices``, or ""."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'? " if close else ""


def join(key: str, sub: str) -> str:
    return f"{key}.{sub}" if key else sub


def _fmt(x: float) -> str:
    return "inf" if x == math.inf else f"{x:g}"


@dataclass(frozen=True)
class Key:
    """One scene key.

    ``kind``: quantity (a number in SI or a string with a unit of ``unit``), vector (three of
    them), direction (a nonzero 3-vector, normalised on load), boolean, integer, string,
    choice (one of ``choices``), or table / tables / any (parsed by the section's own code,
    described by ``schema``). ``unit`` is a dimension of ``scene/units.py`` (``"length"``,
    ``"temperature"``, ...). ``default`` is REQUIRED, None (absent means off or derived, as
    ``description`` says) or the SI value used when the key is absent. ``minimum`` /
    ``maximum`` bound the SI value (``exclusive_*`` for open ends); ``why`` says what the
    bound means, in the error. ``auto``: "auto" is also accepted (the owner resolves it).
    ``effect``: the effect the key configures, where a section serves several.
    ``default_words``: the default as it applies, where another key changes it.
    """
    name: str
    kind: str
    description: str
    unit: Optional[str] = None
    default: Any = None
    minimum: Optional[float] = None
    maximum: Optional[float] = None
    exclusive_minimum: bool = False
    exclusive_maximum: bool = False
    why: str = ""
    choices: tuple = ()
    auto: bool = False
    effect: str = ""
    schema: Optional[dict] = None
    # the default in words where it depends on another key (shown instead of ``default``)
    default_words: str = ""
    # a key an effect adds to another section (Section.adds), given in a scene without the
    # effect's section: "refused" (an error naming the key; ``off_reason`` says why, else a
    # generic reason), "ignored" (a note from ``check`` and ``run``: nothing reads it) or
    # "kept" (a property the effect reads where it is on: a material's conductivity)
    when_off: str = "refused"
    off_reason: str = ""
    # a structured key's reader where no section's code reads it (a key added to another
    # section): ``parse(value, file, key) -> value`` (its errors name ``file`` and ``key``)
    parse: Optional[Callable[[Any, str, str], Any]] = None

    def __post_init__(self):
        assert self.kind in KINDS, self.kind
        assert self.unit is None or self.unit in DIMENSIONS, self.unit
        assert self.kind not in ("quantity", "vector") or self.unit is not None, self.name
        assert self.kind != "choice" or self.choices, self.name
        assert self.when_off in ("refused", "ignored", "kept"), self.when_off

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    @property
    def si_unit(self) -> str:
        """The SI unit of the key's value ("1" when dimensionless, "" when not a quantity)."""
        if self.kind == "direction":
            return "1"
        return DIMENSIONS[self.unit][0] if self.unit else ""

    def range_text(self) -> str:
        """The allowed range in words: "> 0", "in (0, 1]", ... ("" when unbounded)."""
        lo, hi = self.minimum, self.maximum
        if lo is not None and hi is not None:
            if self.exclusive_minimum and self.exclusive_maximum:
                return f"strictly between {_fmt(lo)} and {_fmt(hi)}"
            return (f"in {'(' if self.exclusive_minimum else '['}{_fmt(lo)}, {_fmt(hi)}"
                    f"{')' if self.exclusive_maximum else ']'}")
        if lo is not None:
            return f"{'>' if self.exclusive_minimum else '>='} {_fmt(lo)}"
        if hi is not None:
            return f"{'<' if self.exclusive_maximum else '<='} {_fmt(hi)}"
        return ""

    def in_range(self, x: float) -> bool:
        if self.minimum is not None:
            if x < self.minimum or (self.exclusive_minimum and x == self.minimum):
                return False
        if self.maximum is not None:
            if x > self.maximum or (self.exclusive_maximum and x == self.maximum):
                return False
        return not (isinstance(x, float) and math.isnan(x))

    def read(self, value: Any, file: str, key: str) -> Any:
        """The value of this key in SI (a tuple for vectors), or AUTO; a SceneError naming
        ``file`` and ``key`` when it is the wrong type, unit or out of range."""
        if self.parse is not None:
            return self.parse(value, file, key)
        if self.auto and isinstance(value, str) and value.strip().lower() == AUTO:
            return AUTO
        k = self.kind
        if k == "quantity":
            try:
                x = parse_quantity(value, self.unit, file=file, key=key)
            except SceneError as e:
                if self.auto:
                    raise SceneError(file, key, f"{e.reason}; \"auto\" or {self.unit_hint()}") from None
                raise
            self._check_range(x, file, key, f"{x:g}")
            return x
        if k == "vector":
            return parse_vec3(value, self.unit, file=file, key=key)
        if k == "direction":
            v = parse_vec3(value, "dimensionless", file=file, key=key)
            n = math.sqrt(sum(c * c for c in v))
            if not n > 0.0:
                raise SceneError(file, key, "must be a nonzero vector (it is normalised on load)")
            return tuple(c / n for c in v)
        if k == "boolean":
            if not isinstance(value, bool):
                raise SceneError(file, key, f"expected true or false, got {type_name(value)}")
            return value
        if k == "integer":
            if isinstance(value, bool) or not isinstance(value, int):
                raise SceneError(file, key, f"expected an integer, got {type_name(value)}")
            self._check_range(value, file, key, f"{value}")
            return value
        if k == "string":
            if not isinstance(value, str):
                raise SceneError(file, key, f"expected a string, got {type_name(value)}")
            return value
        if k == "choice":
            if not isinstance(value, str) or value not in self.choices:
                words = [f'"{c}"' for c in self.choices]
                allowed = (", ".join(words[:-1]) + " or " + words[-1]) if len(words) > 1 else words[0]
                hint = suggest(value, self.choices) if isinstance(value, str) else ""
                raise SceneError(file, key, f"must be {allowed}, got {type_name(value)}"
                                            + (f"; {hint.strip()}" if hint else ""))
            return value
        return value        # table / tables / any: the section's own code reads it

    def unit_hint(self) -> str:
        return f"{DIMENSIONS[self.unit][1]} in {self.si_unit}" if self.unit else "a value"

    def _check_range(self, x, file: str, key: str, shown: str) -> None:
        if self.in_range(x):
            return
        text = self.range_text()
        if self.kind == "integer" and text.startswith("in ["):
            text = f"between {self.minimum:g} and {self.maximum:g}"
        why = f" ({self.why})" if self.why else ""
        verb = "lie" if text.startswith("strictly") else "be"
        raise SceneError(file, key, f"must {verb} {text}, got {shown}{why}")

    def default_text(self) -> str:
        """The default in words, for references ("required", "off/derived", a value, or
        ``default_words`` where it depends on another key)."""
        if self.default_words:
            return self.default_words
        d = self.default
        if d is REQUIRED:
            return "required"
        if d is None:
            return "none"
        if isinstance(d, bool):
            return "true" if d else "false"
        if isinstance(d, str):
            return f'"{d}"'
        if isinstance(d, tuple):
            return "[" + ", ".join(_fmt(c) for c in d) + "]"
        if isinstance(d, float):
            return _fmt(d)
        return str(d)


@dataclass(frozen=True)
class Section:
    """The keys of one scene table. ``path`` is its dotted place in the scene ("thermal.gas";
    "particles[]" for an array of tables, "materials.*" for a table of named tables);
    ``owner`` the module that declares it (an effect's, or scene/sections)."""
    path: str
    description: str
    keys: tuple[Key, ...]
    owner: str = ""
    # key -> nested Section for keys whose value is a table the section's code reads with it
    nested: dict = field(default_factory=dict)
    # an effect's own top-level section: ``reader(table, parser) -> settings`` (parser: the
    # loader's, with ``source``, ``materials``, ``domain``, ``simulation``, ``sources``,
    # ``walls``, ``bodies``, ``parse_region``); the loader calls it when the scene has the
    # section and keeps the result in ``Scene.settings[path]``
    reader: Optional[Callable[[Any, Any], Any]] = None
    # with a reader: "module:function" building the effect objects from (scene, settings);
    # effects/registry.py imports it only for a scene that has the section
    builds: str = ""
    # with a reader: ``derive(parser) -> settings or None``, the effect's settings implied by
    # other sections when the scene lacks this one (the drag of a [thermal.gas] with
    # ``drag``; gravity from [simulation] gravity, a section without a table of its own)
    derive: Optional[Callable[[Any], Any]] = None
    # the effect sections whose settings its reader or ``derive`` reads (the
    # loader's ``settings``, as read so far): the loader reads those first
    after: tuple = ()
    # the keys the effect adds to other sections' tables, by the host's path ({"materials.*":
    # (Key, ...), "walls[]", "bodies[]", "particles[]", "factories[]", "simulation"}):
    # the host reads them with its own keys into its object's ``effect_values`` (their
    # defaults where absent; scene/model.py ``AddedKeys``), the schema lists them under it.
    # Given in a scene without this section, each does what its ``when_off`` says
    adds: dict = field(default_factory=dict)
    # with ``adds``: ``added_rules() -> {host path: [JSON Schema, ...]}``, the conditional
    # keys among the added ones (one needs another), for the host's ``allOf``
    added_rules: Optional[Callable[[], dict]] = None
    # with ``adds``: ``check_added(parser)``, the checks among the added keys that hold
    # whether or not the section is on (a real modulus no softer than the simulated one);
    # the loader calls it after reading every section
    check_added: Optional[Callable[[Any], None]] = None
    # what the effect can do to a free particle, for the time step and the divergence guard
    # (setup/timestep.py expected_max_speed), both from (scene, settings):
    # ``acceleration_bound`` the largest acceleration it gives one, m/s^2 (a body force);
    # ``speed_bound`` the largest speed it can carry one to, m/s (a gas's drag)
    acceleration_bound: Optional[Callable[[Any, Any], float]] = None
    speed_bound: Optional[Callable[[Any, Any], float]] = None
    # ``work_bound(scene, settings, span)``: the work per unit mass (J/kg) its field can do on
    # a particle crossing the domain (``span``: its extent per axis, m), where the field has a
    # direction (gravity along its own); ``resting_acceleration(scene, settings)``: the steady
    # acceleration (m/s^2) a particle at rest bears from it (its weight, for the overlap a
    # particle's own weight presses into its partner)
    work_bound: Optional[Callable[[Any, Any, Any], float]] = None
    resting_acceleration: Optional[Callable[[Any, Any], float]] = None
    # with a reader: ``step_problem(settings, dt) -> (key, reason) or None``, why the effect
    # cannot be stepped at ``dt`` s (the scene is refused naming [path].key)
    step_problem: Optional[Callable[[Any, float], Any]] = None
    # ``schema_rules() -> [JSON Schema, ...]``: the section's conditional keys as its own code
    # checks them (one key needs another), the ``allOf`` of its schema (scene/schema.py)
    schema_rules: Optional[Callable[[], list]] = None

    def __post_init__(self):
        names = [k.name for k in self.keys]
        assert len(names) == len(set(names)), f"{self.path}: duplicate key"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(k.name for k in self.keys)

    def __getitem__(self, name: str) -> Key:
        for k in self.keys:
            if k.name == name:
                return k
        raise KeyError(f"{self.path} has no key {name!r}")

    def __contains__(self, name: str) -> bool:
        return name in self.names

    def default(self, name: str) -> Any:
        """The declared default of ``name`` (for dataclass fields: one definition)."""
        return self[name].default

    def check(self, table: dict, file: str, key: str, required: tuple[str, ...] | None = None) -> None:
        """Unknown keys (with the closest known one suggested) and missing required keys;
        ``required`` overrides the declared ones (a section whose required keys depend on
        a mode)."""
        allowed = self.names
        for k in table:
            if k not in allowed:
                raise SceneError(file, join(key, k),
                                 f"unknown key '{k}'; {suggest(k, allowed)}"
                                 f"allowed keys here: {', '.join(allowed)}")
        needed = required if required is not None else tuple(k.name for k in self.keys if k.required)
        for k in needed:
            if k not in table:
                raise SceneError(file, join(key, k), "required key is missing")

    def read(self, table: dict, file: str, key: str, only: tuple[str, ...] | None = None,
             defaults: bool = False, required: tuple[str, ...] | None = None) -> dict:
        """Check ``table`` and read its plain keys: {name: SI value} for the keys present
        (``only`` limits it to those); ``defaults`` adds the declared default of each absent
        plain key that has one. Structured keys (table, tables, any) are left to the caller."""
        self.check(table, file, key, required)
        out: dict[str, Any] = {}
        for k in self.keys:
            if only is not None and k.name not in only:
                continue
            if k.kind in ("table", "tables", "any"):
                continue
            if k.name in table:
                out[k.name] = k.read(table[k.name], file, join(key, k.name))
            elif defaults and k.default is not None and k.default is not REQUIRED:
                out[k.name] = k.default
        return out


@dataclass(frozen=True)
class Series:
    """One /series name a sensor or an effect writes (sensors/series.py says what each field
    means; sensors/units.py gathers them): its name pattern, its SI unit ("1": a count or a ratio), what it is and
    the shape of one sample ("": a number; "(3,)": a vector; the dataset adds the samples
    axis in front)."""
    name: str
    unit: str
    description: str
    shape: str = ""
    interval: str = ""
    weight: str = ""


# every declared section, by path, filled by ``register`` when the declaring module loads
_REGISTRY: dict[str, Section] = {}


# JSON Schema fragments for a section's conditional keys (Section.schema_rules)
def given(*names: str) -> dict:
    """The table gives every one of ``names``."""
    return {"required": list(names)}


def none_of(*names: str) -> dict:
    """The table gives none of ``names``."""
    return {"not": {"anyOf": [given(n) for n in names]}}


def equals(key: str, *values) -> dict:
    """The table gives ``key`` as one of ``values``."""
    return {"properties": {key: {"enum": list(values)}}, "required": [key]}


def unless(key: str, *values) -> dict:
    """The table gives ``key`` as another value than ``values``, or not at all (default)."""
    return {"not": equals(key, *values)}


def register(section: Section) -> Section:
    """Record ``section`` for the schema (scene/schema.py); returns it."""
    _REGISTRY[section.path] = section
    return section


def registered() -> dict[str, Section]:
    """Every declared section by path, each host with the keys effects add to it."""
    return {path: host_section(section) for path, section in _REGISTRY.items()}


def added_keys(host: str) -> tuple[tuple[str, Key], ...]:
    """(the adding section's path, key) for each key the effect sections add to the section
    at ``host`` ("materials.*", "walls[]", ...: Section.adds), by their order of
    registration, whether the scene enables them or not."""
    return tuple((s.path, k) for s in _REGISTRY.values() for k in s.adds.get(host, ()))


def host_section(section: Section) -> Section:
    """``section`` with the keys effects add to it (its own keys first)."""
    extra = tuple(k for _, k in added_keys(section.path))
    if not extra:
        return section
    nested = dict(section.nested)
    for k in extra:
        assert k.name not in section, f"{section.path}.{k.name}: an effect adds a built-in key"
        # (required only where its effect is on: the host cannot know that by itself)
        assert not k.required, f"{section.path}.{k.name}: an added key needs a default"
        inner = _REGISTRY.get(f"{section.path}.{k.name}")
        if inner is not None:           # a table the adding effect declares the keys of
            nested[k.name] = inner
    return replace(section, keys=section.keys + extra, nested=nested)


def added_values(host: str, table: dict, file: str, key: str) -> dict:
    """{name: SI value, or its default} of every key the effects add to the host section at
    ``host``, read from its ``table`` (at ``key``, for errors); a structured key (a table)
    is read by its ``parse``."""
    out = {}
    for _, k in added_keys(host):
        if k.name in table:
            out[k.name] = k.read(table[k.name], file, join(key, k.name))
        else:
            out[k.name] = k.default
    return out


def added_in(doc: dict, section) -> list:
    """(the table's dotted key, Key) for each key ``section`` adds to another section that
    the scene ``doc`` gives, in the document's order."""
    out = []
    for host, keys in section.adds.items():
        for where, table in _host_tables(doc, host):
            out.extend((where, k) for k in keys if k.name in table)
    return out


def _host_tables(doc: dict, host: str) -> list:
    """(dotted key, table) of each table of the host section ``host`` in ``doc``
    ("materials.*": each [materials.NAME]; "walls[]": each [[walls]])."""
    name = host.split(".")[0].split("[")[0]
    value = doc.get(name, {} if host.endswith(".*") else [])
    if host.endswith(".*") and isinstance(value, dict):
        return [(f"{name}.{k}", t) for k, t in value.items() if isinstance(t, dict)]
    if host.endswith("[]") and isinstance(value, list):
        return [(f"{name}[{i}]", t) for i, t in enumerate(value) if isinstance(t, dict)]
    return []


def effect_sections() -> dict[str, Section]:
    """The registered sections that declare an effect (``builds``), each of which the scene
    enables by a table of its own (``reader``) or by what other sections imply (``derive``:
    gravity by [simulation] gravity)."""
    return {p: s for p, s in _REGISTRY.items() if s.builds}


def table_sections() -> dict[str, Section]:
    """The effect sections that are a scene table of their own (``reader``: [mobility])."""
    return {p: s for p, s in effect_sections().items() if s.reader is not None}
