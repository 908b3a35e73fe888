import math

import pytest

from taichi_dem.errors import SceneError
from taichi_dem.scene import catalog  # noqa: F401 (the effects' dimensions: the temperature)
from taichi_dem.scene.units import DIMENSIONS, parse_quantity, parse_vec3, units_for


@pytest.mark.parametrize("text, dimension, expected", [
    ("13 t/h", "mass_rate", 13000.0 / 3600.0),
    ("6.5 t/h", "mass_rate", 6500.0 / 3600.0),
    ("2 kg/s", "mass_rate", 2.0),
    ("3600 kg/h", "mass_rate", 1.0),
    ("1 t/s", "mass_rate", 1000.0),
    ("10 rpm", "angular_speed", 10 * 2 * math.pi / 60),
    ("2 rad/s", "angular_speed", 2.0),
    ("180 deg/s", "angular_speed", math.pi),
    ("3 1/s", "angular_speed", 3.0),
    ("150 C", "temperature", 423.15),
    ("150 °C", "temperature", 423.15),
    ("150 degC", "temperature", 423.15),
    ("300 K", "temperature", 300.0),
    ("32 F", "temperature", 273.15),
    ("212 F", "temperature", 373.15),
    ("15 mm", "length", 0.015),
    ("15mm", "length", 0.015),
    ("2.5 cm", "length", 0.025),
    ("1.1e7 Pa", "pressure", 1.1e7),
    ("2 GPa", "pressure", 2e9),
    ("3 MPa", "pressure", 3e6),
    ("4 kPa", "pressure", 4e3),
    ("0.5 m/s", "speed", 0.5),
    ("45 deg", "angle", math.pi / 4),
    ("1 rad", "angle", 1.0),
    ("9.81 m/s^2", "acceleration", 9.81),
    ("9.81 m/s2", "acceleration", 9.81),
    ("870 kg/m3", "density", 870.0),
    ("870 kg/m^3", "density", 870.0),
    ("2.5 g/cm3", "density", 2500.0),
    ("5 g", "mass", 0.005),
    ("2 t", "mass", 2000.0),
    ("3 kg", "mass", 3.0),
    ("20 ms", "time", 0.02),
    ("2 min", "time", 120.0),
    ("1 h", "time", 3600.0),
    ("5 kW", "power", 5000.0),
    ("2 kJ", "energy", 2000.0),
    ("1 kWh", "energy", 3.6e6),
    ("50 %", "dimensionless", 0.5),
    ("0.3 W/(m K)", "thermal_conductivity", 0.3),
    ("0.8 kJ/(kg K)", "specific_heat", 800.0),
    ("-1.5e-3 m", "length", -1.5e-3),
    ("10 RPM", "angular_speed", 10 * 2 * math.pi / 60),   # case-insensitive when unambiguous
])
def test_quantity_strings_convert_to_si(text, dimension, expected):
    assert parse_quantity(text, dimension, file="s.toml", key="k") == pytest.approx(expected)


@pytest.mark.parametrize("value", [3, 3.0, "3"])
def test_numbers_are_already_si(value):
    assert parse_quantity(value, "length", file="f", key="k") == 3.0
    assert parse_quantity(value, "temperature", file="f", key="k") == 3.0


def test_every_dimension_has_units_and_si_name():
    for dim in DIMENSIONS:
        if dim != "dimensionless":
            assert units_for(dim), dim


def _err(value, dimension, key="a.b"):
    with pytest.raises(SceneError) as e:
        parse_quantity(value, dimension, file="scene.toml", key=key)
    assert e.value.file == "scene.toml"
    assert e.value.key == key
    assert "scene.toml" in str(e.value) and key in str(e.value)
    return e.value.reason


def test_wrong_dimension_names_both():
    reason = _err("10 rpm", "length")
    assert "'10 rpm' is an angular speed" in reason
    assert "expected a length" in reason
    assert "a temperature" in _err("150 C", "pressure")
    assert "a mass flow rate" in _err("13 t/h", "mass")


def test_unknown_unit_lists_allowed_units():
    reason = _err("10 furlongs", "length")
    assert "unknown unit 'furlongs'" in reason and "mm" in reason


def test_ambiguous_case_is_unknown():
    # mW vs MW: case matters when the lower-cased spelling is ambiguous
    assert parse_quantity("2 MW", "power", file="f", key="k") == 2e6
    assert parse_quantity("2 mW", "power", file="f", key="k") == 2e-3
    assert "unknown unit" in _err("2 mw", "power")


@pytest.mark.parametrize("value", ["abc", "", "mm 15", "1.2.3 m", "--1 m"])
def test_unparseable_strings(value):
    reason = _err(value, "length")
    assert "expected a length" in reason or "unknown unit" in reason


@pytest.mark.parametrize("value, word", [(True, "boolean"), ([1, 2], "array"),
                                          ({"a": 1}, "table")])
def test_wrong_types(value, word):
    assert word in _err(value, "length")


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "1e999 m"])
def test_non_finite(value):
    assert "not a finite number" in _err(value, "length")


def test_below_absolute_zero():
    assert "below absolute zero" in _err("-300 C", "temperature")
    assert "below absolute zero" in _err(-1.0, "temperature")
    assert parse_quantity("-40 C", "temperature", file="f", key="k") == pytest.approx(233.15)


def test_unknown_dimension_is_a_programming_error():
    with pytest.raises(ValueError):
        parse_quantity(1.0, "furlongs_per_fortnight", file="f", key="k")


def test_vec3():
    assert parse_vec3([0, 0, "-9.81 m/s2"], "acceleration", file="f", key="g") == (0.0, 0.0, -9.81)
    assert parse_vec3(["1 mm", 2, 3.0], "length", file="f", key="p") == (0.001, 2.0, 3.0)


def test_vec3_errors():
    with pytest.raises(SceneError) as e:
        parse_vec3([1, 2], "length", file="f", key="domain.min")
    assert e.value.key == "domain.min" and "3 values" in e.value.reason
    with pytest.raises(SceneError) as e:
        parse_vec3(1.0, "length", file="f", key="domain.min")
    assert e.value.key == "domain.min" and "array of 3" in e.value.reason
    with pytest.raises(SceneError) as e:
        parse_vec3([1, "2 rpm", 3], "length", file="f", key="domain.min")
    assert e.value.key == "domain.min[1]" and "angular speed" in e.value.reason
