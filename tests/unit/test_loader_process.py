"""[[factories]], [[outlets]] and [[sensors]]: what loads, and clear errors for what does not."""
import math

import pytest

from test_loader import base, error, load


def factory(**kw):
    f = {"name": "inlet", "material": "ash", "radius": 0.01,
         "region": {"box": {"min": [0.1, 0.1, 0.7], "max": [0.9, 0.9, 0.9]}},
         "mass_rate": [[0.0, "6.5 t/h"], [150.0, "13 t/h"]]}
    f.update(kw)
    return f


def with_process(**kw):
    d = base()
    d["factories"] = [factory(**kw)]
    d["outlets"] = [{"name": "discharge",
                     "region": {"box": {"min": [0.0, 0.0, 0.0], "max": [1.0, 0.2, 0.2]}}}]
    d["sensors"] = [
        {"kind": "mass_flow", "name": "plane", "plane": {"point": [0.5, 0, 0], "normal": [1, 0, 0]},
         "radius": 0.3},
        {"kind": "residence_time", "name": "res", "from": "inlet", "to": "discharge"}]
    return d


def test_contract_keys_load():
    d = with_process(velocity=[0.0, 0.0, -0.5], temperature="450 C", moisture=0.05)
    d["materials"]["ash"].update(thermal_conductivity=0.3, heat_capacity=800.0)
    d["particles"][0]["temperature"] = 300.0
    d["thermal"] = {"conduction": True}
    s = load(d)
    assert s.settings.get("thermal").moisture
    (f,) = s.factories
    assert f.name == "inlet" and f.radius.mean == 0.01 and f.temperature == pytest.approx(723.15)
    assert f.moisture == 0.05 and f.velocity == (0.0, 0.0, -0.5)
    assert f.mass_rate.at(10.0) == pytest.approx(6.5 / 3.6) and f.mass_rate.at(150.0) == pytest.approx(13 / 3.6)
    # the scheduled mass is the integral of the rate
    assert f.mass_rate.mass_until(200.0) == pytest.approx(150 * 6.5 / 3.6 + 50 * 13 / 3.6)
    assert s.outlets[0].name == "discharge"
    plane, res = s.sensors
    assert plane.kind == "mass_flow" and plane.normal == (1.0, 0.0, 0.0) and plane.radius == 0.3
    assert res.source == "inlet" and res.target == "discharge"


def test_sizes_with_mass_fractions():
    d = with_process(sizes=[["5 mm", 0.3], ["10 mm", 0.7]])
    del d["factories"][0]["radius"]
    s = load(d)
    assert s.factories[0].sizes == ((0.005, 0.3), (0.01, 0.7))


@pytest.mark.parametrize("kw, key, frag", [
    ({"mass_rate": "13 m/s"}, "factories[0].mass_rate", "mass flow rate"),
    ({"mass_rate": [[1.0, "1 kg/s"]]}, "factories[0].mass_rate[0][0]", "start at time 0"),
    ({"mass_rate": [[0.0, "1 kg/s"], [0.0, "2 kg/s"]]}, "factories[0].mass_rate[1][0]", "increase"),
    ({"mass_rate": [[0.0, "-1 kg/s"]]}, "factories[0].mass_rate[0][1]", ">= 0"),
    ({"sizes": [[0.01, 0.5]]}, "factories[0].radius", "exactly one of radius"),
    ({"material": "sand"}, "factories[0].material", "sand"),
    ({"radius": 0.3}, "factories[0].region", "narrower than one particle"),
    ({"moisture": -0.1}, "factories[0].moisture", ">= 0"),
    ({"name": "a b"}, "factories[0].name", "letters"),
    ({"rate": 1}, "factories[0].rate", "unknown key"),
])
def test_factory_errors(kw, key, frag):
    error(with_process(**kw), key, frag)


def test_fractions_must_sum_to_one():
    d = with_process()
    del d["factories"][0]["radius"]
    d["factories"][0]["sizes"] = [[0.01, 0.5], [0.012, 0.4]]
    error(d, "factories[0].sizes", "sum to 1")


def test_duplicate_names_and_missing_references():
    d = with_process()
    d["factories"].append(factory())
    error(d, "factories[1].name", "already the name")
    d = with_process()
    d["sensors"][1]["to"] = "nowhere"
    error(d, "sensors[1].to", "no outlet named 'nowhere'")
    d = with_process()
    d["sensors"][1]["from"] = "nowhere"
    error(d, "sensors[1].from", "no factory named 'nowhere'")
    d = with_process()
    d["sensors"].append({"kind": "contact_count", "name": "c", "body": "shell"})
    error(d, "sensors[2].body", "no body named 'shell'")
    d = with_process()
    d["sensors"].append({"kind": "torque", "name": "c"})
    error(d, "sensors[2].kind", "unknown sensor kind")


def test_outlet_region_inside_domain():
    d = with_process()
    d["outlets"][0]["region"] = {"box": {"min": [0.0, 0.0, -1.0], "max": [1.0, 0.2, 0.2]}}
    error(d, "outlets[0].region.box", "inside the domain")


def test_factory_moisture_needs_thermal():
    error(with_process(moisture=0.05), "factories[0].moisture", "drying needs heat transfer")


def test_factories_need_temperature_when_thermal():
    d = with_process()
    d["materials"]["ash"].update(thermal_conductivity=0.3, heat_capacity=800.0)
    d["particles"][0]["temperature"] = 300.0
    d["thermal"] = {"conduction": True}
    error(d, "factories[0].temperature", "required when [thermal]")


def test_factory_only_scene_is_allowed():
    d = with_process()
    del d["particles"]
    s = load(d)
    assert s.fills == () and len(s.factories) == 1
