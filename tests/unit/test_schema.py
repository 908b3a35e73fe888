"""The scene-key declarations (scene/keys.py) and the JSON Schema generated from them
(scene/schema.py, `taichi-dem schema`): every key has its type, unit, default and description;
every valid scene of the fuzz corpus (the demos, the suite's scenes) validates against the
schema; the schema and the loader refuse the same unknown keys and accept the same sections;
declared defaults are the defaults the settings dataclasses use (one definition)."""
import dataclasses
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import jsonschema
import pytest

from taichi_dem.errors import SceneError
from taichi_dem.scene import loader, schema
from taichi_dem.scene.keys import REQUIRED, Key, Section, registered

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))
import scene_fuzz  # noqa: E402

SCHEMA = schema.scene_schema()
VALIDATOR = schema.validator(SCHEMA)


def test_the_schema_is_valid_json_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


def test_every_key_has_a_description_and_quantities_a_unit():
    keys = schema.every_key(SCHEMA)
    assert len(keys) > 150
    for path, node in keys:
        assert node.get("description"), path
        quantity = node.get("type") == ["number", "string"] or any(
            a.get("type") == ["number", "string"] for a in node.get("anyOf", []))
        if quantity and "builder" not in path:
            assert "x-unit" in node, f"{path}: a quantity without a unit"


def test_the_top_level_sections_are_the_loaders():
    assert set(SCHEMA["properties"]) == set(loader.SECTIONS)


@pytest.mark.parametrize("base", scene_fuzz.base_scenes(), ids=lambda b: b.name)
def test_every_valid_scene_validates(base):
    errors = [f"{list(e.absolute_path)}: {e.message}"
              for e in VALIDATOR.iter_errors(schema.json_compatible(base.doc))]
    assert not errors, errors[:5]


@pytest.mark.parametrize("section,where", [
    ("simulation", ("simulation",)), ("thermal", ("thermal",)), ("mobility", ("mobility",)),
    ("materials", ("materials", "ash")), ("interactions", ("interactions", 0)),
])
def test_an_unknown_key_is_refused_by_both(section, where):
    """A typo is refused by the schema and by the loader, at the same key."""
    import copy
    from test_loader import base, dumps
    doc = base()
    doc.setdefault("thermal", {}) if section == "thermal" else None
    if section == "thermal":
        doc["materials"]["ash"].update(thermal_conductivity=1.0, heat_capacity=800.0)
        for f in doc["particles"]:
            f["temperature"] = 300.0
    if section == "mobility":
        doc["mobility"] = {}
    bad = copy.deepcopy(doc)
    node = bad
    for k in where:
        node = node[k]
    node["no_such_key"] = 1
    assert not list(VALIDATOR.iter_errors(doc)), "the base scene must be valid"
    assert list(VALIDATOR.iter_errors(bad))
    with pytest.raises(SceneError) as e:
        loader.parse_scene(dumps(bad), source="scene.toml")
    assert e.value.key.endswith("no_such_key")


def test_declared_defaults_are_the_dataclass_defaults():
    """Each settings dataclass takes its defaults from the declarations (or the declarations
    from it): they must never drift apart."""
    from taichi_dem.effects.drag.settings import SECTION as DRAG
    from taichi_dem.effects.mobility.settings import SECTION as MOBILITY, MobilitySettings
    from taichi_dem.scene.model import Interaction, Output, SimulationSettings
    from taichi_dem.thermal.host_keys import CoarseGraining
    from taichi_dem.thermal.settings import GAS, THERMAL, GasSettings, ThermalSettings
    sections = registered()
    pairs = [(THERMAL, ThermalSettings, {}), (GAS, GasSettings, {}),
             (MOBILITY, MobilitySettings, {}),
             (sections["simulation"], SimulationSettings, {}),
             (sections["output"], Output, {}),
             (sections["materials.*.coarse_grained"], CoarseGraining, {}),
             (sections["interactions[]"], Interaction, {"model": "rolling_model"})]
    checked = 0
    for section, cls, rename in pairs:
        fields = {f.name: f.default for f in dataclasses.fields(cls)}
        for key in section.keys:
            name = rename.get(key.name, key.name)
            if name not in fields or key.default in (None, REQUIRED) or key.auto:
                continue
            assert fields[name] == key.default, f"{section.path}.{key.name}"
            checked += 1
    assert checked >= 25
    assert DRAG.default("density") == GasSettings.density


