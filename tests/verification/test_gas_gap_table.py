"""The gas-gap tables (thermal/gas_gap.py "tables"; issue 14: the step looks the integral up
instead of integrating it at every contact, which was a third of the cooler demo's step).

1. Interpolation: between the nodes the table agrees with the brute-force reference (4000
   graded panels) to 1e-5 of the contact value, for both models, equal and unequal spheres
   and the plane (measured: 1e-6 - 4e-6). The tolerance is ten times below the 1e-4 the
   in-kernel Gauss-Legendre quadrature reaches (test_gas_gap.py), so the table is no coarser
   than what it replaces.
2. In the step: two particles exchange the same heat through the tables as through the
   quadrature (a scene whose particle kinds are not tabulated), to 1e-4.
3. Which scenes get tables: one per pair of particle kinds; none when a factory samples radii
   from a distribution.
"""
import math

import numpy as np
import pytest

import taichi_dem
import taichi_dem.run.simulation as simulation_module
from taichi_dem.thermal import gas_gap

from test_gas_gap_pair import _heat_flows, R

LENS, MIN_GAP = 0.2, 1e-6


def _check(values, separations, reference, contact):
    mid = 0.5 * (separations[:-1] + separations[1:])
    picks = mid[::9]
    exact = np.array([reference(s) for s in picks])
    looked_up = np.interp(picks, separations, values)
    return float(np.max(np.abs(looked_up - exact)) / contact)


@pytest.mark.parametrize("radii", [(0.015, 0.015), (0.001, 0.0015)])
@pytest.mark.parametrize("model", ["isothermal", "solid_resistance", "voronoi"])
def test_pair_table_interpolates_the_reference(radii, model):
    ri, rj = radii
    g = 0.026 / 0.3
    values = gas_gap.pair_table(ri, rj, LENS, MIN_GAP, model, g, g, 0.4)
    s = gas_gap.table_separations(min(radii), max(radii), LENS, MIN_GAP)
    assert len(values) == gas_gap.TABLE_NODES and s[gas_gap.TABLE_NODES_OVERLAP - 1] == 0.0
    if model == "isothermal":
        def reference(x):
            return gas_gap.pair_gap_integral_reference(ri, rj, ri + rj + x, LENS, MIN_GAP)
    elif model == "voronoi":
        def reference(x):
            return gas_gap.pair_voronoi_gap_integral_reference(ri, rj, ri + rj + x, LENS,
                                                                MIN_GAP, g, g, 0.4)
    else:
        def reference(x):
            return gas_gap.pair_solid_gap_integral_reference(ri, rj, ri + rj + x, LENS, MIN_GAP,
                                                              g, g)
    contact = values[gas_gap.TABLE_NODES_OVERLAP - 1]
    error = _check(values, s, reference, contact)
    print(f"\n  {model} {radii}: interpolation error {error:.2e} of the contact value")
    assert error < 1e-5
    # the last node is where the lens stops reaching the other sphere: nothing flows
    assert abs(values[-1]) < 1e-12 * contact and values[-2] > 1e-9 * contact


@pytest.mark.parametrize("model", ["solid_resistance", "voronoi"])
def test_plane_table_interpolates_the_reference(model):
    r, g = 0.015, 0.026 / 0.3
    values = gas_gap.plane_table(r, LENS, MIN_GAP, g, model, 0.4)
    s = gas_gap.table_separations(r, r, LENS, MIN_GAP)

    def reference(x):
        if model == "voronoi":
            return gas_gap.plane_voronoi_gap_integral_reference(r, r + x, LENS, MIN_GAP, g, 0.4)
        return gas_gap.plane_solid_gap_integral_reference(r, r + x, LENS, MIN_GAP, g)
    error = _check(values, s, reference, values[gas_gap.TABLE_NODES_OVERLAP - 1])
    print(f"\n  plane {model}: interpolation error {error:.2e} of the contact value")
    # the Voronoi cone's end r_sf moves with the distance (its integrand ends where the solid
    # path reaches zero): 1.4e-5 measured, still 10x under the step's 1e-4
    assert error < (3e-5 if model == "voronoi" else 1e-5)


@pytest.mark.parametrize("model,relative", [("isothermal", 1 - 1e-4), ("solid_resistance", 1.001),
                                            ("solid_resistance", 1 - 0.02), ("voronoi", 1.001),
                                            ("voronoi", 1 - 0.02)])
def test_the_step_through_the_tables_matches_the_quadrature(tmp_path, monkeypatch, relative,
                                                            model):
    distance = relative * 2 * R
    tabulated, _, _, _ = _heat_flows(tmp_path, (R, R), distance, model=model)
    monkeypatch.setattr(simulation_module, "_particle_species", lambda *a, **k: None)
    integrated, _, _, _ = _heat_flows(tmp_path, (R, R), distance, model=model)
    print(f"\n  {model} d/2R = {relative}: table {tabulated:.8e} W, quadrature {integrated:.8e} W")
    assert tabulated == pytest.approx(integrated, rel=1e-4)


def _kinds(text):
    scene = taichi_dem.scene.loader.parse_scene(text, source="<test>")
    from taichi_dem.setup.placement import place_fills
    from taichi_dem.setup.pair_tables import build_pair_tables
    placed = place_fills(scene, np.random.default_rng(0))
    return simulation_module._particle_species(scene, placed, build_pair_tables(scene).names)


SCENE = """
[simulation]
end_time = 0.01
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]
[materials.ash]
density = 870.0
youngs_modulus = 1e7
poisson_ratio = 0.25
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
[[particles]]
material = "ash"
radius = 0.01
count = 20
region = {{ box = {{ min = [-0.09, -0.09, -0.09], max = [0.0, 0.09, 0.09] }} }}
[[factories]]
name = "feed"
material = "ash"
{radius}
region = {{ box = {{ min = [0.02, -0.05, -0.05], max = [0.09, 0.05, 0.05] }} }}
mass_rate = "0.1 t/h"
"""


def test_kinds_of_a_scene():
    same = _kinds(SCENE.format(radius="radius = 0.01"))
    assert same == ((0, 0.01),)
    two = _kinds(SCENE.format(radius="radius = 0.006"))
    assert two == ((0, 0.006), (0, 0.01))
    spread = _kinds(SCENE.format(radius="radius = { mean = 0.006, std = 0.001, min = 0.004, "
                                        "max = 0.008 }"))
    assert spread is None
