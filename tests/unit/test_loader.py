import copy
import json
import math

import numpy as np
import pytest

from taichi_dem.scene.loader import load_scene, parse_scene
from taichi_dem.errors import SceneError

# A full scene written from the keys of CONTRACT.md (sections planned for later versions left out).
CONTRACT_SCENE = """
[simulation]
end_time = 30.0             # s
dt = "auto"
rayleigh_fraction = 0.2
gravity = [0.0, 0.0, -9.81]
precision = "f32"
seed = 1

[domain]
min = [-0.6, -0.6, -0.6]
max = [6.6, 0.6, 0.6]
periodic = []

[[walls]]
name = "floor"
plane = { point = [0, 0, -0.5], normal = [0, 0, 2] }
material = "steel"
temperature = 300.0

[materials.ash]
density = 870.0
youngs_modulus = 1.1e7
poisson_ratio = 0.25
thermal_conductivity = 0.3
heat_capacity = 800.0
emissivity = 0.9
real_youngs_modulus = 1.1e10

[materials.steel]
density = "7.8 g/cm3"
youngs_modulus = "200 GPa"
poisson_ratio = 0.3

[[interactions]]
pair = ["ash", "steel"]
restitution = 0.65
friction = 0.8
rolling_friction = 0.05

[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.6
rolling_friction = 0.1
model = "epsd"

[[particles]]
material = "ash"
radius = 0.0075
count = 5000
region = { box = { min = [0, -0.3, -0.3], max = [1, 0.3, 0.0] } }
velocity = [0.0, 0.0, 0.0]
temperature = 700.0
fixed = false

[[particles]]
material = "ash"
radius = { mean = "7.5 mm", std = "1 mm", min = "5 mm", max = "10 mm" }
count = 100
region = { cylinder = { axis_point = [2,0,0], axis_direction = [1,0,0], radius = 0.4, length = 1.0 } }
velocity = ["0.1 m/s", 0, 0]
angular_velocity = [0, 0, "10 rpm"]
temperature = "450 C"
fixed = true

[output]
interval = 0.05
rrd = "out/scene.rrd"
h5 = "out/scene.h5"
checkpoint_interval = 10.0
"""


def test_contract_scene_loads():
    s = parse_scene(CONTRACT_SCENE, source="contract.toml")
    assert s.source == "contract.toml" and s.text == CONTRACT_SCENE
    assert s.simulation.end_time == 30.0 and s.simulation.dt is None
    assert s.simulation.rayleigh_fraction == 0.2 and s.simulation.gravity == (0.0, 0.0, -9.81)
    assert s.simulation.precision == "f32" and s.simulation.seed == 1
    assert s.simulation.skin is None
    assert s.domain.min == (-0.6, -0.6, -0.6) and s.domain.max == (6.6, 0.6, 0.6)
    assert s.domain.periodic == ()
    ash, steel = s.materials["ash"], s.materials["steel"]
    assert ash.density == 870.0 and ash.real_youngs_modulus == 1.1e10 and ash.emissivity == 0.9
    assert steel.density == pytest.approx(7800.0) and steel.youngs_modulus == 2e11
    assert steel.thermal_conductivity is None
    i = s.interaction("steel", "ash")
    assert (i.restitution, i.friction, i.rolling_friction, i.rolling_model) == \
        (0.65, 0.8, 0.05, "constant_torque")
    assert s.interaction("ash", "ash").rolling_model == "epsd"
    (w,) = s.walls
    assert w.name == "floor" and w.normal == (0.0, 0.0, 1.0) and w.temperature == 300.0
    f0, f1 = s.fills
    assert f0.key == "particles[0]" and f0.count == 5000 and f0.radius.mean == 0.0075
    assert f0.region.kind == "box" and f0.region.box_max == (1.0, 0.3, 0.0)
    assert f0.temperature == 700.0 and f0.fixed is False and f0.file is None
    assert f1.key == "particles[1]" and f1.radius.std == pytest.approx(0.001)
    assert f1.radius.min == pytest.approx(0.005) and f1.radius.max == pytest.approx(0.01)
    assert f1.region.kind == "cylinder" and f1.region.axis_direction == (1.0, 0.0, 0.0)
    assert f1.temperature == pytest.approx(723.15) and f1.fixed is True
    assert f1.velocity == (0.1, 0.0, 0.0)
    assert f1.angular_velocity[2] == pytest.approx(10 * 2 * math.pi / 60)
    assert s.expected_particle_count == 5100
    assert s.output.interval == 0.05 and s.output.rrd == "out/scene.rrd"
    assert s.output.h5 == "out/scene.h5" and s.output.checkpoint_interval == 10.0


