"""Effective conductivity of a settled packed bed by DEM (issue 10 item 5): the experiment
behind tests/verification/test_packed_bed.py and its BENCHMARKS.md figures.

A bed of monodisperse spheres settles under gravity on an isothermal hot plate (z = 0) in a box
periodic in x and y. Then every particle above a cut 2 diameters below the bed's top is made a
heat sink (its thermal mass set to 1e12 J/K at the cold temperature) and heat is conducted
(contact spots, and the gas gap between particles and to the plate) until steady. Thermal time
scaling ([thermal] time_scale, issue 10 item 3) brings the bed's hour-long time constant into
a fraction of a simulated second; the steady state does not depend on heat capacities.

k_eff = q / |dT/dz|: q the plate's heat flow over the box's cross-section, dT/dz the slope of a
straight-line fit of the particles' temperatures against height in the core of the bed (3
diameters away from the plate and the sinks, where the packing is the bulk's and the wall's
contact resistance does not enter). The bulk porosity is measured in the same core (the
volume of sphere parts inside the slab over the slab's volume).
"""
from __future__ import annotations

import math

import numpy as np

import taichi_dem
from taichi_dem.thermal.correlations import modified_mean_free_path
from taichi_dem.thermal.correlations import zehner_schlunder  # re-exported: drum_wall_heat.py imports it here

MATERIALS = {
    # name: (density kg/m^3, real Young's modulus Pa, Poisson, conductivity W/(m K), c J/(kg K))
    "glass": (2500.0, 63e9, 0.22, 1.0, 840.0),
    "steel": (7800.0, 200e9, 0.3, 45.0, 480.0),
    # sintered alumina (k 30) and a low-conductivity ash-like solid (k_s / k_g = 11.5)
    "alumina": (3900.0, 370e9, 0.22, 30.0, 880.0),
    "ash": (2300.0, 20e9, 0.25, 0.3, 800.0),
}


def scene_text(material: str, radius: float, count: int, width: float, lens: float,
               k_gas: float, time_scale: float, softened_modulus: float,
               model: str = "solid_resistance", friction: float = 0.3,
               pressure: float | None = None) -> str:
    density, youngs, poisson, k_s, c = MATERIALS[material]
    height = 60.0 * radius
    return f"""
[simulation]
end_time = 1.0
gravity = [0.0, 0.0, -9.81]
precision = "f64"
[domain]
min = [0.0, 0.0, 0.0]
max = [{width!r}, {width!r}, {height!r}]
periodic = ["x", "y"]
[materials.bead]
density = {density!r}
youngs_modulus = {softened_modulus!r}
real_youngs_modulus = {youngs!r}
poisson_ratio = {poisson!r}
thermal_conductivity = {k_s!r}
heat_capacity = {c!r}
[materials.plate]
density = 7800.0
youngs_modulus = {softened_modulus!r}
real_youngs_modulus = 200e9
poisson_ratio = 0.3
thermal_conductivity = 45.0
heat_capacity = 480.0
[[interactions]]
pair = ["bead", "bead"]
restitution = 0.3
friction = {friction!r}
[[interactions]]
pair = ["bead", "plate"]
restitution = 0.3
friction = 0.3
[[walls]]
name = "hot_plate"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "plate"
temperature = 400.0
[[particles]]
material = "bead"
radius = {radius!r}
count = {count}
temperature = 300.0
region = {{ box = {{ min = [0.0, 0.0, {radius!r}], max = [{width!r}, {width!r}, {height - radius!r}] }} }}
[thermal]
conduction = true
wall_conduction = true
contact_radius_correction = "static"
gas_gap = true
gap_gas_conductivity = {k_gas!r}
gas_gap_lens = {lens!r}
gas_gap_model = "{model}"
{"" if pressure is None else f"gas_pressure = {pressure!r}"}
time_scale = {time_scale!r}
[output]
interval = 0.01
"""


def packed_bed_conductivity(material: str = "glass", radius: float = 1e-3, count: int = 900,
                            width_diameters: float = 8.0, lens: float = 0.2,
                            k_gas: float = 0.0262, time_scale: float = 1e5,
                            softened_modulus: float = 5e7, settle: float = 0.15,
                            heat: float = 0.1, model: str = "solid_resistance",
                            friction: float = 0.3, pressure: float | None = None) -> dict:
    """Run the experiment; returns k_eff (W/(m K)), the core porosity, the Zehner-Schlünder
    value at that porosity, the plate's and the sinks' heat flows (W) and the fit's r^2.

    ``heat`` (s, simulated, at time_scale): the bed's slowest thermal mode decays in ~H^2 /
    (pi^2 alpha) ~ 5e-3 s here, so 0.1 s is steady. The slowest bed, the ash at friction 0.02
    with the "schlunder" model at lens 0.4: k_eff 0.10829 / 0.10948 / 0.10964 / 0.10973 W/(m K)
    after 0.05 / 0.08 / 0.1 / 0.15 s (2026-12-07; 0.15 s was the default until then)."""
    width = width_diameters * 2.0 * radius
    text = scene_text(material, radius, count, width, lens, k_gas, time_scale, softened_modulus,
                      model, friction, pressure)
    with taichi_dem.Simulation.from_text(text, precision="f64") as sim:
        sim.run(settle)
        s = sim.engine.state
        n = sim.engine.count
        z = s.position.to_numpy()[:n, 2]
        top = float(np.max(z))
        cut = top - 4.0 * radius
        sink = z > cut
        inverse = s.inverse_thermal_mass.to_numpy()
        temperature = s.temperature.to_numpy()
        inverse[:n][sink] = 1e-12
        temperature[:n][sink] = 300.0
        s.inverse_thermal_mass.from_numpy(inverse)
        s.temperature.from_numpy(temperature)
        sim.run(settle + heat)
        q_plate = float(np.mean(sim.series["walls/hot_plate/heat_flow"][-3:]))
        z = s.position.to_numpy()[:n, 2]
        t = s.temperature.to_numpy()[:n]
        r = s.radius.to_numpy()[:n]
    lo, hi = 6.0 * radius, cut - 6.0 * radius
    core = (z > lo) & (z < hi) & ~sink
    slope, intercept = np.polyfit(z[core], t[core], 1)
    fit = slope * z[core] + intercept
    r2 = 1.0 - np.sum((t[core] - fit) ** 2) / np.sum((t[core] - np.mean(t[core])) ** 2)
    # solid volume inside the core slab: spherical caps cut by its two planes
    solid = 0.0
    for zc, rc in zip(z, r):
        a, b = max(lo, zc - rc), min(hi, zc + rc)
        if b > a:
            u0, u1 = a - zc, b - zc
            solid += math.pi * (rc * rc * (u1 - u0) - (u1 ** 3 - u0 ** 3) / 3.0)
    porosity = 1.0 - solid / (width * width * (hi - lo))
    k_eff = q_plate / (width * width) / abs(slope)
    k_s = MATERIALS[material][3]
    # the Smoluchowski form at the gas's modified mean free path as the scene's "schlunder" law
    # takes it (air at the pressure and the mean of the plate's 400 K and the fill's 300 K)
    free_path = modified_mean_free_path(350.0, pressure or 101325.0, k_gas)
    return {"k_eff": k_eff, "porosity": porosity, "zehner_schlunder": zehner_schlunder(k_s, k_gas, porosity),
            "zehner_schlunder_smoluchowski": zehner_schlunder(k_s, k_gas, porosity, free_path,
                                                              2.0 * radius),
            "plate_heat_flow": q_plate, "r2": float(r2), "core_particles": int(np.sum(core)),
            "bed_height": top + radius}
