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
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)


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
    errors = [f"{list(e.absolute_path)}: {e.message}" for e in VALIDATOR.iter_errors(base.doc)]
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
    from taichi_dem.scene.model import CoarseGraining, Interaction, Output, SimulationSettings
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
