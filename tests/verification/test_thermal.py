"""Heat transfer against analytic solutions (issue 4).

Conduction through a Hertz contact (PHYSICS.md, Batchelor & O'Brien as in EDEM):
Q = h_c (T_j - T_i), h_c = 4 k_i k_j/(k_i + k_j) a, a = sqrt(R* d) the Hertz contact radius,
times (E*_sim/E*_real)^x when a material gives its real modulus. The temperature update is
explicit Euler, T += dt Q/(m c): against exp(-lambda t) its relative error after time t is
about lambda^2 dt t / 2 - with lambda dt <= 1e-3 and t <= 2/lambda, below 2e-3 (asserted).

1. Two fixed, touching spheres equilibrate as dT(t) = dT0 exp(-h_c (1/(m1 c1) + 1/(m2 c2)) t),
   and sum m c T stays constant to round-off (the flows are antisymmetric by construction).
2. A sphere on an isothermal plate decays with tau = m c / h_c (wall: R* = R), and the wall's
   recorded heat flow is h_c (T - T_w).
3. Lumped convection: a sphere in a gas stream decays with tau = m c / (h A), h = k_g Nu / d,
   with Ranz-Marshall (Nu = 2 + 0.6 Re^1/2 Pr^1/3) and with Gunn (1978) at voidage 0.4.
4. A chain of 10 spheres between walls at two temperatures reaches a linear profile (equal
   contact conductances in series): second differences below 1e-6 of the span.
5. An adiabatic box of moving, colliding particles at two temperatures conserves sum m c T
   (1e-12 relative, f64).
6. The contact-radius correction: with E_real = 1000 E_sim the decay rate of test 1 scales by
   1000^(-1/3) = 0.1 ("static", the default: enduring contacts) or 1000^(-1/5) = 0.25
   ("collision", Morris et al. 2016) - what the choice changes, measured.
7. A scene without [thermal] allocates no temperature and compiles nothing thermal.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

R = 0.01
# a heat capacity scaled down (real glass: 800 J/(kg K)) so the analytic time constants are
# seconds, not hours; the analytic solutions hold for any c
RHO, C, K = 2500.0, 1.0, 1.0
E_SIM = 1.0e7


def _glass(extra=""):
    return (f"[materials.glass]\ndensity = {RHO}\nyoungs_modulus = {E_SIM}\npoisson_ratio = 0.25\n"
            f"thermal_conductivity = {K}\nheat_capacity = {C}\n{extra}\n")


def _steel():
    return ("[materials.steel]\ndensity = 7800.0\nyoungs_modulus = 2e11\npoisson_ratio = 0.3\n"
            "thermal_conductivity = 50.0\nheat_capacity = 500.0\n\n")


def _fixed_fill(tmp_path, name, positions, temperature, material="glass"):
    text = h.csv_fill(tmp_path, name, material, positions, R)
    return text.replace("file = ", f"fixed = true\ntemperature = {temperature}\nfile = ")


def _two_spheres(tmp_path, overlap, correction=None, real_e=None, dt=1e-3):
    thermal = "[thermal]\nconduction = true\n"
    if correction:
        thermal += f"contact_radius_correction = \"{correction}\"\n"
    extra = f"real_youngs_modulus = {real_e}\n" if real_e else ""
    text = (h.header(dt=dt, lo=(-0.05,) * 3, hi=(0.05,) * 3, output_interval=0.5)
            + _glass(extra) + h.interaction("glass", "glass", 0.5, 0.5)
            + _fixed_fill(tmp_path, "a.csv", [[0.0, 0.0, 0.0]], 300.0)
            + _fixed_fill(tmp_path, "b.csv", [[2 * R - overlap, 0.0, 0.0]], 400.0)
            + thermal)
    return taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")


def _mass():
    return 4.0 / 3.0 * math.pi * R ** 3 * RHO


def test_two_spheres_equilibrate(tmp_path):
    overlap = 1e-4
    h_c = 4 * K * K / (2 * K) * math.sqrt(R / 2 * overlap)
    rate = h_c * 2.0 / (_mass() * C)
    with _two_spheres(tmp_path, overlap) as sim:
        e0 = sim.thermal_energy()
        assert rate * sim.dt < 1e-3
        t_end = 2.0 / rate
        sim.step(int(round(t_end / sim.dt)))
        T = sim.particles()["temperature"]
        e1 = sim.thermal_energy()
    expected = 100.0 * math.exp(-rate * sim.time)
    print(f"\n  two spheres: dT = {T[1] - T[0]:.5f} K at t = {sim.time:.1f} s, analytic {expected:.5f} K;"
          f" sum m c T changed by {abs(e1 / e0 - 1):.1e}")
    assert T[1] - T[0] == pytest.approx(expected, rel=2e-3)
    assert abs(e1 / e0 - 1) < 1e-12


def test_sphere_on_isothermal_plate(tmp_path):
    overlap, t_wall = 1e-4, 350.0
    k_eff = 4 * K * 50.0 / (K + 50.0)
    h_c = k_eff * math.sqrt(R * overlap)
    tau = _mass() * C / h_c
    text = (h.header(dt=1e-3, lo=(-0.05,) * 3, hi=(0.05,) * 3, output_interval=0.5)
            + _glass() + _steel() + h.interaction("glass", "glass", 0.5, 0.5)
            + h.interaction("glass", "steel", 0.5, 0.5)
            + h.wall("plate", (0, 0, 0), (0, 0, 1), "steel").replace("material = \"steel\"",
                                                                      f"material = \"steel\"\ntemperature = {t_wall}")
            + _fixed_fill(tmp_path, "s.csv", [[0.0, 0.0, R - overlap]], 300.0)
            + "[thermal]\nwall_conduction = true\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(round(tau / 0.5) * 0.5)         # end on an output sample
        T = sim.particles()["temperature"][0]
        q = sim.series["walls/plate/heat_flow"][-1]
    expected = t_wall + (300.0 - t_wall) * math.exp(-sim.time / tau)
    print(f"\n  plate: T = {T:.4f} K at t = {sim.time:.1f} s (tau = {tau:.2f} s), analytic {expected:.4f} K; heat into "
          f"the plate {q:.5f} W, h_c (T - T_w) = {h_c * (T - t_wall):.5f} W")
    assert T - t_wall == pytest.approx(expected - t_wall, rel=2e-3)
    # recorded in the last step, before its update: h_c (T_before - T_w), T_before - T_w =
    # (T - T_w)(1 + dt/tau)
    assert q == pytest.approx(h_c * (T - t_wall) * (1 + sim.dt / tau), rel=1e-6)


@pytest.mark.parametrize("correlation", ["ranz_marshall", "gunn"])
def test_lumped_convection(tmp_path, correlation):
    u, t_gas, eps = 2.0, 500.0, 0.4
    gas = dict(density=1.177, viscosity=1.846e-5, conductivity=0.02624, heat_capacity=1007.0)
    d = 2 * R
    re = gas["density"] * d * u / gas["viscosity"]
    pr = gas["heat_capacity"] * gas["viscosity"] / gas["conductivity"]
    if correlation == "gunn":
        nu = ((7 - 10 * eps + 5 * eps ** 2) * (1 + 0.7 * re ** 0.2 * pr ** (1 / 3))
              + (1.33 - 2.4 * eps + 1.2 * eps ** 2) * re ** 0.7 * pr ** (1 / 3))
    else:
        nu = 2 + 0.6 * math.sqrt(re) * pr ** (1 / 3)
    hA = gas["conductivity"] * nu / d * math.pi * d * d
    tau = _mass() * C / hA
    text = (h.header(dt=2e-5, lo=(-0.05,) * 3, hi=(0.05,) * 3, output_interval=0.01)
            + _glass() + h.interaction("glass", "glass", 0.5, 0.5)
            + _fixed_fill(tmp_path, "g.csv", [[0.0, 0.0, 0.0]], 300.0)
            + f"[thermal]\n[thermal.gas]\nmodel = \"fixed\"\ntemperature = {t_gas}\n"
              f"velocity = [{u}, 0.0, 0.0]\ncorrelation = \"{correlation}\"\nporosity = {eps}\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(tau)
        T = sim.particles()["temperature"][0]
    expected = t_gas + (300.0 - t_gas) * math.exp(-sim.time / tau)
    assert hA * sim.dt / (_mass() * C) < 1e-3
    print(f"\n  convection ({correlation}): Re {re:.0f}, Nu {nu:.2f}, tau {tau:.3f} s; T = {T:.3f} K, analytic {expected:.3f} K")
    assert T - t_gas == pytest.approx(expected - t_gas, rel=2e-3)


def test_chain_between_two_walls_reaches_a_linear_profile(tmp_path):
    n, overlap = 10, 1e-4
    xs = [R - overlap + k * (2 * R - overlap) for k in range(n)]
    right = xs[-1] + R - overlap
    text = (h.header(dt=1e-3, lo=(-0.05, -0.05, -0.05), hi=(0.25, 0.05, 0.05), output_interval=5.0)
            + _glass().replace(f"thermal_conductivity = {K}", "thermal_conductivity = 100.0")
            + _steel() + h.interaction("glass", "glass", 0.5, 0.5) + h.interaction("glass", "steel", 0.5, 0.5)
            + h.wall("hot", (0, 0, 0), (1, 0, 0), "steel").replace("material = \"steel\"", "material = \"steel\"\ntemperature = 400.0")
            + h.wall("cold", (right, 0, 0), (-1, 0, 0), "steel").replace("material = \"steel\"", "material = \"steel\"\ntemperature = 300.0")
            + _fixed_fill(tmp_path, "chain.csv", [[x, 0.0, 0.0] for x in xs], 350.0)
            + "[thermal]\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(30.0)                        # the slowest mode decays in ~1.5 s
        T = sim.particles()["temperature"]
    second = np.diff(T, 2)
    print(f"\n  chain: T = {np.round(T, 3)}; largest second difference {np.abs(second).max():.2e} K")
    assert np.all(np.diff(T) < 0)
    assert np.abs(second).max() < 1e-6 * 100.0


def test_adiabatic_box_conserves_heat(tmp_path, small_scene_text):
    text = small_scene_text(count=150).replace("poisson_ratio = 0.25", "poisson_ratio = 0.25\n"
                                               "thermal_conductivity = 1.0\nheat_capacity = 800.0")
    text = text.replace("count = 150\n", "count = 150\ntemperature = 300.0\n")
    text += ("[[particles]]\nmaterial = \"glass\"\nradius = 0.004\ncount = 100\ntemperature = 400.0\n"
             "region = { box = { min = [-0.04, -0.04, 0.11], max = [0.04, 0.04, 0.19] } }\n"
             "[thermal]\n")
    for name, point, normal in (("left", (-0.045, 0, 0), (1, 0, 0)), ("right", (0.045, 0, 0), (-1, 0, 0)),
                                ("front", (0, -0.045, 0), (0, 1, 0)), ("back", (0, 0.045, 0), (0, -1, 0))):
        text += h.wall(name, point, normal, "steel")
    with taichi_dem.Simulation.from_text(text) as sim:
        e0 = sim.thermal_energy()
        t0 = sim.particles()["temperature"].std()
        sim.run(0.3)
        e1 = sim.thermal_energy()
        t1 = sim.particles()["temperature"].std()
        assert sim.series["particles/lost"][-1] == 0
    print(f"\n  adiabatic box: sum m c T changed by {abs(e1 / e0 - 1):.1e}; temperature spread "
          f"{t0:.2f} -> {t1:.2f} K")
    assert abs(e1 / e0 - 1) < 1e-12
    assert t1 < t0                       # heat did flow between the two fills


@pytest.mark.parametrize("mode, factor", [("static", 1000 ** (-1 / 3)), ("collision", 1000 ** (-1 / 5)),
                                          ("none", 1.0)])
def test_contact_radius_correction(tmp_path, mode, factor):
    overlap = 1e-4
    h_c = 2 * K * math.sqrt(R / 2 * overlap) * factor
    rate = h_c * 2.0 / (_mass() * C)
    with _two_spheres(tmp_path, overlap, correction=mode, real_e=1000 * E_SIM) as sim:
        sim.step(int(round(1.0 / rate / sim.dt)))
        T = sim.particles()["temperature"]
    expected = 100.0 * math.exp(-rate * sim.time)
    print(f"\n  correction {mode}: h_c x {factor:.3f}; dT {T[1] - T[0]:.4f} K, analytic {expected:.4f} K")
    assert T[1] - T[0] == pytest.approx(expected, rel=2e-3)


def test_no_thermal_allocates_nothing(small_scene_text):
    with taichi_dem.Simulation.from_text(small_scene_text()) as sim:
        assert not hasattr(sim.engine.state, "temperature")
        assert sim.engine.pairs.partner_heat is None
        assert not any(e.name in ("temperature", "conduction", "convection", "wall_conduction")
                       for e in sim.effects)
        assert "particles/mean_temperature" not in sim.series