# --- a tiny TOML writer so each test can mutate a base scene as a dict ---------------------------

def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else repr(v))
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{json.dumps(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(v)


def dumps(doc: dict) -> str:
    out = []
    for k, v in doc.items():
        if isinstance(v, dict):
            out.append(f"[{k}]")
            out += [f"{json.dumps(kk)} = {_value(vv)}" for kk, vv in v.items()]
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                out.append(f"[[{k}]]")
                out += [f"{json.dumps(kk)} = {_value(vv)}" for kk, vv in item.items()]
        else:
            out.insert(0, f"{json.dumps(k)} = {_value(v)}")
    return "\n".join(out) + "\n"


BASE = {
    "simulation": {"end_time": 1.0, "dt": "auto", "rayleigh_fraction": 0.2,
                   "gravity": [0.0, 0.0, -9.81], "precision": "f32", "seed": 1},
    "domain": {"min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0], "periodic": []},
    "materials": {
        "ash": {"density": 870.0, "youngs_modulus": 1.1e7, "poisson_ratio": 0.25},
        "steel": {"density": 7800.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3},
    },
    "interactions": [
        {"pair": ["ash", "steel"], "restitution": 0.6, "friction": 0.5},
        {"pair": ["ash", "ash"], "restitution": 0.5, "friction": 0.5},
    ],
    "walls": [{"name": "floor", "plane": {"point": [0, 0, 0], "normal": [0, 0, 1]},
               "material": "steel"}],
    "particles": [{"material": "ash", "radius": 0.01, "count": 10,
                   "region": {"box": {"min": [0.1, 0.1, 0.1], "max": [0.9, 0.9, 0.9]}}}],
    "output": {"interval": 0.05},
}


def base():
    return copy.deepcopy(BASE)


def load(doc, **kw):
    return parse_scene(dumps(doc), source="scene.toml", **kw)


def error(doc, key, *fragments, **kw):
    with pytest.raises(SceneError) as e:
        load(doc, **kw)
    err = e.value
    assert err.key == key, f"key {err.key!r} != {key!r}: {err}"
    for frag in fragments:
        assert frag in err.reason, f"{frag!r} not in {err.reason!r}"
    assert str(err).startswith(err.file)
    return err


def test_base_scene_loads():
    s = load(base())
    assert s.source == "scene.toml" and len(s.fills) == 1 and len(s.walls) == 1


# --- file-level errors ------------------------------------------------------------------------

def test_missing_file(tmp_path):
    with pytest.raises(SceneError) as e:
        load_scene(tmp_path / "nope.toml")
    assert e.value.file.endswith("nope.toml") and "not found" in e.value.reason


def test_syntax_error_names_line(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[simulation]\nend_time = 1.0\ndt = = 2\n")
    with pytest.raises(SceneError) as e:
        load_scene(p)
    assert e.value.file == str(p)
    assert "TOML syntax error at line 3" in e.value.reason


def test_load_scene_from_file(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(dumps(base()))
    s = load_scene(p)
    assert s.source == str(p) and s.fills[0].count == 10


# --- unknown keys and sections ----------------------------------------------------------------

def test_unknown_section_suggests():
    d = base()
    d["simulaton"] = {"end_time": 1.0}
    error(d, "simulaton", "did you mean 'simulation'")


@pytest.mark.parametrize("path, bad, good", [
    (("simulation",), "end_tme", "end_time"),
    (("domain",), "periodc", "periodic"),
    (("materials", "ash"), "densty", "density"),
    (("interactions", 0), "restitutoin", "restitution"),
    (("particles", 0), "radious", "radius"),
    (("particles", 0, "region", "box"), "mn", "min"),
    (("walls", 0), "materal", "material"),
    (("walls", 0, "plane"), "normall", "normal"),
    (("output",), "intervall", "interval"),
])
def test_unknown_keys_suggest_closest(path, bad, good):
    d = base()
    t = d
    for p in path:
        t = t[p]
    t[bad] = 1
    # the dotted key, with [i] for array indices
    parts = []
    for p in path:
        if isinstance(p, int):
            parts[-1] += f"[{p}]"
        else:
            parts.append(p)
    key = ".".join(parts) + "." + bad
    error(d, key, f"unknown key '{bad}'", f"did you mean '{good}'")


def test_unknown_radius_table_key():
    d = base()
    d["particles"][0]["radius"] = {"mean": 0.01, "std": 0.0, "sigma": 1}
    error(d, "particles[0].radius.sigma", "unknown key 'sigma'")


def test_mobility_section_is_read():
    # [mobility] is no longer a planned section (issue 12): tests/unit/test_mobility.py
    d = base()
    d["mobility"] = {"enabled": True}
    assert load(d).settings.get("mobility") is not None


# --- [simulation] ---------------------------------------------------------------------------------

@pytest.mark.parametrize("key, value, frag", [
    ("end_time", 0.0, "must be > 0"),
    ("end_time", -1.0, "must be > 0"),
    ("end_time", "3 mm", "is a length, expected a time"),
    ("dt", -1e-5, "must be > 0"),
    ("dt", "fast", "\"auto\" or a positive time"),
    ("rayleigh_fraction", 0.0, "(0, 1]"),
    ("rayleigh_fraction", 1.5, "(0, 1]"),
    ("precision", "f16", "\"f32\" or \"f64\""),
    ("seed", 1.5, "integer"),
    ("seed", True, "integer"),
    ("skin", 0.0, "must be > 0"),
    ("skin", "1 rpm", "angular speed"),
])
def test_simulation_errors(key, value, frag):
    d = base()
    d["simulation"][key] = value
    error(d, f"simulation.{key}", frag)


def test_simulation_gravity_errors():
    d = base()
    d["simulation"]["gravity"] = [0, -9.81]
    error(d, "simulation.gravity", "3 values")
    d["simulation"]["gravity"] = [0, 0, "9.81 m/s"]
    error(d, "simulation.gravity[2]", "is a speed, expected an acceleration")


def test_simulation_values():
    d = base()
    d["simulation"].update(dt="10 us", rayleigh_fraction=1.0, precision="f64", skin="1 mm",
                           gravity=[0, 0, "-9.81 m/s^2"])
    s = load(d).simulation
    assert s.dt == pytest.approx(1e-5) and s.rayleigh_fraction == 1.0
    assert s.precision == "f64" and s.skin == pytest.approx(1e-3) and s.gravity[2] == -9.81
    d["simulation"] = {}
    s = load(d).simulation
    assert s.dt is None and s.end_time == 1.0


# --- [domain] ---------------------------------------------------------------------------------

def test_domain_required():
    d = base()
    del d["domain"]
    error(d, "domain", "required section [domain] is missing")


def test_domain_min_below_max():
    d = base()
    d["domain"]["max"] = [1.0, 0.0, 1.0]
    error(d, "domain.max", "on y", "max must exceed min")


def test_domain_missing_min():
    d = base()
    del d["domain"]["min"]
    error(d, "domain.min", "required key is missing")


@pytest.mark.parametrize("periodic, key, frag", [
    (["w"], "domain.periodic[0]", "\"x\", \"y\" or \"z\""),
    (["x", "x"], "domain.periodic[1]", "listed twice"),
    ("x", "domain.periodic", "array of axis names"),
])
def test_domain_periodic_errors(periodic, key, frag):
    d = base()
    d["domain"]["periodic"] = periodic
    error(d, key, frag)


def test_domain_periodic_ok():
    d = base()
    d["domain"]["periodic"] = ["x", "y"]
    assert load(d).domain.periodic == ("x", "y")


# --- [materials] ------------------------------------------------------------------------------

@pytest.mark.parametrize("key, value, frag", [
    ("density", 0.0, "must be > 0"),
    ("density", "870 Pa", "is a pressure"),
    ("youngs_modulus", -1.0, "must be > 0"),
    ("poisson_ratio", 0.5, "strictly between -1 and 0.5"),
    ("poisson_ratio", -1.0, "strictly between -1 and 0.5"),
    ("thermal_conductivity", 0.0, "must be > 0"),
    ("heat_capacity", -800.0, "must be > 0"),
    ("emissivity", 1.5, "[0, 1]"),
    ("emissivity", -0.1, "[0, 1]"),
    ("real_youngs_modulus", 0.0, "must be > 0"),
    ("real_youngs_modulus", 1e6, "must be >= youngs_modulus"),
])
def test_material_errors(key, value, frag):
    d = base()
    d["materials"]["ash"][key] = value
    error(d, f"materials.ash.{key}", frag)


def test_material_values():
    d = base()
    d["materials"]["ash"].update(poisson_ratio=0.49, emissivity=0.0, thermal_conductivity=0.3,
                                 heat_capacity="0.8 kJ/(kg K)", real_youngs_modulus=1.1e7)
    m = load(d).materials["ash"]
    assert m.poisson_ratio == 0.49 and m.emissivity == 0.0 and m.heat_capacity == 800.0
    assert m.real_youngs_modulus == 1.1e7


def test_material_required_keys():
    d = base()
    del d["materials"]["ash"]["poisson_ratio"]
    error(d, "materials.ash.poisson_ratio", "required key is missing")


def test_material_must_be_table():
    d = base()
    d["materials"]["ash"] = 3
    error(d, "materials.ash", "expected a table")


# --- [[interactions]] -------------------------------------------------------------------------

@pytest.mark.parametrize("key, value, frag", [
    ("restitution", 0.0, "(0, 1]"),
    ("restitution", 1.1, "(0, 1]"),
    ("friction", -0.1, "must be >= 0"),
    ("rolling_friction", -0.01, "must be >= 0"),
    ("model", "viscous", "\"constant_torque\" or \"epsd\""),
])
def test_interaction_errors(key, value, frag):
    d = base()
    d["interactions"][0][key] = value
    error(d, f"interactions[0].{key}", frag)


def test_interaction_unknown_material():
    d = base()
    d["interactions"][0]["pair"] = ["ash", "steal"]
    error(d, "interactions[0].pair[1]", "unknown material 'steal'", "did you mean 'steel'")


def test_interaction_pair_shape():
    d = base()
    d["interactions"][0]["pair"] = ["ash"]
    error(d, "interactions[0].pair", "two material names")


def test_interaction_duplicate_pair():
    d = base()
    d["interactions"].append({"pair": ["steel", "ash"], "restitution": 0.5, "friction": 0.1})
    error(d, "interactions[2].pair", "duplicate", "interactions[0]")


def test_interaction_required():
    d = base()
    del d["interactions"][1]["friction"]
    error(d, "interactions[1].friction", "required key is missing")


def test_interaction_defaults_and_same_material():
    s = load(base())
    i = s.interaction("ash", "ash")
    assert i.pair == ("ash", "ash") and i.rolling_friction == 0.0
    assert i.rolling_model == "constant_torque"


def test_missing_particle_particle_interaction():
    d = base()
    del d["interactions"][1]
    error(d, "interactions", "('ash', 'ash')", "particles of 'ash'")


def test_missing_particle_wall_interaction():
    d = base()
    del d["interactions"][0]
    error(d, "interactions", "('ash', 'steel')", "wall 'floor'")


def test_missing_interaction_between_two_particle_materials():
    d = base()
    d["materials"]["coal"] = dict(d["materials"]["ash"])
    d["particles"].append({"material": "coal", "radius": 0.01, "count": 1,
                           "region": {"box": {"min": [0.1, 0.1, 0.1], "max": [0.9, 0.9, 0.9]}}})
    d["interactions"].append({"pair": ["coal", "coal"], "restitution": 0.5, "friction": 0.5})
    d["interactions"].append({"pair": ["coal", "steel"], "restitution": 0.5, "friction": 0.5})
    error(d, "interactions", "('ash', 'coal')")
    d["interactions"].append({"pair": ["coal", "ash"], "restitution": 0.5, "friction": 0.5})
    assert len(load(d).fills) == 2


def test_unused_material_needs_no_interaction():
    d = base()
    d["materials"]["rubber"] = dict(d["materials"]["ash"])
    load(d)


# --- [[particles]] ----------------------------------------------------------------------------

def fill_error(mutate, key, *frags, **kw):
    d = base()
    mutate(d["particles"][0])
    return error(d, key, *frags, **kw)


def test_fill_unknown_material():
    fill_error(lambda f: f.update(material="assh"), "particles[0].material",
               "unknown material 'assh'", "did you mean 'ash'", "ash, steel")


def test_fill_needs_count_region_radius():
    for k in ("count", "region", "radius"):
        fill_error(lambda f: f.pop(k), f"particles[0].{k}", "required key is missing", "file")


def test_fill_material_required():
    fill_error(lambda f: f.pop("material"), "particles[0].material", "required")


def test_fill_file_and_count_exclusive():
    fill_error(lambda f: f.update(file="fill.csv"), "particles[0].count",
               "not allowed together with file")


@pytest.mark.parametrize("radius, key, frag", [
    (0.0, "particles[0].radius", "must be > 0"),
    (-0.01, "particles[0].radius", "must be > 0"),
    ("10 rpm", "particles[0].radius", "angular speed"),
    ({"mean": 0.01, "std": -0.001, "min": 0.005, "max": 0.02}, "particles[0].radius.std",
     "must be >= 0"),
    ({"mean": 0.01, "std": 0.001, "min": 0.02, "max": 0.03}, "particles[0].radius.min",
     "min <= mean <= max"),
    ({"mean": 0.01, "std": 0.001, "min": 0.005, "max": 0.008}, "particles[0].radius.max",
     "min <= mean <= max"),
    ({"mean": 0.01, "std": 0.001, "min": 0.0, "max": 0.02}, "particles[0].radius.min",
     "must be > 0"),
    ({"mean": 0.01, "std": 0.001, "min": 0.005}, "particles[0].radius.max",
     "required when std > 0"),
    ({"mean": 0.0, "std": 0.001, "min": 0.005, "max": 0.02}, "particles[0].radius.mean",
     "must be > 0"),
    ({"std": 0.001, "min": 0.005, "max": 0.02}, "particles[0].radius.mean", "required"),
])
def test_fill_radius_errors(radius, key, frag):
    fill_error(lambda f: f.update(radius=radius), key, frag)


def test_fill_radius_distribution():
    d = base()
    d["particles"][0]["radius"] = {"mean": "5 mm", "std": "1 mm", "min": "3 mm", "max": "8 mm"}
    r = load(d).fills[0].radius
    assert (r.mean, r.std, r.min, r.max) == pytest.approx((0.005, 0.001, 0.003, 0.008))
    assert r.largest == pytest.approx(0.008) and r.smallest == pytest.approx(0.003)
    d["particles"][0]["radius"] = {"mean": 0.005, "std": 0.0}
    r = load(d).fills[0].radius
    assert r.largest == r.smallest == 0.005


@pytest.mark.parametrize("count, frag", [(-1, "must be >= 0"), (1.5, "integer"),
                                         ("10", "integer")])
def test_fill_count_errors(count, frag):
    fill_error(lambda f: f.update(count=count), "particles[0].count", frag)


def test_fill_count_zero_ok():
    d = base()
    d["particles"][0]["count"] = 0
    assert load(d).fills[0].count == 0


@pytest.mark.parametrize("region, key, frag", [
    ({"box": {"min": [0.1, 0.1, 0.1], "max": [0.9, 0.9, 0.9]},
      "cylinder": {"axis_point": [0, 0, 0], "axis_direction": [1, 0, 0], "radius": 0.1,
                   "length": 0.1}}, "particles[0].region", "exactly one of"),
    ({}, "particles[0].region", "exactly one of"),
    ({"sphere": {"radius": 1}}, "particles[0].region.sphere", "unknown key 'sphere'"),
    ({"box": {"min": [0.1, 0.1, 0.5], "max": [0.9, 0.9, 0.5]}}, "particles[0].region.box.max",
     "on z"),
    ({"box": {"min": [0.1, 0.1, 0.1]}}, "particles[0].region.box.max", "required"),
    ({"box": {"min": [-0.1, 0.1, 0.1], "max": [0.9, 0.9, 0.9]}}, "particles[0].region.box",
     "must lie inside the domain"),
    ({"box": {"min": [0.1, 0.1, 0.1], "max": [0.9, 0.9, 1.5]}}, "particles[0].region.box",
     "must lie inside the domain"),
    ({"cylinder": {"axis_point": [0.1, 0.5, 0.5], "axis_direction": [0, 0, 0], "radius": 0.1,
                   "length": 0.5}}, "particles[0].region.cylinder.axis_direction", "nonzero"),
    ({"cylinder": {"axis_point": [0.1, 0.5, 0.5], "axis_direction": [1, 0, 0], "radius": 0.0,
                   "length": 0.5}}, "particles[0].region.cylinder.radius", "must be > 0"),
    ({"cylinder": {"axis_point": [0.1, 0.5, 0.5], "axis_direction": [1, 0, 0], "radius": 0.1,
                   "length": -0.5}}, "particles[0].region.cylinder.length", "must be > 0"),
    ({"cylinder": {"axis_point": [0.1, 0.5, 0.5], "axis_direction": [1, 0, 0], "radius": 0.1}},
     "particles[0].region.cylinder.length", "required"),
    # runs past the domain along its axis
    ({"cylinder": {"axis_point": [0.1, 0.5, 0.5], "axis_direction": [1, 0, 0], "radius": 0.1,
                   "length": 1.0}}, "particles[0].region.cylinder", "must lie inside the domain"),
    # sticks out sideways
    ({"cylinder": {"axis_point": [0.1, 0.5, 0.05], "axis_direction": [1, 0, 0], "radius": 0.1,
                   "length": 0.5}}, "particles[0].region.cylinder", "must lie inside the domain"),
])
def test_fill_region_errors(region, key, frag):
    fill_error(lambda f: f.update(region=region), key, frag)


def test_fill_cylinder_region_normalised():
    d = base()
    d["particles"][0]["region"] = {"cylinder": {"axis_point": [0.5, 0.5, 0.1],
                                                "axis_direction": [0, 0, 5], "radius": "10 cm",
                                                "length": 0.5}}
    r = load(d).fills[0].region
    assert r.kind == "cylinder" and r.axis_direction == (0.0, 0.0, 1.0)
    assert r.radius == pytest.approx(0.1) and r.length == 0.5


@pytest.mark.parametrize("key, value, frag", [
    ("velocity", [0, 0, "1 rpm"], "angular speed"),
    ("velocity", [0, 0], "3 values"),
    ("angular_velocity", [0, 0, "1 m/s"], "is a speed, expected an angular speed"),
    ("temperature", "-300 C", "below absolute zero"),
    ("temperature", "3 mm", "is a length"),
    ("fixed", "yes", "true or false"),
])
def test_fill_misc_errors(key, value, frag):
    expected_key = f"particles[0].{key}"
    if isinstance(value, list) and len(value) == 3:
        expected_key += "[2]"
    fill_error(lambda f: f.update({key: value}), expected_key, frag)


# --- particle files -----------------------------------------------------------------------------

def file_scene(tmp_path, csv_text, name="fill.csv"):
    (tmp_path / name).write_text(csv_text)
    d = base()
    d["particles"][0] = {"material": "ash", "file": name, "temperature": 400.0,
                         "velocity": [0, 0, -1]}
    return d


def test_file_fill_loads(tmp_path):
    d = file_scene(tmp_path, "x,y,z,radius\n0.5,0.5,0.5,0.01\n0.2,0.2,0.2,0.02\n")
    f = load(d, base_dir=tmp_path).fills[0]
    assert f.file == "fill.csv" and f.count == 0 and f.region is None
    np.testing.assert_allclose(f.positions, [[0.5, 0.5, 0.5], [0.2, 0.2, 0.2]])
    np.testing.assert_allclose(f.radii, [0.01, 0.02])
    assert f.velocities is None and f.angular_velocities is None
    assert f.expected_count == 2 and f.largest_radius == 0.02 and f.smallest_radius == 0.01
    assert f.velocity == (0.0, 0.0, -1.0) and f.temperature == 400.0


def test_file_fill_with_velocities_columns_by_name(tmp_path):
    d = file_scene(tmp_path, "radius, z, y, x, vz, vy, vx, wx, wy, wz\n"
                             "0.01, 0.3, 0.2, 0.1, 3, 2, 1, 4, 5, 6\n")
    f = load(d, base_dir=tmp_path).fills[0]
    np.testing.assert_allclose(f.positions, [[0.1, 0.2, 0.3]])
    np.testing.assert_allclose(f.velocities, [[1, 2, 3]])
    np.testing.assert_allclose(f.angular_velocities, [[4, 5, 6]])


def test_file_fill_relative_to_scene_file(tmp_path):
    sub = tmp_path / "scenes"
    sub.mkdir()
    (sub / "fill.csv").write_text("x,y,z,radius\n0.5,0.5,0.5,0.01\n")
    d = base()
    d["particles"][0] = {"material": "ash", "file": "fill.csv"}
    (sub / "s.toml").write_text(dumps(d))
    s = load_scene(sub / "s.toml")
    assert len(s.fills[0].radii) == 1


def test_file_missing(tmp_path):
    d = base()
    d["particles"][0] = {"material": "ash", "file": "nope.csv"}
    error(d, "particles[0].file", "'nope.csv' not found", base_dir=tmp_path)


@pytest.mark.parametrize("text, frag", [
    ("x,y,radius\n0.5,0.5,0.01\n", "lacks column 'z'"),
    ("x,y,z,radius,colour\n0.5,0.5,0.5,0.01,1\n", "column 5 of the header"),
    ("x,y,z,radius,vx,vy\n0.5,0.5,0.5,0.01,1,1\n", "give all of vx,vy,vz"),
    ("x,y,z,radius,x\n0.5,0.5,0.5,0.01,1\n", "appears twice"),
    ("", "empty file"),
    ("x,y,z,radius\n0.5,0.5,0.5,0.01\n0.5,0.5,0.5,0\n", "line 3: radius must be > 0"),
    ("x,y,z,radius\n0.5,0.5,0.5,-0.01\n", "line 2: radius must be > 0"),
    ("x,y,z,radius\n0.5,nan,0.5,0.01\n", "line 2, column 'y'"),
    ("x,y,z,radius\n0.5,inf,0.5,0.01\n", "not finite"),
    ("x,y,z,radius\n0.5,abc,0.5,0.01\n", "line 2, column 'y': not a number"),
    ("x,y,z,radius\n0.5,0.5,0.01\n", "line 2: 3 values"),
    ("x,y,z,radius\n0.5,0.5,1.5,0.01\n", "outside the domain"),
])
def test_file_errors(tmp_path, text, frag):
    d = file_scene(tmp_path, text)
    err = error(d, "particles[0].file", frag, base_dir=tmp_path)
    assert err.file.endswith("fill.csv")


def test_file_header_only_is_empty_fill(tmp_path):
    d = file_scene(tmp_path, "x,y,z,radius\n")
    f = load(d, base_dir=tmp_path).fills[0]
    assert f.positions.shape == (0, 3) and f.expected_count == 0


# --- [[walls]] ----------------------------------------------------------------------------------

def test_wall_duplicate_name():
    d = base()
    d["walls"].append(copy.deepcopy(d["walls"][0]))
    error(d, "walls[1].name", "duplicate wall name 'floor'")


def test_wall_zero_normal():
    d = base()
    d["walls"][0]["plane"]["normal"] = [0, 0, 0]
    error(d, "walls[0].plane.normal", "nonzero")


def test_wall_unknown_material():
    d = base()
    d["walls"][0]["material"] = "iron"
    error(d, "walls[0].material", "unknown material 'iron'")


def test_wall_missing_plane_point():
    d = base()
    del d["walls"][0]["plane"]["point"]
    error(d, "walls[0].plane.point", "required")


def test_wall_temperature_and_normalisation():
    d = base()
    d["walls"][0]["plane"]["normal"] = [3, 0, 4]
    d["walls"][0]["temperature"] = "27 C"
    w = load(d).walls[0]
    assert w.normal == pytest.approx((0.6, 0.0, 0.8)) and w.temperature == pytest.approx(300.15)
    d["walls"][0]["temperature"] = "1 m"
    error(d, "walls[0].temperature", "is a length")


def test_wall_name_must_be_string():
    d = base()
    d["walls"][0]["name"] = 3
    error(d, "walls[0].name", "expected a string")


# --- [output] -----------------------------------------------------------------------------------

@pytest.mark.parametrize("key, value, frag", [
    ("interval", 0.0, "must be > 0"),
    ("interval", "5 m", "is a length"),
    ("rrd", 3, "expected a string"),
    ("h5", "", "non-empty"),
    ("checkpoint_interval", -1.0, "must be > 0"),
])
def test_output_errors(key, value, frag):
    d = base()
    d["output"][key] = value
    error(d, f"output.{key}", frag)


def test_output_defaults():
    d = base()
    del d["output"]
    o = load(d).output
    assert o.interval == 0.05 and o.rrd is None and o.h5 is None and o.checkpoint_interval is None


# --- issue 10 / 15 keys: gas gap model, time scale, drag ------------------------------------

def _thermal_base():
    d = base()
    for m in d["materials"].values():
        m.update(thermal_conductivity=0.3, heat_capacity=900.0)
    d["walls"][0]["temperature"] = 300.0
    d["particles"][0]["temperature"] = 700.0
    d["thermal"] = {"conduction": True, "wall_conduction": True, "gas_gap": True}
    return d


def test_gas_gap_and_time_scale_keys_load():
    d = _thermal_base()
    d["thermal"].update(gas_gap_model="isothermal", gas_gap_pairs=False, time_scale=50.0)
    th = load(d).settings.get("thermal")
    assert (th.gas_gap_model, th.gas_gap_pairs, th.time_scale) == ("isothermal", False, 50.0)
    default = load(_thermal_base()).settings.get("thermal")
    assert (default.gas_gap_model, default.gas_gap_lens) == ("schlunder", 0.4)
    assert default.gas_pressure == 101325.0 and default.gas_gap_free_path is None
    d = _thermal_base()
    d["thermal"].update(gas_gap_model="voronoi", gas_gap_porosity=0.45)
    th = load(d).settings.get("thermal")
    assert (th.gas_gap_model, th.gas_gap_porosity) == ("voronoi", 0.45)
    d["thermal"].pop("gas_gap_porosity")
    assert load(d).settings.get("thermal").gas_gap_porosity == 0.4


@pytest.mark.parametrize("key, value, frag", [
    ("gas_gap_model", "lumped", "\"voronoi\" or \"schlunder\""),
    ("time_scale", 0.5, "at least 1"),
    ("time_scale", -2.0, "must be > 0"),
    ("gas_gap_pairs", "yes", "true or false"),
])
def test_gas_gap_and_time_scale_errors(key, value, frag):
    d = _thermal_base()
    d["thermal"][key] = value
    error(d, f"thermal.{key}", frag)


@pytest.mark.parametrize("model, value, frag", [
    ("voronoi", 0.05, "0.2 to 0.9"),
    ("voronoi", "high", "number"),
    ("solid_resistance", 0.4, "only the \"voronoi\" and \"schlunder\" gas_gap_models"),
])
def test_gas_gap_porosity_errors(model, value, frag):
    d = _thermal_base()
    d["thermal"].update(gas_gap_model=model, gas_gap_porosity=value)
    error(d, "thermal.gas_gap_porosity", frag)


@pytest.mark.parametrize("model, key, value, frag", [
    ("schlunder", "gas_gap_min_gap", 1e-6, "widens every gap"),
    ("voronoi", "gas_pressure", 1e4, "only the \"schlunder\" gas_gap_model"),
    ("isothermal", "gas_gap_free_path", 1e-7, "only the \"schlunder\" gas_gap_model"),
    ("schlunder", "gas_pressure", -1.0, "must be > 0"),
])
def test_schlunder_keys_refused_where_they_do_nothing(model, key, value, frag):
    d = _thermal_base()
    d["thermal"].update({"gas_gap_model": model, key: value})
    error(d, f"thermal.{key}", frag)


def test_schlunder_keys_load():
    d = _thermal_base()
    d["thermal"].update(gas_pressure="50 kPa", gas_gap_free_path="0.5 um", gas_gap_lens=0.3)
    d["materials"][d["particles"][0]["material"]]["surface_roughness"] = "2 um"
    scene = load(d)
    th = scene.settings.get("thermal")
    assert (th.gas_pressure, th.gas_gap_free_path, th.gas_gap_lens) == (5e4, 5e-7, 0.3)
    assert scene.materials[d["particles"][0]["material"]].surface_roughness == pytest.approx(2e-6)


def test_gas_gap_keys_without_gas_gap():
    d = _thermal_base()
    d["thermal"].update(gas_gap=False, gas_gap_model="isothermal")
    error(d, "thermal.gas_gap_model", "gas_gap is off")


def test_mechanics_gas_drag_loads_and_refuses():
    d = base()
    d["gas"] = {"velocity": [0.0, 0.0, 1.5], "drag": "schiller_naumann", "density": 1.2}
    g = load(d).settings["gas"]
    assert g.model == "schiller_naumann" and g.velocity == (0.0, 0.0, 1.5) and g.density == 1.2
    assert g.through_bed is False          # a drum's gas goes round its bed unless told
    d["gas"]["through_bed"] = True
    assert load(d).settings["gas"].through_bed is True
    d["gas"]["through_bed"] = "yes"
    error(d, "gas.through_bed", "true or false")
    del d["gas"]["through_bed"]
    d["gas"]["drag"] = "ergun"
    error(d, "gas.drag", "\"di_felice\" or \"schiller_naumann\"")
    d["gas"] = {"drag": "di_felice"}
    error(d, "gas.velocity", "required")
    d["gas"] = {"velocity": [0, 0, 1], "temperature": 300.0}
    error(d, "gas.temperature", "unknown key")


def test_thermal_gas_drag():
    d = _thermal_base()
    d["thermal"]["gas"] = {"model": "fixed", "velocity": [1.0, 0.0, 0.0], "drag": "di_felice"}
    g = load(d).settings["gas"]
    assert g.model == "di_felice" and g.velocity == (1.0, 0.0, 0.0) and not g.through_bed
    d["thermal"]["gas"]["drag_through_bed"] = True
    assert load(d).settings["gas"].through_bed is True
    d["thermal"]["gas"]["drag"] = "none"
    error(d, "thermal.gas.drag_through_bed", "only with a drag")
    del d["thermal"]["gas"]["drag_through_bed"]
    d["thermal"]["gas"]["drag"] = "stokes"
    error(d, "thermal.gas.drag", "\"none\", \"di_felice\" or \"schiller_naumann\"")
    d["thermal"]["gas"]["drag"] = "none"
    assert "gas" not in load(d).settings
    d["gas"] = {"velocity": [0.0, 0.0, 1.0]}
    error(d, "gas", "[thermal.gas] already")
