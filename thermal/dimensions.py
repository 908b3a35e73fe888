"""The dimensions heat transfer brings to the scene's units (scene/units.py ``add_dimension``):
the temperature (K, absolute: nothing below 0 K), a conductivity and a specific heat, with the
spellings a scene may give them in. Imported by the heat transfer's keys before they are
declared. Plain Python (no Taichi)."""
from taichi_dem.scene.units import add_dimension

_F = 5.0 / 9.0

add_dimension("temperature", "K", "a temperature", (
    ({"K": 1.0}, 0.0),
    ({"C": 1.0, "degC": 1.0, "°C": 1.0, "celsius": 1.0}, 273.15),
    ({"F": _F, "degF": _F, "°F": _F}, 273.15 - 32.0 * _F),
), absolute=True)
add_dimension("thermal_conductivity", "W/(m K)", "a thermal conductivity", (
    ({"W/(mK)": 1.0, "W/(m*K)": 1.0, "W/m/K": 1.0, "W/mK": 1.0}, 0.0),
))
add_dimension("specific_heat", "J/(kg K)", "a specific heat capacity", (
    ({"J/(kgK)": 1.0, "J/(kg*K)": 1.0, "J/kg/K": 1.0, "J/kgK": 1.0, "kJ/(kgK)": 1e3,
      "kJ/(kg*K)": 1e3, "kJ/kg/K": 1e3}, 0.0),
))
