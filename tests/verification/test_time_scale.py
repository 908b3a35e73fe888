"""Thermal time scaling (issue 10 item 3): ``[thermal] time_scale = S`` divides every heat
capacity by S, so heat moves S times faster than the mechanics and thermal time = S x
simulated time.

Exact case: a fixed particle pressed into an isothermal wall by a fixed overlap d has a
constant spot conductance H = 4 k_p k_w/(k_p + k_w) sqrt(R d), so its temperature relaxes as

    T(t) = T_w + (T_0 - T_w) exp(-H t / (m c))                     (lumped, exact)

and the explicit update gives T_n = T_w + (T_0 - T_w) (1 - x)^n with x = S H dt/(m c) at thermal
time S n dt. Asserted: the engine's temperatures equal that discrete solution to 1e-10 (so the
scaling is exactly S on the increment), lie within the Euler error bound n x^2/2 of the exact
curve at thermal time, and the /series thermal_time is S x time. What scaling costs in accuracy
where the mechanics matter (particles moving S times too slowly for their heat) is measured on
the cooler (BENCHMARKS.md), not here.
"""
import math

import numpy as np
import pytest

import taichi_dem

R, OVERLAP = 0.01, 1e-4
K_P, K_W = 0.3, 45.0
DENSITY, HEAT_CAPACITY = 870.0, 1000.0
T_0, T_W = 700.0, 300.0
DT, END = 1e-4, 0.2


def _scene(tmp_path, scale):
    (tmp_path / "p.csv").write_text(f"x,y,z,radius\n0.0,0.0,{R - OVERLAP!r},{R!r}\n")
    key = f"time_scale = {scale!r}\n" if scale != 1 else ""
    return f"""
[simulation]
end_time = {END}
dt = {DT}
gravity = [0.0, 0.0, -9.81]
precision = "f64"
[domain]
min = [-0.05, -0.05, -0.05]
max = [0.05, 0.05, 0.05]
[materials.ash]
density = {DENSITY}
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = {K_P}
heat_capacity = {HEAT_CAPACITY}
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = {K_W}
heat_capacity = 480.0
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["ash", "steel"]
restitution = 0.5
friction = 0.5
[[walls]]
name = "shell"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "steel"
temperature = {T_W}
[[particles]]
material = "ash"
fixed = true
temperature = {T_0}
file = "p.csv"
[thermal]
conduction = false
wall_conduction = true
{key}
[output]
interval = 0.05
"""


@pytest.mark.parametrize("scale", [1.0, 100.0, 1.0e4])
def test_time_scale_on_the_lumped_wall_case(tmp_path, scale):
    text = _scene(tmp_path, scale)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert sim.dt == DT
        sim.run()
        s = sim.series
        t = np.asarray(s["time"])
        temperature = np.asarray(s["particles/mean_temperature"])
        if scale != 1.0:
            np.testing.assert_allclose(s["thermal_time"], scale * t, rtol=1e-12)
            assert "thermal time" in next(e.description for e in sim.effects
                                          if e.name == "temperature")
        else:
            assert "thermal_time" not in s
    mass = DENSITY * 4.0 / 3.0 * math.pi * R ** 3
    conductance = 4 * K_P * K_W / (K_P + K_W) * math.sqrt(R * OVERLAP)
    x = scale * conductance * DT / (mass * HEAT_CAPACITY)
    steps = np.rint(t / DT)
    discrete = T_W + (T_0 - T_W) * (1.0 - x) ** steps
    exact = T_W + (T_0 - T_W) * np.exp(-conductance * scale * t / (mass * HEAT_CAPACITY))
    np.testing.assert_allclose(temperature, discrete, rtol=1e-10)
    euler_bound = steps * x * x / 2 * 1.01 + 1e-12
    assert np.all(np.abs(temperature - exact) <= euler_bound * (T_0 - T_W) + 1e-9)
    cooled = (T_0 - temperature[-1]) / (T_0 - T_W)
    print(f"\n  S = {scale:g}: cooled {cooled:.4f} of the way in {END} s simulated "
          f"({scale * END:g} s thermal); |T - exact| = {np.max(np.abs(temperature - exact)):.3e} K")
    assert cooled == pytest.approx(1.0 - math.exp(-conductance * scale * END / (mass * HEAT_CAPACITY)),
                                   rel=1e-3)


def test_time_scale_below_one_is_refused(tmp_path):
    text = _scene(tmp_path, 0.5)
    with pytest.raises(taichi_dem.SceneError, match="thermal.time_scale.*at least 1"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")


def test_a_time_scale_past_the_thermal_stability_limit_stops_the_run(tmp_path):
    # x = S H dt/(m c) = 33 for S = 1e9: the explicit update would blow up; the temperature
    # effect's check (thermal/effects.py) stops the run with the remedy
    text = _scene(tmp_path, 1.0e9)
    with pytest.raises(taichi_dem.DivergenceError, match="temperature update is unstable.*time_scale"):
        with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
            sim.run()