def test_range_errors_name_the_key_and_the_bound():
    k = Key("x", "quantity", "a test", unit="length", minimum=0.0, maximum=1.0,
            exclusive_minimum=True, why="because")
    assert k.read("5 mm", "f.toml", "s.x") == pytest.approx(0.005)
    with pytest.raises(SceneError) as e:
        k.read(2.0, "f.toml", "s.x")
    assert str(e.value) == "f.toml: s.x: must be in (0, 1], got 2 (because)"
    choice = Key("m", "choice", "a test", choices=("one", "two"))
    with pytest.raises(SceneError) as e:
        choice.read("tow", "f.toml", "s.m")
    assert "did you mean 'two'" in e.value.reason
    section = Section("s", "a test", (k, choice))
    with pytest.raises(SceneError) as e:
        section.check({"xx": 1}, "f.toml", "s")
    assert e.value.key == "s.xx" and "did you mean 'x'" in e.value.reason


def test_reading_a_scene_does_not_import_taichi():
    """The loader and the schema read the declarations only (no kernels, no Taichi)."""
    code = ("import sys; from taichi_dem.scene import loader, schema; schema.scene_schema(); "
            "loader.load_scene('demos/paddle_cooler.toml'); print('taichi' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "False"


def test_the_cli_prints_the_schema():
    out = subprocess.run([sys.executable, "-m", "taichi_dem", "schema"], cwd=ROOT,
                         capture_output=True, text=True, check=True)
    assert json.loads(out.stdout)["title"] == "taichi_dem scene"
    out = subprocess.run([sys.executable, "-m", "taichi_dem", "schema", "--keys"], cwd=ROOT,
                         capture_output=True, text=True, check=True)
    line = next(x for x in out.stdout.splitlines() if x.startswith("thermal.gas_gap_min_gap"))
    assert " m " in line and "1e-06" in line


def test_every_leaf_is_typed():
    """No key of the schema accepts anything: each says its type, its choices or its
    alternatives (a key that takes any value would hide a loader refusal)."""
    def typed(node):
        return any(k in node for k in ("type", "enum", "const")) or (
            "anyOf" in node and all(typed(b) for b in node["anyOf"]))
    loose = [path for path, node in schema.every_key(SCHEMA) if not typed(node)]
    assert not loose, loose


def _quantity_strings():
    """Spellings of every unit of every dimension, as users write them."""
    from taichi_dem.scene.units import DIMENSIONS, units_for
    out = ["abc", "nan", "inf m", "", "5", "-5", "1_000", "1e999", "++1", "1.2.3", ".5 m",
           "5.", "51/min", "5 1/min", "5^1/min", "5 ^", "5 m m", "0 m", "-0 mm", "0e5 m",
           "٥ m"]
    for d in DIMENSIONS:
        for u in units_for(d):
            out += [f"2.5 {u}", f"-2.5 {u}", f"2.5{u}", f"2.5 {u.upper()}", f"2.5 {u.lower()}",
                    f" 3e2\t{u} ", f"0 {u}", f"2.5 {u.replace('2', '²').replace('3', '^3')}"]
    out += ["0.3 W/(m K)", "0.3 W/(m·K)", "9.81 m/s²", "2.5 g/cm³", "1 N·m", "10 r p m"]
    return out


@pytest.mark.parametrize("dimension", sorted(__import__("taichi_dem.scene.units",
                                                           fromlist=["DIMENSIONS"]).DIMENSIONS))
def test_a_quantity_pattern_accepts_what_the_loader_reads(dimension):
    """For each dimension, the schema's pattern for a quantity string and parse_quantity agree
    on every unit spelling of every dimension (with spaces, case, '^', '²'), on bare numbers
    and on garbage; for a positive key, the pattern refuses what the loader's range refuses
    (a minus, a zero) wherever the unit has no offset (C and F do; their value after
    conversion is the documented exemption). Exact agreement: no tolerance."""
    import math
    import re
    from taichi_dem.scene.units import parse_quantity, quantity_pattern
    for sign in ("any", "nonnegative", "positive"):
        pattern = re.compile(quantity_pattern(dimension, sign))
        for text in _quantity_strings():
            try:
                x = parse_quantity(text, dimension)
            except SceneError:
                x = None
            if x is not None and "C" not in text and "F" not in text and "celsius" not in text:
                x = x if {"any": True, "nonnegative": x >= 0, "positive": x > 0}[sign] else None
            elif x is not None:
                continue            # an offset unit: the value's sign is not the number's
            loader = x is not None and math.isfinite(x)
            # magnitudes (1e999, 1e40) are the value after conversion: not the pattern's
            if x is None and re.search(r"e\d{3}", text):
                continue
            assert bool(pattern.search(text)) == loader, (dimension, sign, text)


def test_integers_are_toml_integers():
    """count = 3000.0 is a float in TOML: the loader refuses it, and so does the schema's
    validator (JSON's "integer" would take 3000.0)."""
    from test_loader import base, dumps
    doc = base()
    assert not list(VALIDATOR.iter_errors(doc))
    doc["particles"][0]["count"] = float(doc["particles"][0]["count"])
    assert list(VALIDATOR.iter_errors(doc))
    with pytest.raises(SceneError) as e:
        loader.parse_scene(dumps(doc), source="scene.toml")
    assert e.value.key == "particles[0].count"


@pytest.mark.parametrize("where, value", [
    (("materials", "ash", "density"), float("nan")), (("materials", "ash", "density"), "nan"),
    (("materials", "ash", "density"), float("inf")), (("materials", "ash", "density"), 1e308),
    (("materials", "ash", "density"), 1e-31), (("materials", "ash", "density"), "5 kg"),
    (("materials", "ash", "density"), "abc"), (("particles", 0, "radius"), 0.0),
    (("particles", 0, "radius"), "-5 mm"), (("particles", 0, "velocity"), [float("nan"), 0, 0]),
    (("particles", 0, "velocity"), [1e31, 0, 0]), (("walls", 0, "name"), ""),
    (("walls", 0, "name"), "tab\tname"), (("walls", 0, "plane", "normal"), [0, "0", 0.0]),
    (("simulation", "dt"), "autom"), (("particles", 0, "count"), 3000.0),
])
def test_the_schema_refuses_what_the_loader_refuses(where, value):
    """Each value the issue found the schema accepting (a quantity with no pattern, NaN, no
    magnitude limits, no lower bound on a radius, untyped vector items, a float count, an
    empty or control-character name) is refused by the schema and by the loader."""
    import copy
    from test_loader import base, dumps
    doc = base()
    doc["walls"] = [{"name": "floor", "material": "steel",
                     "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]
    doc["simulation"] = {"dt": "auto"}
    assert not list(VALIDATOR.iter_errors(schema.json_compatible(doc)))
    loader.parse_scene(dumps(doc), source="scene.toml")
    bad = copy.deepcopy(doc)
    node = bad
    for k in where[:-1]:
        node = node[k]
    node[where[-1]] = value
    assert list(VALIDATOR.iter_errors(schema.json_compatible(bad))), (where, value)
    with pytest.raises(SceneError):
        loader.parse_scene(scene_fuzz.dumps(bad), source="scene.toml")


def test_builder_parameters_are_typed():
    """A mesh builder's parameters have the types of their kind: a count is a whole number
    within 1 .. MAX_COUNT, a length positive with a length unit, a choice one of its words."""
    mesh = {"builder": "drum", "radius": 0.1, "length": 0.2, "flights": 4,
            "flight_height": 0.02}
    one = {"$schema": schema.DIALECT, **schema.builder_schema()}
    check = schema.validator(one)
    assert check.is_valid(mesh)
    for key, value in (("flights", 2.5), ("flights", -1), ("flights", 10 ** 6),
                       ("radius", "5 kg"), ("radius", -0.1), ("radius", "-5 mm"),
                       ("flight_shape", "U"), ("end_walls", 1), ("origin", [0, 0]),
                       ("axis_direction", [0, 0, 0]), ("segments", "many")):
        assert not check.is_valid(dict(mesh, **{key: value})), (key, value)
    assert check.is_valid(dict(mesh, flights=4.0, radius="100 mm", origin=["1 ft", 0, 0]))


@pytest.mark.parametrize("builder, param", sorted(
    __import__("taichi_dem.geometry.builders", fromlist=["x"]).PARAMETER_RANGES))
def test_builder_parameter_ranges_are_the_builders(builder, param):
    """Each declared range (geometry/builders.py PARAMETER_RANGES, in the schema) is where the
    builder itself refuses: it builds 1e-6 (degrees) inside each open bound and at each closed
    one, and refuses at an open bound and the next float past a closed one (1e-6: an angle in
    degrees goes through radians, where the next float past 0 deg is 0 rad)."""
    import math
    from taichi_dem import geometry
    from taichi_dem.geometry.builders import PARAMETER_RANGES
    valid = {"drum": {"radius": 0.1, "length": 0.2, "flights": 4, "flight_height": 0.02,
                      "flight_shape": "L", "flight_lip": 0.01},
             "paddle_shaft": {"length": 1.0, "shaft_radius": 0.05, "rows": 2,
                              "paddles_per_row": 2},
             "chute": {"length": 0.5, "width": 0.2}}[builder]
    lo, hi, exclusive = PARAMETER_RANGES[(builder, param)]
    for bound, inward in ((lo, math.inf), (hi, -math.inf)):
        if bound is None:
            continue
        inside = bound if not exclusive else bound + math.copysign(1e-6, inward)
        if isinstance(bound, int):
            inside, outside = bound, bound - 1 if inward > 0 else bound + 1
        else:
            outside = bound if exclusive else math.nextafter(float(bound), -inward)
        geometry.build(builder, dict(valid, **{param: inside}), key="mesh")
        with pytest.raises(geometry.GeometryError):
            geometry.build(builder, dict(valid, **{param: outside}), key="mesh")
