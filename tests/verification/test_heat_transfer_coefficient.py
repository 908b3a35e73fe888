"""The wall-to-bed heat transfer coefficient series of an isothermal body (issue 10 item 4):
/series bodies/<name>/heat_transfer_coefficient = heat_flow / (covered_area (T_bed - T_w)),
covered_area the area of the body's triangles a particle touches at the sample.

A bead resting under gravity on a box plate (whose top face is two triangles of 0.0128 m^2
each) touches exactly one triangle, so the covered area is that triangle's, and the coefficient
is the recorded heat flow over it and the temperature difference (the bead's heat capacity is
so large that its temperature stays at T_P). A body nobody touches has NaN (undefined), not 0.
"""
import math

import numpy as np

import taichi_dem

R = 0.01
T_P, T_W = 400.0, 300.0


def _scene(tmp_path, z):
    (tmp_path / "p.csv").write_text(f"x,y,z,radius\n0.02,0.03,{z!r},{R!r}\n")
    return f"""
[simulation]
end_time = 0.05
gravity = [0.0, 0.0, -9.81]
precision = "f64"
[domain]
min = [-0.1, -0.1, -0.05]
max = [0.1, 0.1, 0.1]
[materials.ash]
density = 870.0
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = 0.3
heat_capacity = 1e12
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = 45.0
heat_capacity = 480.0
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.3
friction = 0.5
[[interactions]]
pair = ["ash", "steel"]
restitution = 0.3
friction = 0.5
[[bodies]]
name = "plate"
material = "steel"
temperature = {T_W}
mesh = {{ builder = "box", min = [-0.08, -0.08, -0.02], max = [0.08, 0.08, 0.0], normals = "outward" }}
[[particles]]
material = "ash"
temperature = {T_P}
file = "p.csv"
[thermal]
conduction = false
wall_conduction = true
gas_gap = true
[output]
interval = 0.01
"""


def test_coefficient_of_a_bead_on_a_plate(tmp_path):
    with taichi_dem.Simulation.from_text(_scene(tmp_path, R * (1 - 1e-5)),
                                         base_dir=str(tmp_path), precision="f64") as sim:
        sim.run()
        s = sim.series
        area = np.asarray(s["bodies/plate/covered_area"])[1:]
        q = np.asarray(s["bodies/plate/heat_flow"])[1:]
        h = np.asarray(s["bodies/plate/heat_transfer_coefficient"])[1:]
        t_bed = np.asarray(s["particles/mean_temperature"])[1:]
    triangle = 0.5 * 0.16 * 0.16
    print(f"\n  covered {area[-1]:.6g} m^2, heat flow {q[-1]:.6g} W, h = {h[-1]:.6g} W/(m^2 K)")
    np.testing.assert_allclose(area, triangle, rtol=1e-12)
    np.testing.assert_allclose(t_bed, T_P, rtol=1e-12)
    assert np.all(q > 0.0)
    np.testing.assert_allclose(h, q / (triangle * (T_P - T_W)), rtol=1e-12)


def test_untouched_body_has_no_coefficient(tmp_path):
    # the bead falls from 3 cm: at the first samples nothing touches the plate
    with taichi_dem.Simulation.from_text(_scene(tmp_path, 0.04), base_dir=str(tmp_path),
                                         precision="f64") as sim:
        sim.run(0.01)
        s = sim.series
        assert s["bodies/plate/covered_area"][-1] == 0.0
        assert math.isnan(s["bodies/plate/heat_transfer_coefficient"][-1])
