"""Conduction through the gas gap between two particles, in the engine (issue 10 item 1,
particle-fluid-particle part; issue 16: a pair effect declared in one place, with a contact
margin).

With `[thermal] gas_gap = true` and conduction on, two particles whose centres are d apart
exchange Q = (h_spot + k_g I(d)) (T_j - T_i), I(d) the lens integral of thermal/gas_gap.py
(touching or not, up to the lens of the larger sphere) and h_spot the Hertz spot conductance
when they touch. The pair is fixed and the heat capacity chosen so that the temperatures change
by ~1e-6 K over the run: Q is read from each particle's m c dT / t (f64: the spacing at 400 K,
6e-14 K, is 1e-7 of the change) and must match the model with the integral by the slow
reference quadrature to 1e-3 (the issue's tolerance; the kernel's 12-point Gauss-Legendre rule
agrees with it to ~1e-6, tests/verification/test_gas_gap.py). Energy is conserved to round-off.
Beyond the lens nothing flows, and without gas_gap the pair reach is the contact reach.
"""
import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.thermal import gas_gap

R = 0.01
K_P, K_G = 0.3, 0.026
LENS, MIN_GAP = 0.2, 1e-6
T_HOT, T_COLD = 400.0, 300.0
DENSITY, HEAT_CAPACITY = 870.0, 1.0e6
END = 0.01


def _scene(tmp_path, radii, distance, gas=True, model="isothermal"):
    for name, row in (("hot", (0.0, 0.0, 0.0, radii[0])), ("cold", (distance, 0.0, 0.0, radii[1]))):
        (tmp_path / f"{name}.csv").write_text("x,y,z,radius\n" + ",".join(repr(float(c)) for c in row) + "\n")
    keys = (f"gas_gap = true\ngap_gas_conductivity = {K_G}\ngas_gap_lens = {LENS}\n"
            f"gas_gap_min_gap = {MIN_GAP}\ngas_gap_model = \"{model}\"\n") if gas else ""
    return f"""
[simulation]
end_time = {END}
dt = 1e-4
gravity = [0.0, 0.0, 0.0]
precision = "f64"
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]
[materials.ash]
density = {DENSITY}
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = {K_P}
heat_capacity = {HEAT_CAPACITY}
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
[[particles]]
material = "ash"
fixed = true
temperature = {T_HOT}
file = "hot.csv"
[[particles]]
material = "ash"
fixed = true
temperature = {T_COLD}
file = "cold.csv"
[thermal]
conduction = true
{keys}
[output]
interval = 0.005
"""


def _heat_flows(tmp_path, radii, distance, gas=True, model="isothermal"):
    """(heat into the cold particle W, into the hot one W, names of the effects, relative drift
    of sum m c T) over the run."""
    text = _scene(tmp_path, radii, distance, gas, model)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        names = {e.name for e in sim.effects}
        energy = sim.thermal_energy()
        sim.run()
        p = sim.particles()
        drift = (sim.thermal_energy() - energy) / energy
    t = p["temperature"]            # in id order: the hot particle first
    r = np.asarray(radii)
    thermal_mass = DENSITY * 4.0 / 3.0 * math.pi * r ** 3 * HEAT_CAPACITY
    return ((t[1] - T_COLD) * thermal_mass[1] / END, (t[0] - T_HOT) * thermal_mass[0] / END,
            names, drift)


def _expected(radii, distance, model="isothermal"):
    ri, rj = radii
    spot = 0.0
    if distance < ri + rj:
        r_eff = ri * rj / (ri + rj)
        spot = 4 * K_P * K_P / (K_P + K_P) * math.sqrt(r_eff * (ri + rj - distance))
    if model == "isothermal":
        gap = K_G * gas_gap.pair_gap_integral_reference(ri, rj, distance, LENS, MIN_GAP)
    else:
        gap = K_G * gas_gap.pair_solid_gap_integral_reference(ri, rj, distance, LENS, MIN_GAP,
                                                              K_G / K_P, K_G / K_P)
    return (spot + gap) * (T_HOT - T_COLD)


@pytest.mark.parametrize("radii,relative", [((R, R), 1 - 1e-4), ((R, R), 1 + 1e-4),
                                            ((R, R), 1.02), ((R, R), 1.08),
                                            ((R, 0.5 * R), 1 + 1e-3), ((R, 0.5 * R), 1.1)])
def test_pair_gas_gap_heat_flow(tmp_path, radii, relative):
    distance = relative * (radii[0] + radii[1])
    q_cold, q_hot, names, drift = _heat_flows(tmp_path, radii, distance)
    assert "gas_gap_pair" in names
    expected = _expected(radii, distance)
    print(f"\n  d/(ri+rj) = {relative}, radii {radii}: heat {q_cold:.6e} W, model {expected:.6e} W")
    assert expected > 0.0
    assert q_cold == pytest.approx(expected, rel=1e-3)
    assert q_hot == pytest.approx(-expected, rel=1e-3)
    # adiabatic pair: what one loses the other gains, to the f64 round-off of sum m c T
    # (~1e-16 of it; the heat moved is ~1e-10 of it)
    assert abs(drift) < 1e-14


@pytest.mark.parametrize("relative", [1 - 1e-4, 1.02])
def test_pair_gas_gap_with_the_solid_resistance(tmp_path, relative):
    # the default model: the ash's own resistance (k_g/k_s = 0.087) in series with the gas
    distance = relative * 2 * R
    q_cold, q_hot, names, drift = _heat_flows(tmp_path, (R, R), distance, model="solid_resistance")
    expected = _expected((R, R), distance, "solid_resistance")
    isothermal = _expected((R, R), distance)
    print(f"\n  d/(2R) = {relative}: heat {q_cold:.6e} W, model {expected:.6e} W "
          f"(isothermal surfaces: {isothermal:.6e} W)")
    assert q_cold == pytest.approx(expected, rel=1e-3)
    assert expected < 0.8 * isothermal


def test_beyond_the_lens_nothing_flows(tmp_path):
    # the lens of the larger sphere, R (1 + 0.2), does not reach the other sphere's surface
    q_cold, q_hot, names, drift = _heat_flows(tmp_path, (R, R), 2.25 * R)
    assert "gas_gap_pair" in names
    assert q_cold == 0.0 and q_hot == 0.0


def test_without_gas_gap_a_near_pair_exchanges_nothing(tmp_path):
    # a gap of 1e-4 R: the gas would carry heat, the contact spot cannot
    q_cold, q_hot, names, drift = _heat_flows(tmp_path, (R, R), 2.0002 * R, gas=False)
    assert "gas_gap_pair" not in names
    assert q_cold == 0.0
    # nothing of it is allocated or listed: no margin on the pair reach, no model table
    text = _scene(tmp_path, (R, R), 2.0002 * R, gas=False)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert sim.engine.model.pair_margin == 0.0
        assert "gas_over_solid" not in sim.engine.table
    text = _scene(tmp_path, (R, R), 2.0002 * R, model="solid_resistance")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert sim.engine.model.pair_margin == pytest.approx(LENS)
        assert "gas_over_solid" in sim.engine.table


def test_gas_gap_pairs_false_keeps_only_the_walls(tmp_path):
    text = _scene(tmp_path, (R, R), 2.01 * R).replace("gas_gap = true\n",
                                                       "gas_gap = true\ngas_gap_pairs = false\n")
    with pytest.raises(taichi_dem.SceneError, match="thermal.gas_gap.*nothing to conduct"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")
