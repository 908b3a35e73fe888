"""Conduction through the gas gap between a particle and a wall or body, in the engine
(issue 10 items 1-2, particle-fluid-wall part).

With `[thermal] gas_gap = true`, a particle within the fluid lens of an isothermal plane wall or
mesh body exchanges Q = (h_spot + k_g I(h)) (T_w - T_p), where I(h) is the lens integral of
thermal/gas_gap.py at the centre-surface distance h (touching or not) and h_spot the Hertz
spot conductance when it touches. The particle's heat capacity is made huge so its temperature
is constant over the sample; the recorded heat flow into the wall must then equal the formula
to the f64 round-off of the sums (1e-9 asserted). Beyond the lens nothing flows. Without
gas_gap nothing of it is compiled (the effect is absent, the mesh reach is the contact reach).
"""
import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.thermal import gas_gap

R = 0.01
K_P, K_W, K_G = 0.3, 45.0, 0.026
LENS, MIN_GAP = 0.2, 1e-6
T_P, T_W = 400.0, 300.0


def _scene(tmp_path, rows, wall, gas=True, fixed=True):
    lines = ["x,y,z,radius"] + [",".join(repr(float(c)) for c in (*p, R)) for p in rows]
    (tmp_path / "p.csv").write_text("\n".join(lines) + "\n")
    keys = (f"gas_gap = true\ngap_gas_conductivity = {K_G}\ngas_gap_lens = {LENS}\n"
            f"gas_gap_min_gap = {MIN_GAP}\ngas_gap_model = \"isothermal\"\n") if gas else ""
    return f"""
[simulation]
end_time = 0.01
dt = 1e-4
gravity = [0.0, 0.0, 0.0]
precision = "f64"
[domain]
min = [-0.1, -0.1, -0.05]
max = [0.1, 0.1, 0.1]
[materials.ash]
density = 870.0
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = {K_P}
heat_capacity = 1e12
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
{wall}
[[particles]]
material = "ash"
fixed = {"true" if fixed else "false"}
temperature = {T_P}
file = "p.csv"
[thermal]
conduction = false
wall_conduction = true
{keys}
[output]
interval = 0.005
"""


PLANE = f"""[[walls]]
name = "shell"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "steel"
temperature = {T_W}
"""

PLATE = f"""[[bodies]]
name = "plate"
material = "steel"
temperature = {T_W}
mesh = {{ builder = "box", min = [-0.08, -0.08, -0.02], max = [0.08, 0.08, 0.0], normals = "outward" }}
"""


def _expected(distance):
    spot = 0.0
    if distance < R:
        spot = 4 * K_P * K_W / (K_P + K_W) * math.sqrt(R * (R - distance))
    return (spot + K_G * gas_gap.plane_gap_integral_reference(R, distance, LENS, MIN_GAP)) * (T_P - T_W)


@pytest.mark.parametrize("relative", [1 - 1e-4, 1 + 1e-4, 1 + 1e-2, 1.1, 1.25])
def test_plane_wall_gas_gap_heat_flow(tmp_path, relative):
    distance = relative * R
    text = _scene(tmp_path, [(0.0, 0.0, distance)], PLANE)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert "gas_gap_wall" in {e.name for e in sim.effects}
        sim.run()
        q = sim.series["walls/shell/heat_flow"][1:]
    expected = _expected(distance)
    print(f"\n  h/R = {relative}: wall heat flow {q[-1]:.9e} W, model {expected:.9e} W")
    if relative > 1 + LENS:
        assert np.all(q == 0.0)
    else:
        assert expected > 0.0
        np.testing.assert_allclose(q, expected, rtol=1e-6)


@pytest.mark.parametrize("relative", [1 + 1e-3, 1.1])
def test_mesh_body_gas_gap_heat_flow(tmp_path, relative):
    # mesh contacts are for moving particles: a free particle at rest, without gravity, that
    # does not touch stays where it is
    distance = relative * R
    text = _scene(tmp_path, [(0.01, 0.02, distance)], PLATE, fixed=False)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run()
        q = sim.series["bodies/plate/heat_flow"][1:]
        z = sim.particles()["position"][0, 2]
    assert z == pytest.approx(distance, rel=1e-12)
    expected = _expected(distance)
    print(f"\n  body h/R = {relative}: heat flow {q[-1]:.9e} W, model {expected:.9e} W")
    np.testing.assert_allclose(q, expected, rtol=1e-6)


def test_without_gas_gap_nothing_is_compiled(tmp_path):
    text = _scene(tmp_path, [(0.01, 0.02, 1.05 * R)], PLATE, gas=False, fixed=False)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert "gas_gap_wall" not in {e.name for e in sim.effects}
        assert "gas_gap_wall" not in sim.engine.model.effect_names
        assert sim.engine.mesh.expand == pytest.approx(sim.engine.model.max_radius + sim.skin)
        sim.run()
        q = sim.series["bodies/plate/heat_flow"][1:]
    assert np.all(q == 0.0)          # not touching: no spot, and no gas gap


def test_gas_gap_keys_need_gas_gap(tmp_path):
    text = _scene(tmp_path, [(0.0, 0.0, 0.02)], PLANE, gas=False).replace(
        "wall_conduction = true\n", "wall_conduction = true\ngas_gap_lens = 0.3\n")
    with pytest.raises(taichi_dem.SceneError, match="thermal.gas_gap_lens.*gas_gap is off"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")
    text = _scene(tmp_path, [(0.0, 0.0, 0.02)], PLANE).replace(f"gas_gap_lens = {LENS}",
                                                               "gas_gap_lens = 2.0")
    with pytest.raises(taichi_dem.SceneError, match="thermal.gas_gap_lens.*at most 1"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")


def test_gas_gap_without_a_wall_to_conduct_to_is_refused(tmp_path):
    # the gas gap between particles is not in the step: a scene that would get nothing from
    # gas_gap is told so instead of silently running without it
    cold_wall = PLANE.replace(f"temperature = {T_W}\n", "")
    text = _scene(tmp_path, [(0.0, 0.0, 0.02)], cold_wall)
    with pytest.raises(taichi_dem.SceneError, match="thermal.gas_gap.*temperature"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")
    text = _scene(tmp_path, [(0.0, 0.0, 0.02)], PLANE).replace("wall_conduction = true",
                                                               "wall_conduction = false")
    with pytest.raises(taichi_dem.SceneError, match="thermal.gas_gap.*wall_conduction"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")
