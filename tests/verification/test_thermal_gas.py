"""Plug-flow gas, radiation and drying against analytic solutions (issue 4, second part).

Plug-flow gas (thermal/plug_flow.py): the quasi-steady gas passes each cell's particles of
mean temperature T_pc and leaves at T_out = T_pc + (T_in - T_pc) exp(-G_c/(m_dot c_g)),
G_c = sum h_i A_i of the cell, marching from the inlet; the particles receive exactly what the
gas loses.
  (a) energy: the particles' gain sum C T (+ the vapour's enthalpy when they dry) equals the
      integrated m_dot c_g (T_in - T_out), to round-off (f64; the relative tolerance 1e-9 of
      the heat exchanged covers ~1e4 steps of f64 sums);
  (b) particles of huge thermal mass at one temperature: the cell exit temperatures are
      T_p + (T_in - T_p) exp(-k NTU), k = 1..N counted from the inlet (closed form, 1e-10);
  (c) co- and counter-current: with cell temperatures rising along the axis, the profile is
      the march from the inlet end the scene names (both directions, 1e-10); particles
      outside the axial span exchange nothing.
Radiation: a lumped particle in an enclosure at T_w, m c dT/dt = eps sigma A (T_w^4 - T^4),
  has the implicit solution t(T) = m c / (4 eps sigma A T_w^3) [ln((T_w + T)/(T_w - T))
  + 2 atan(T/T_w)] from T0 to T; explicit Euler with rate dt < 3e-4 keeps t within 1e-3 (an
  enclosure temperature, and a hot wall with a region that leaves a second particle out).
  Radiating to a fixed gas adds to convection (t(T) by quadrature); to a plug-flow gas, the
  particle sees its cell's gas temperature (one explicit step checked exactly).
Drying: a wet particle in a hot fixed gas heats as exp(-t hA/C_wet), C_wet = m (c + X0 c_w),
  to T_e, holds there for t_dry = X0 m L / (hA (T_g - T_e)), its moisture falling linearly,
  then heats as exp(-t hA/(m c)).
Heat capacities and latent heats are scaled down so the time constants are a fraction of a
second; the analytic solutions hold for any values.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.scene.loader import parse_scene
from taichi_dem.errors import SceneError
import dem_helpers as h

R = 0.01
RHO = 2500.0
SIGMA = 5.670374419e-8
AIR = dict(density=1.177, viscosity=1.846e-5, conductivity=0.02624, heat_capacity=1007.0)


def _mass():
    return 4.0 / 3.0 * math.pi * R ** 3 * RHO


def _material(name, c, extra=""):
    return (f"[materials.{name}]\ndensity = {RHO}\nyoungs_modulus = 1e7\npoisson_ratio = 0.25\n"
            f"thermal_conductivity = 1.0\nheat_capacity = {c!r}\n{extra}\n")


def _fill(tmp_path, name, material, positions, temperature, extra=""):
    text = h.csv_fill(tmp_path, name, material, positions, R)
    return text.replace("file = ", f"fixed = true\ntemperature = {temperature!r}\n{extra}file = ")


def _ranz_marshall_hA(speed):
    re = AIR["density"] * 2 * R * speed / AIR["viscosity"]
    pr = AIR["heat_capacity"] * AIR["viscosity"] / AIR["conductivity"]
    nu = 2 + 0.6 * math.sqrt(re) * pr ** (1 / 3)
    return AIR["conductivity"] * nu / (2 * R) * math.pi * (2 * R) ** 2


# ------------------------------------------------------------------------------ plug flow
MDOT, AREA, T_IN, CELLS, LENGTH = 1e-4, 1e-3, 600.0, 5, 0.5


def _plug_gas(flow="along_axis", axis=(1, 0, 0), point=(0, 0, 0), length=LENGTH, cells=CELLS):
    return (f"[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_point = {h.vec(point)}\n"
            f"axis_direction = {h.vec(axis)}\nlength = {length}\ncells = {cells}\n"
            f"flow_area = {AREA}\nmass_flow = \"{MDOT * 1000} g/s\"\ninlet_temperature = {T_IN}\n"
            f"flow = \"{flow}\"\n")


def _cells_scene(tmp_path, flow, cell_temperatures):
    """Two fixed particles of huge thermal mass per cell (their temperatures stay put), one
    ordinary particle before the span."""
    text = (h.header(dt=1e-3, lo=(-0.1, -0.05, -0.05), hi=(0.6, 0.05, 0.05), output_interval=0.01)
            + _material("hot", 1e12) + _material("glass", 1.0)
            + h.all_interactions(["glass", "hot"], 0.5, 0.5))
    for k, t in enumerate(cell_temperatures):
        x0 = k * LENGTH / CELLS
        text += _fill(tmp_path, f"c{k}.csv", "hot", [[x0 + 0.03, 0, 0], [x0 + 0.07, 0, 0]], t)
    text += _fill(tmp_path, "out.csv", "glass", [[-0.05, 0, 0]], 300.0)
    text += "[thermal]\n" + _plug_gas(flow)
    return taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")


def _march(cell_temperatures, g_cell, flow):
    """The exit temperature of each cell (cells in axis order) marching from the inlet."""
    order = range(len(cell_temperatures)) if flow == "along_axis" else reversed(range(len(cell_temperatures)))
    out = np.zeros(len(cell_temperatures))
    t = T_IN
    for c in order:
        tp = cell_temperatures[c]
        t = tp + (t - tp) * math.exp(-g_cell / (MDOT * AIR["heat_capacity"]))
        out[c] = t
    return out


@pytest.mark.parametrize("sums", ["blocks", "atomics"])
def test_plug_flow_profile_at_one_particle_temperature(tmp_path, monkeypatch, sums):
    """Both ways of summing per cell: per-block rows (CPU) and atomic adds (the GPU path,
    forced here on the CPU)."""
    if sums == "atomics":
        from taichi_dem.thermal import plug_flow
        monkeypatch.setattr(plug_flow, "BLOCKS", 0)
    tp = 350.0
    g_cell = 2 * _ranz_marshall_hA(MDOT / (AIR["density"] * AREA))
    ntu = g_cell / (MDOT * AIR["heat_capacity"])
    with _cells_scene(tmp_path, "along_axis", [tp] * CELLS) as sim:
        assert sim.engine.model.effect("plug_flow_convection").stream.blocks == (0 if sums == "atomics" else 64)
        sim.step(10)
        profile = sim.series["gas/temperature"][-1]
        outlet = sim.series["gas/outlet_temperature"][-1]
        q = sim.series["gas/heat_flow"][-1]
    closed = tp + (T_IN - tp) * np.exp(-ntu * np.arange(1, CELLS + 1))
    print(f"\n  plug flow, NTU per cell {ntu:.3f}: exit temperatures {np.round(profile, 4)}, "
          f"closed form {np.round(closed, 4)}")
    assert profile == pytest.approx(closed, rel=1e-10)
    assert outlet == pytest.approx(closed[-1], rel=1e-12)
    assert q == pytest.approx(MDOT * AIR["heat_capacity"] * (T_IN - closed[-1]), rel=1e-10)


@pytest.mark.parametrize("flow", ["along_axis", "against_axis"])
def test_plug_flow_direction(tmp_path, flow):
    temps = [300.0, 350.0, 400.0, 450.0, 500.0]
    g_cell = 2 * _ranz_marshall_hA(MDOT / (AIR["density"] * AREA))
    with _cells_scene(tmp_path, flow, temps) as sim:
        sim.step(10)
        profile = sim.series["gas/temperature"][-1]
        outlet = sim.series["gas/outlet_temperature"][-1]
        outside = sim.particles()["temperature"][-1]
        assert sim.series["gas/transferred_heat"][-1] == pytest.approx(
            sim.series["gas/heat_flow"][-1] * sim.time, rel=1e-10)
    expected = _march(temps, g_cell, flow)
    other = _march(temps, g_cell, "against_axis" if flow == "along_axis" else "along_axis")
    print(f"\n  {flow}: exit temperatures {np.round(profile, 3)}; outlet {outlet:.3f} K "
          f"(the other direction gives {np.round(other, 3)})")
    assert profile == pytest.approx(expected, rel=1e-10)
    assert outlet == pytest.approx(expected[-1] if flow == "along_axis" else expected[0], rel=1e-12)
    assert abs(outlet - (other[-1] if flow == "against_axis" else other[0])) > 1.0
    assert outside == 300.0                  # outside the span: no exchange at all


def _box_scene(small_scene_text, wet: bool):
    """250 moving, colliding particles in a walled box with a plug-flow gas down its height."""
    text = small_scene_text(count=150).replace("poisson_ratio = 0.25", "poisson_ratio = 0.25\n"
                                               "thermal_conductivity = 1.0\nheat_capacity = 8.0")
    moist = "moisture = 0.05\n" if wet else ""
    text = text.replace("count = 150\n", f"count = 150\ntemperature = 325.0\n{moist}")
    text += ("[[particles]]\nmaterial = \"glass\"\nradius = 0.004\ncount = 100\ntemperature = 300.0\n"
             "region = { box = { min = [-0.04, -0.04, 0.11], max = [0.04, 0.04, 0.19] } }\n")
    for name, point, normal in (("left", (-0.045, 0, 0), (1, 0, 0)), ("right", (0.045, 0, 0), (-1, 0, 0)),
                                ("front", (0, -0.045, 0), (0, 1, 0)), ("back", (0, 0.045, 0), (0, -1, 0))):
        text += h.wall(name, point, normal, "steel")
    text += "[thermal]\nevaporation_temperature = 330.0\nlatent_heat = \"20 kJ/kg\"\nwater_heat_capacity = 40.0\n"
    # the gas enters at the floor, through the (wet) lower fill first
    text += _plug_gas("along_axis", axis=(0, 0, 1), point=(0, 0, 0), length=0.2, cells=8)
    return taichi_dem.Simulation.from_text(text)


@pytest.mark.parametrize("wet", [False, True])
def test_plug_flow_energy_balance(small_scene_text, wet):
    with _box_scene(small_scene_text, wet) as sim:
        e0 = sim.thermal_energy()
        sim.step(30 * sim.output_every)          # ends on a sample: the series are current
        e1 = sim.thermal_energy()
        s = sim.series
        given = s["gas/transferred_heat"][-1]
        assert s["particles/lost"][-1] == 0
        vapour = 0.0
        if wet:
            th = sim.scene.settings.get("thermal")
            evaporated = s["particles/evaporated_mass"][-1] - s["particles/evaporated_mass"][0]
            vapour = evaporated * (th.latent_heat + th.water_heat_capacity * th.evaporation_temperature)
            assert evaporated > 0 and s["particles/mean_moisture"][-1] < s["particles/mean_moisture"][0]
    print(f"\n  plug-flow energy ({'wet' if wet else 'dry'}): gas gave {given:.6f} J; particles "
          f"gained {e1 - e0:.6f} J sensible + {vapour:.6f} J with the vapour; mismatch "
          f"{abs(e1 - e0 + vapour - given) / given:.1e}; outlet {s['gas/outlet_temperature'][-1]:.2f} K")
    assert given > 1.0
    assert e1 - e0 + vapour == pytest.approx(given, rel=1e-9)
    # the run's own balance books the vapour (Drying.energy_terms): it closes as this one does
    assert -s["thermal/source_heat"][-1] == pytest.approx(vapour, rel=1e-12, abs=1e-12)
    loss = s["thermal/particle_heat_loss"][-1]
    booked = s["thermal/wall_heat"][-1] - s["thermal/gas_heat"][-1] - s["thermal/source_heat"][-1]
    assert loss == pytest.approx(booked, rel=1e-9)


# ------------------------------------------------------------------------------ radiation
def _radiation_time(t0, t, tw, k):
    """t(T) of m c dT/dt = k (T_w^4 - T^4), k = eps sigma A / (m c)."""
    def f(x):
        return math.log((tw + x) / (tw - x)) + 2 * math.atan(x / tw)
    return (f(t) - f(t0)) / (4 * k * tw ** 3)


@pytest.mark.parametrize("source", ["enclosure", "wall"])
def test_radiation_lumped(tmp_path, source):
    eps, c, tw, t0 = 0.9, 100.0, 1000.0, 300.0
    k = eps * SIGMA * 4 * math.pi * R ** 2 / (_mass() * c)
    text = (h.header(dt=1e-3, lo=(-0.1, -0.1, -0.1), hi=(0.1, 0.1, 0.1), output_interval=0.5)
            + _material("glass", c, f"emissivity = {eps}") + _material("steel", 500.0)
            + h.all_interactions(["glass", "steel"], 0.5, 0.5)
            + _fill(tmp_path, "p.csv", "glass", [[0, 0, 0], [0.05, 0, 0]], t0))
    if source == "wall":
        text += h.wall("burner", (0, 0, -0.09), (0, 0, 1), "steel").replace(
            'material = "steel"', f'material = "steel"\ntemperature = "{tw - 273.15} C"')
        text += ("[thermal]\nradiation = true\nradiation_to = \"burner\"\n"
                 "radiation_region = { box = { min = [-0.02, -0.02, -0.02], max = [0.02, 0.02, 0.02] } }\n")
    else:
        text += f"[thermal]\nradiation = true\nradiation_to = {tw}\n"
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert 4 * k * tw ** 3 * sim.dt < 3e-4
        e0 = sim.thermal_energy()
        sim.run(6.0)
        temps = sim.particles()["temperature"]
        gained = sim.thermal_energy() - e0
        radiated = sim.series["thermal/radiated_heat"][-1]
        balance = sim.series["thermal/particle_heat_loss"][-1] + sim.series["thermal/source_heat"][-1]
    # every joule the particles gained came by radiation, and the run books it (to f64 sums)
    assert radiated == pytest.approx(gained, rel=1e-9)
    assert abs(balance) < 1e-9 * gained
    analytic = _radiation_time(t0, temps[0], tw, k)
    print(f"\n  radiation ({source}): T = {temps[0]:.3f} K at t = {sim.time:.3f} s; the analytic "
          f"t(T) = {analytic:.4f} s; second particle {temps[1]:.3f} K")
    assert temps[0] > 600.0
    assert analytic == pytest.approx(sim.time, rel=1e-3)
    if source == "wall":
        assert temps[1] == t0                # outside radiation_region
    else:
        assert temps[1] == pytest.approx(temps[0], rel=1e-12)


def test_radiation_to_the_gas_adds_to_convection(tmp_path):
    """radiation_to = "gas" with a fixed gas: C dT/dt = hA (T_g - T) + eps sigma A (T_g^4 - T^4),
    t(T) = integral of C dT / (...) by the trapezoid rule on 20001 points (error ~1e-9)."""
    eps, c, t_gas, t0, u = 0.8, 100.0, 1200.0, 300.0, 1.0
    hA = _ranz_marshall_hA(u)
    k_rad = eps * SIGMA * 4 * math.pi * R ** 2
    text = (h.header(dt=1e-3, lo=(-0.1,) * 3, hi=(0.1,) * 3, output_interval=0.5)
            + _material("glass", c, f"emissivity = {eps}") + h.interaction("glass", "glass", 0.5, 0.5)
            + _fill(tmp_path, "p.csv", "glass", [[0, 0, 0]], t0)
            + f"[thermal]\nradiation = true\nradiation_to = \"gas\"\n[thermal.gas]\n"
              f"temperature = \"{t_gas - 273.15} C\"\nvelocity = [{u}, 0, 0]\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(4.0)
        temp = sim.particles()["temperature"][0]
    grid = np.linspace(t0, temp, 20001)
    rate = (hA * (t_gas - grid) + k_rad * (t_gas ** 4 - grid ** 4)) / (_mass() * c)
    f = 1.0 / rate
    t_of_T = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(grid)))
    without = (_mass() * c / hA) * math.log((t_gas - t0) / (t_gas - temp))
    print(f"\n  radiation to the gas + convection: T = {temp:.3f} K at t = {sim.time:.3f} s; t(T) by "
          f"quadrature {t_of_T:.4f} s (convection alone would take {without:.3f} s)")
    assert t_of_T == pytest.approx(sim.time, rel=1e-3)
    assert without > 1.5 * sim.time                   # radiation does matter here


def test_radiation_to_the_plug_flow_gas_of_the_cell(tmp_path):
    """radiation_to = "gas" with a plug-flow gas: a lone particle in the first cell sees the
    cell's gas temperature T_gc = T_p + (T_in - T_p)(1 - e^-NTU)/NTU, by convection and by
    radiation; one step of the explicit update is T += dt (G (T_gc - T) + eps sigma A (T_gc^4 -
    T^4)) / (m c) exactly (1e-12). A particle outside the span gets neither."""
    eps, c, t0 = 0.9, 100.0, 400.0
    text = (h.header(dt=1e-3, lo=(-0.1, -0.05, -0.05), hi=(0.6, 0.05, 0.05), output_interval=0.01)
            + _material("glass", c, f"emissivity = {eps}") + h.interaction("glass", "glass", 0.5, 0.5)
            + _fill(tmp_path, "p.csv", "glass", [[0.05, 0, 0], [-0.05, 0, 0]], t0)
            + "[thermal]\nradiation = true\nradiation_to = \"gas\"\n" + _plug_gas())
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.step(1)
        temps = sim.particles()["temperature"]
    g = _ranz_marshall_hA(MDOT / (AIR["density"] * AREA))
    ntu = g / (MDOT * AIR["heat_capacity"])
    t_gc = t0 + (T_IN - t0) * (1 - math.exp(-ntu)) / ntu
    q = g * (t_gc - t0) + eps * SIGMA * 4 * math.pi * R ** 2 * (t_gc ** 4 - t0 ** 4)
    expected = t0 + sim.dt * q / (_mass() * c)
    print(f"\n  radiation to the plug-flow gas: cell gas {t_gc:.3f} K; after one step T = {temps[0]:.9f} K, "
          f"expected {expected:.9f} K")
    assert temps[0] == pytest.approx(expected, rel=1e-12)
    assert temps[1] == t0


# ------------------------------------------------------------------------------ drying
def test_drying_holds_at_evaporation_temperature(tmp_path):
    u, t_gas, t0, t_evap = 2.0, 500.0, 300.0, 373.15
    c, c_water, x0 = 1.0, 4.0, 0.1
    m = _mass()
    hA = _ranz_marshall_hA(u)
    latent = hA * (t_gas - t_evap) * 0.5 / (x0 * m)       # dries in 0.5 s
    c_wet = m * (c + x0 * c_water)
    t1 = c_wet / hA * math.log((t_gas - t0) / (t_gas - t_evap))
    t_dry = x0 * m * latent / (hA * (t_gas - t_evap))
    tau_dry = m * c / hA
    text = (h.header(dt=5e-5, lo=(-0.05,) * 3, hi=(0.05,) * 3, output_interval=0.01)
            + _material("glass", c) + h.interaction("glass", "glass", 0.5, 0.5)
            + _fill(tmp_path, "w.csv", "glass", [[0, 0, 0]], t0, extra=f"moisture = {x0}\n")
            + f"[thermal]\nlatent_heat = {latent!r}\nwater_heat_capacity = {c_water}\n"
              f"[thermal.gas]\ntemperature = {t_gas}\nvelocity = [{u}, 0.0, 0.0]\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        assert "drying" in {e.name for e in sim.effects}
        sim.run(t1 + t_dry + 0.3)
        s = sim.series
    t, T, X = s["time"], s["particles/mean_temperature"], s["particles/mean_moisture"]
    heating = t < t1 - 0.01
    drying = (t > t1 + 0.01) & (t < t1 + t_dry - 0.01)
    after = t > t1 + t_dry + 0.01
    wet_T = t_gas - (t_gas - t0) * np.exp(-t[heating] * hA / c_wet)
    dry_X = x0 - hA * (t_gas - t_evap) * (t[drying] - t1) / (m * latent)
    dry_T = t_gas - (t_gas - t_evap) * np.exp(-(t[after] - t1 - t_dry) / tau_dry)
    done = t[np.argmax(X <= 0.0)]
    print(f"\n  drying: reaches T_e at {t1:.3f} s, dries in {t_dry:.3f} s (analytic); moisture 0 "
          f"first sampled at {done:.3f} s (expected {t1 + t_dry:.3f} s); evaporated "
          f"{s['particles/evaporated_mass'][-1]:.6e} kg of {x0 * m:.6e} kg")
    assert np.all(T[drying] == pytest.approx(t_evap, abs=1e-9))
    assert T[heating] - t_gas == pytest.approx(wet_T - t_gas, rel=2e-3)
    assert X[drying] == pytest.approx(dry_X, abs=2e-3 * x0)
    assert T[after] - t_gas == pytest.approx(dry_T - t_gas, rel=2e-3)
    assert abs(done - (t1 + t_dry)) <= 0.011          # one output interval
    assert s["particles/evaporated_mass"][-1] == pytest.approx(x0 * m, rel=1e-12)


def test_drying_falling_rate_follows_its_ode(tmp_path):
    """[thermal] critical_moisture: below X_cr a fraction X / X_cr of the heat evaporates water
    and the rest warms the particle. Once at T_e the particle follows
        C(X) dT/dt = Q - m' (L + c_w (T_e - T)),   m dX/dt = -m',   m' = (X / X_cr) Q / L,
    Q = hA (T_g - T), C = m (c + X c_w) (the enthalpy balance of moisture.py in continuous
    form), integrated here by scipy (rtol 1e-10); the run's explicit steps agree to 2e-3 as the
    constant-rate test's do."""
    from scipy.integrate import solve_ivp
    u, t_gas, t0, t_evap = 2.0, 500.0, 300.0, 373.15
    c, c_water, x0, x_cr = 1.0, 4.0, 0.1, 0.2
    m = _mass()
    hA = _ranz_marshall_hA(u)
    latent = hA * (t_gas - t_evap) * 0.5 / (x0 * m)
    c_wet = m * (c + x0 * c_water)
    t1 = c_wet / hA * math.log((t_gas - t0) / (t_gas - t_evap))     # reaches T_e, still wet

    def rates(_, y):
        temperature, x = y
        q = hA * (t_gas - temperature)
        vapour = x / x_cr * q / latent if x > 0.0 else 0.0
        return [(q - vapour * (latent + c_water * (t_evap - temperature))) / (m * (c + x * c_water)),
                -vapour / m]

    text = (h.header(dt=5e-5, lo=(-0.05,) * 3, hi=(0.05,) * 3, output_interval=0.01)
            + _material("glass", c) + h.interaction("glass", "glass", 0.5, 0.5)
            + _fill(tmp_path, "w.csv", "glass", [[0, 0, 0]], t0, extra=f"moisture = {x0}\n")
            + f"[thermal]\nlatent_heat = {latent!r}\nwater_heat_capacity = {c_water}\n"
              f"critical_moisture = {x_cr}\n"
              f"[thermal.gas]\ntemperature = {t_gas}\nvelocity = [{u}, 0.0, 0.0]\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(t1 + 1.5)
        s = sim.series
    t, T, X = s["time"], s["particles/mean_temperature"], s["particles/mean_moisture"]
    after = t > t1 + 0.01
    ode = solve_ivp(rates, (t1, t[-1]), [t_evap, x0], t_eval=t[after], rtol=1e-10, atol=1e-12)
    print(f"\n  falling rate: at t = {t[-1]:.2f} s T = {T[-1]:.3f} K (ODE {ode.y[0][-1]:.3f}), "
          f"X = {X[-1]:.5f} (ODE {ode.y[1][-1]:.5f}); constant rate would have dried at "
          f"{t1 + 0.5:.2f} s")
    assert X[-1] > 0.2 * x0                    # slower than the constant rate's 0.5 s
    assert np.all(T[after] > t_evap)           # warming while it dries
    assert T[after] - t_gas == pytest.approx(ode.y[0] - t_gas, rel=2e-3)
    assert X[after] == pytest.approx(ode.y[1], abs=2e-3 * x0)


# ------------------------------------------------------------------------------ input checks
def _scene(thermal, fill_extra=""):
    return (h.header(lo=(-0.1,) * 3, hi=(0.1,) * 3) + _material("glass", 800.0)
            + h.interaction("glass", "glass", 0.5, 0.5)
            + "[[particles]]\nmaterial = \"glass\"\nradius = 0.01\ncount = 1\ntemperature = 300.0\n"
            + fill_extra + "region = { box = { min = [-0.05, -0.05, -0.05], max = [0.05, 0.05, 0.05] } }\n"
            + thermal)


@pytest.mark.parametrize("thermal, key, words", [
    ("[thermal]\n[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_direction = [1, 0, 0]\nlength = 1.0\n"
     "cells = 4\nmass_flow = 1.0\ninlet_temperature = 500.0\n", "thermal.gas.flow_area", "exactly one"),
    ("[thermal]\n[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_direction = [1, 0, 0]\nlength = 1.0\n"
     "cells = 4\nmass_flow = 1.0\ntemperature = 500.0\nradius = 0.1\n", "thermal.gas.temperature", "inlet_temperature"),
    ("[thermal]\n[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_direction = [1, 0, 0]\nlength = 1.0\n"
     "cells = 0\nmass_flow = 1.0\ninlet_temperature = 500.0\nradius = 0.1\n", "thermal.gas.cells", "between"),
    ("[thermal]\n[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_direction = [1, 0, 0]\nlength = 1.0\n"
     "cells = 4\nmass_flow = \"2 kg/m\"\ninlet_temperature = 500.0\nradius = 0.1\n", "thermal.gas.mass_flow", "kg/s"),
    ("[thermal]\n[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_direction = [1, 0, 0]\nlength = 1.0\n"
     "cells = 4\nmass_flow = 1.0\ninlet_temperature = 500.0\nradius = 0.1\nvelocity = [1, 0, 0]\n",
     "thermal.gas.velocity", "mass_flow"),
    ("[thermal]\n[thermal.gas]\nmodel = \"axial_plug_flow\"\naxis_direction = [1, 0, 0]\nlength = 1.0\n"
     "cells = 4\nmass_flow = 1.0\ninlet_temperature = 500.0\nradius = 0.1\nflow = \"counter\"\n",
     "thermal.gas.flow", "against_axis"),
    ("[thermal]\n[thermal.gas]\ncells = 4\n", "thermal.gas.cells", "axial_plug_flow"),
    ("[thermal]\nradiation = true\n", "thermal.radiation_to", "required"),
    ("[thermal]\nradiation = true\nradiation_to = \"gas\"\n", "thermal.radiation_to", "[thermal.gas]"),
    ("[thermal]\nradiation = true\nradiation_to = \"burner\"\n", "thermal.radiation_to", "wall or body"),
    ("[thermal]\nradiation = true\nradiation_to = 1000.0\n", "materials.glass.emissivity", "required"),
    ("[thermal]\nradiation_to = 1000.0\n", "thermal.radiation_to", "radiation = true"),
    ("", "particles[0].moisture", "[thermal]"),
])
def test_scene_errors(thermal, key, words):
    extra = "moisture = 0.1\n" if not thermal else ""
    with pytest.raises(SceneError) as e:
        parse_scene(_scene(thermal, extra))
    print(f"\n  {e.value}")
    assert e.value.key == key and words in e.value.reason


def test_nothing_compiled_without_the_effects(small_scene_text):
    text = small_scene_text(count=20).replace("poisson_ratio = 0.25", "poisson_ratio = 0.25\n"
                                              "thermal_conductivity = 1.0\nheat_capacity = 800.0")
    text = text.replace("count = 20\n", "count = 20\ntemperature = 300.0\n") + "[thermal]\n"
    with taichi_dem.Simulation.from_text(text) as sim:
        e = sim.engine
        assert e.model.effect("plug_flow_convection") is None and not hasattr(e, "emissivity") and not hasattr(e, "evaporated")
        assert not hasattr(e.state, "moisture")
        assert not any(k.startswith("gas/") or k.endswith("moisture") for k in sim.series)
