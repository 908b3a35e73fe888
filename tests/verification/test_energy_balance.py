"""The particles' energy balance (issue 10 item 6): heat the particles lose (what the factory
brought in, minus what left, minus what is inside) equals the heat the isothermal body took
(the time integral of its recorded heat flow), in f64 and in f32 (the cooler demo's precision:
temperatures carry f64 residuals, engine/precision.py).

Hot beads are fed onto a cold plate, conduct to it through the contact spot and the gas gap,
to each other, and roll off its edge out of the domain (lost particles carry their m c T out).
Both sides are sums of the same per-step heat flows, so the difference is round-off: asserted
below 1e-6 of the heat moved in f64, 1e-3 in f32 (the issue asks 1 %), over ~40 % of the
beads' excess heat moved.
"""
import numpy as np
import pytest

import taichi_dem

SCENE = """
[simulation]
end_time = 0.6
gravity = [0.0, 0.0, -9.81]
precision = "{precision}"
[domain]
min = [-0.08, -0.08, -0.06]
max = [0.08, 0.08, 0.1]
[materials.ash]
density = 870.0
youngs_modulus = 1e6
poisson_ratio = 0.25
thermal_conductivity = 0.3
heat_capacity = 0.2          # J/(kg K): tiny, so that heat moves within the 0.6 s run
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = 45.0
heat_capacity = 480.0
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.3
friction = 0.4
[[interactions]]
pair = ["ash", "steel"]
restitution = 0.3
friction = 0.4
[[bodies]]
name = "plate"
material = "steel"
temperature = 300.0
mesh = {{ builder = "box", min = [-0.04, -0.04, -0.02], max = [0.04, 0.04, 0.0], normals = "outward" }}
[[factories]]
name = "feed"
material = "ash"
radius = 0.004
region = {{ box = {{ min = [-0.02, -0.02, 0.02], max = [0.02, 0.02, 0.05] }} }}
velocity = [0.3, 0.0, 0.0]
temperature = 700.0
mass_rate = [[0.0, "0.2 kg/s"], [0.3, "0 kg/s"]]
[thermal]
conduction = true
wall_conduction = true
gas_gap = true
[output]
interval = 0.05
"""


@pytest.mark.parametrize("precision,tolerance", [("f64", 1e-6), ("f32", 1e-3)])
def test_heat_lost_by_particles_is_heat_into_the_plate(tmp_path, precision, tolerance):
    text = SCENE.format(precision=precision)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision=precision) as sim:
        sim.run()
        s = sim.series
        loss = np.asarray(s["thermal/particle_heat_loss"])
        wall = np.asarray(s["thermal/wall_heat"])
        fed = s["thermal/energy_fed"][-1]
        removed = s["thermal/energy_removed"][-1]
        lost = sim.engine.lost
    excess = fed * (1.0 - 300.0 / 700.0)
    print(f"\n  {precision}: fed {fed:.6g} J, removed {removed:.6g} J ({lost} beads), "
          f"lost by particles {loss[-1]:.6g} J, into the plate {wall[-1]:.6g} J, "
          f"difference {abs(loss[-1] - wall[-1]) / wall[-1]:.2e}")
    assert lost > 0 and removed > 0.0          # beads rolled off and carried heat out
    assert wall[-1] > 0.2 * excess             # a good part of the excess heat moved
    np.testing.assert_allclose(loss[1:], wall[1:], rtol=tolerance, atol=tolerance * wall[-1])
