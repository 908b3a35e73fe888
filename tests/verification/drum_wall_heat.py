"""Wall-to-bed heat transfer in a rotating drum by DEM (issue 10 item 5): the experiment behind
tests/verification/test_drum_wall_heat.py and its BENCHMARKS.md figures.

A slice of a smooth drum (no flights, no end walls; periodic along its axis), 2 mm glass beads
in air, turning in the rolling regime. The shell is an isothermal mesh body at T_wall. The bed
starts at T_wall too (no heat flows), rolls until its motion is steady, then every bead is set
to T_bed0 (the wall "switched on", as far as the bed is concerned). After a further start-up
of about one contact time (the wall elements under the bed have then all entered since the
switch), the recorded series bodies/drum/heat_transfer_coefficient = heat flow / (covered
area (T_bed,mean - T_wall)) is averaged: the instantaneous difference, as the definition
has it (the bed warms by a few kelvin meanwhile).

The contact time is the time a wall element spends under the bed, t_c = (2 eps)/omega with
2 eps the wetted angle of the shell; measured here from the angular extent of the beads that
touch the shell (each sample, the 1st-99th percentiles of their angles), and, as a check, from
the covered area (covered_area / (R L)).

Thermal time scaling ([thermal] time_scale S): the heat capacities are divided by S, so a
wall element under the bed for t_mech of simulated time has conducted for S t_mech. The
penetration law depends on the thermal contact time, so a time-scaled run must turn the drum
S times faster in simulated time for the same thermal t_c: ``rpm`` below is the *thermal*
speed (the one the model is evaluated at) and the mechanics turn at S x rpm. That keeps the
number of revolutions per contact time, but not the Froude number (S^2 larger): the bed must
stay in the rolling regime (Fr = omega^2 R / g < ~0.01), and scaling is exact only in the bed's
plug (solid-body) region, where the beads do not move relative to the wall.
"""
from __future__ import annotations

import math
import time as _time

import numpy as np

import taichi_dem

# glass beads (real modulus for the contact-spot correction), steel shell
GLASS = dict(density=2500.0, youngs=63e9, poisson=0.22, k=1.0, c=800.0)
# glass on glass, measured: Foerster, Louge, Chang & Allia, Phys. Fluids 6 (1994) 1108 (mu
# 0.092 for glass spheres). It sets how densely the first layer covers the shell (0.68-0.71 of
# it at 0.092 against 0.63 at 0.5, per covered area), and so the contact part of h.
GLASS_FRICTION = 0.092
STEEL = dict(density=7800.0, youngs=200e9, poisson=0.3, k=45.0, c=480.0)


def fill_count(drum_radius, length, fill, radius, packing=0.6):
    """Beads for a fill degree ``fill`` (bed volume over drum volume) at solid fraction
    ``packing``."""
    volume = fill * math.pi * drum_radius ** 2 * length * packing
    return int(round(volume / (4.0 / 3.0 * math.pi * radius ** 3)))


def scene_text(*, drum_radius=0.05, length=0.008, radius=1e-3, count=1000, rpm_mech=10.0,
               t_wall=373.15, softened_modulus=5e6, segments=72, time_scale=1.0,
               lens=None, min_gap=1e-6, k_gas=0.0262, model="solid_resistance",
               friction=0.5, wall_friction=0.5, rolling_friction=0.02, restitution=0.5,
               output_interval=0.05, rayleigh_fraction=0.3, dt=None, seed=1,
               represented_diameter=None, flights=0, flight_height=None,
               adiabatic_lifters=False, skin=None) -> str:
    g, s = GLASS, STEEL
    step = "" if dt is None else f"dt = {dt!r}\n"
    step += "" if skin is None else f"skin = {skin!r}\n"
    # coarse graining: the beads stand for finer ones (thermal/coarse_grained.py), the bed's
    # porosity that of the DEM's packed bed
    coarse = ("" if represented_diameter is None else
              f"coarse_grained = {{ represented_diameter = {represented_diameter!r}, "
              f"bed_porosity = {PACKED_BED_POROSITY!r} }}\n")
    box = drum_radius * 1.05
    # "schlunder" widens each gap by the gas's mean free path instead of clamping it
    gap_line = "" if model == "schlunder" else f"gas_gap_min_gap = {min_gap!r}\n"
    # the lens: the model's default unless given (0.4 R with "schlunder", 0.2 R otherwise)
    lens_line = "" if lens is None else f"gas_gap_lens = {lens!r}\n"
    # low lifters (a fraction of a bead high) keep the bed from slipping on the smooth shell
    lifters = (f", flights = {int(flights)}, flight_height = {flight_height!r}, flight_thickness = "
               f"{0.5 * flight_height!r}") if flights else ""
    lifter_body = ""
    if flights and adiabatic_lifters:
        lifter_body = f"""[[bodies]]
name = "lifters"
material = "steel"
mesh = {{ builder = "drum", radius = {drum_radius!r}, length = {length!r}, end_walls = false, include_shell = false, segments = {segments}{lifters} }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "{rpm_mech!r} rpm" }} }}
"""
        lifters = ""
    return f"""
[simulation]
end_time = 1.0
gravity = [0.0, 0.0, -9.81]
precision = "f64"
seed = {seed}
rayleigh_fraction = {rayleigh_fraction!r}
{step}[domain]
min = [0.0, {-box!r}, {-box!r}]
max = [{length!r}, {box!r}, {box!r}]
periodic = ["x"]
[materials.glass]
density = {g['density']!r}
youngs_modulus = {softened_modulus!r}
real_youngs_modulus = {g['youngs']!r}
poisson_ratio = {g['poisson']!r}
thermal_conductivity = {g['k']!r}
heat_capacity = {g['c']!r}
{coarse}[materials.steel]
density = {s['density']!r}
youngs_modulus = {softened_modulus!r}
real_youngs_modulus = {s['youngs']!r}
poisson_ratio = {s['poisson']!r}
thermal_conductivity = {s['k']!r}
heat_capacity = {s['c']!r}
[[interactions]]
pair = ["glass", "glass"]
restitution = {restitution!r}
friction = {friction!r}
rolling_friction = {rolling_friction!r}
[[interactions]]
pair = ["glass", "steel"]
restitution = {restitution!r}
friction = {wall_friction!r}
rolling_friction = {rolling_friction!r}
[[bodies]]
name = "drum"
material = "steel"
mesh = {{ builder = "drum", radius = {drum_radius!r}, length = {length!r}, end_walls = false, segments = {segments}{lifters} }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "{rpm_mech!r} rpm" }} }}
temperature = {t_wall!r}
{lifter_body}[[particles]]
material = "glass"
radius = {radius!r}
count = {count}
temperature = {t_wall!r}
region = {{ cylinder = {{ axis_point = [0.0, 0, 0], axis_direction = [1, 0, 0], radius = {drum_radius - 2.5 * radius!r}, length = {length!r} }} }}
[thermal]
conduction = true
wall_conduction = true
contact_radius_correction = "static"
gas_gap = true
gap_gas_conductivity = {k_gas!r}
{lens_line}{gap_line}gas_gap_model = "{model}"
time_scale = {time_scale!r}
[output]
interval = {output_interval!r}
"""


def wetted_angle(position, radius, drum_radius, touch=1.02):
    """The shell's wetted angle (rad): the 1st-99th percentile span of the angles (about +x,
    from -z) of the beads within ``touch`` x their radius of the shell. NaN if none."""
    y, z = position[:, 1], position[:, 2]
    near = np.hypot(y, z) > drum_radius - touch * radius
    if np.count_nonzero(near) < 5:
        return math.nan
    angle = np.arctan2(y[near], -z[near])
    lo, hi = np.percentile(angle, [1.0, 99.0])
    return float(hi - lo)


def first_layer_mask(position, radius, drum_radius, segments=72):
    """The beads touching (or within 0.1 radius of) the polygonal shell: centre farther from
    the axis than the facets' inscribed radius minus 1.1 bead radii."""
    inscribed = drum_radius * math.cos(math.pi / segments)
    return np.hypot(position[:, 1], position[:, 2]) > inscribed - 1.1 * radius


def passive_bed_solid_fraction(position, radius, drum_radius, length, depth=(3.0, 9.0),
                               half_angle=0.25, points=20000, seed=0):
    """The solid fraction of the bed where it rides with the shell: the share of ``points``
    random points (a fixed seed) that fall inside a bead, in the annular sector 1.5-4.5 bead
    diameters in from the shell (``depth`` in radii: past the wall's layering, short of the
    flowing layer) within ``half_angle`` (rad) of the middle of the wetted arc, periodic along
    the axis (length). NaN without beads touching the shell."""
    from scipy.spatial import cKDTree
    y, z = position[:, 1], position[:, 2]
    r = np.hypot(y, z)
    angle = np.arctan2(y, -z)
    touching = r > drum_radius - 1.02 * radius
    if np.count_nonzero(touching) < 5:
        return math.nan
    lo, hi = np.percentile(angle[touching], [1.0, 99.0])
    middle = 0.5 * (lo + hi)
    r_out, r_in = drum_radius - depth[0] * radius, drum_radius - depth[1] * radius
    rng = np.random.default_rng(seed)
    # uniform in the sector's area: r^2 uniform between r_in^2 and r_out^2
    pr = np.sqrt(rng.uniform(r_in ** 2, r_out ** 2, points))
    pa = middle + rng.uniform(-half_angle, half_angle, points)
    px = rng.uniform(0.0, length, points)
    sample = np.column_stack([px, pr * np.sin(pa), -pr * np.cos(pa)])
    centres = np.asarray(position, dtype=float).copy()
    centres[:, 0] %= length
    # periodic along x by images: beads within a radius of either end, shifted by +-length
    images = [centres]
    for shift in (-length, length):
        near = (centres[:, 0] + shift > -radius) & (centres[:, 0] + shift < length + radius)
        images.append(centres[near] + np.array([shift, 0.0, 0.0]))
    tree = cKDTree(np.vstack(images))
    distance, _ = tree.query(sample)
    return float(np.mean(distance < radius))


def ride_fraction(p: dict, near: np.ndarray, omega: float) -> float:
    """Does the first layer ride with the shell? The mean speed about the axis of the
    particles ``near`` the shell over the shell's at their radius (1: rides; a bed rolling on a
    slipping layer: ~0.5). ``p``: Simulation.particles(); ``omega``: the shell's rad/s."""
    y, z = p["position"][near, 1], p["position"][near, 2]
    vy, vz = p["velocity"][near, 1], p["velocity"][near, 2]
    return float(np.mean((y * vz - z * vy) / (omega * (y * y + z * z))))


def angle_mean(angles):
    return float(np.nanmean(angles))


def drum_wall_heat(*, rpm=6.0, fill=0.15, drum_radius=0.05, length=0.008, radius=1e-3,
                   time_scale=1.0, settle=1.0, startup=None, measure=None, t_wall=373.15,
                   t_bed=293.15, model="solid_resistance", softened_modulus=5e6,
                   rolling_friction=0.02, segments=72, output_interval=0.05, threads=1,
                   dt=None, seed=1, verbose=False, represented_diameter=None, flights=0,
                   flight_height=None, adiabatic_lifters=False, friction=0.5,
                   wall_friction=0.5, skin=None) -> dict:
    """Run the experiment at thermal speed ``rpm`` (the mechanics turn at time_scale x rpm).

    settle: s of simulated time rolling before the bed is made cold; startup: s after that
    before averaging (default 1.1 contact times estimated from the fill, in simulated time:
    every bead then on the shell came to it after the switch, so the wall's elements under the
    bed have the ages 0 to t_c of the steady state the model averages over, not the younger
    ones of the transient, which read high: 4-9 % at 2 rpm);
    measure: s of averaging (default one contact time). Returns a dict: the mean coefficient
    h (W/(m^2 K)) and its spread over 4 sub-windows, the wetted angle and contact time
    (thermal), the bed's mean temperatures, the covered-area check, the count, wall time."""
    count = fill_count(drum_radius, length, fill, radius)
    rpm_mech = rpm * time_scale
    omega_mech = rpm_mech * 2.0 * math.pi / 60.0
    # a first guess of the wetted angle from the fill degree: 2 eps - sin 2 eps = 2 pi f
    from taichi_dem.thermal.correlations import wetted_angle_from_fill
    guess = wetted_angle_from_fill(fill)
    t_c_mech = guess / omega_mech
    # 1.1: the first layer rides at 0.92-0.96 of the shell's speed, so it stays a little
    # longer than a wall element
    startup = 1.1 * t_c_mech if startup is None else startup
    measure = t_c_mech if measure is None else measure
    text = scene_text(drum_radius=drum_radius, length=length, radius=radius, count=count,
                      rpm_mech=rpm_mech, t_wall=t_wall, softened_modulus=softened_modulus,
                      segments=segments, time_scale=time_scale, model=model,
                      rolling_friction=rolling_friction, output_interval=output_interval,
                      dt=dt, seed=seed, represented_diameter=represented_diameter,
                      flights=flights, flight_height=flight_height,
                      adiabatic_lifters=adiabatic_lifters, friction=friction,
                      wall_friction=wall_friction, skin=skin)
    t0 = _time.perf_counter()
    with taichi_dem.Simulation.from_text(text, precision="f64", threads=threads) as sim:
        sim.run(settle)
        s = sim.engine.state
        n = sim.engine.count
        temperature = s.temperature.to_numpy()
        temperature[:n] = t_bed
        s.temperature.from_numpy(temperature)
        first = len(sim.series["time"])
        # to the end of the startup as sim.run(settle + startup) would, a sample at a time:
        # the first layer's ride is averaged over the whole time since the switch (a window of
        # 0.3 s alone reads 0.86 - 0.97 as the bed slips now and then)
        ride_all = []
        to_go = int(round((settle + startup - sim.time) / sim.dt))
        while to_go > 0:
            chunk = min(to_go, sim.output_every - sim.step_count % sim.output_every)
            sim.step(chunk)
            to_go -= chunk
            p = sim.particles()
            ride_all.append(ride_fraction(p, first_layer_mask(p["position"], radius, drum_radius,
                                                              segments), omega_mech))
        start = len(sim.series["time"])
        angles, first_layer, first_count, ride, solid = [], [], [], [], []
        while sim.time < settle + startup + measure - 1e-9:
            sim.step(sim.output_every)
            p = sim.particles()
            angles.append(wetted_angle(p["position"], radius, drum_radius))
            solid.append(passive_bed_solid_fraction(p["position"], radius, drum_radius, length))
            near = first_layer_mask(p["position"], radius, drum_radius, segments)
            first_layer.append(float(np.mean(p["temperature"][near])))
            first_count.append(int(np.count_nonzero(near)))
            ride.append(ride_fraction(p, near, omega_mech))
        series = sim.series
        h = np.asarray(series["bodies/drum/heat_transfer_coefficient"])[start:]
        area = np.asarray(series["bodies/drum/covered_area"])[start:]
        q = np.asarray(series["bodies/drum/heat_flow"])[start:]
        tb = np.asarray(series["particles/mean_temperature"])
        tb_window = tb[start:]
        assert len(h) == len(first_layer) == len(tb_window), (len(h), len(first_layer))
        h_all = np.asarray(series["bodies/drum/heat_transfer_coefficient"])[first:]
        p = sim.particles()
        lost = n - sim.particle_count
        dt = sim.dt
    wall = _time.perf_counter() - t0
    angle = float(np.nanmean(angles))
    omega = rpm * 2.0 * math.pi / 60.0
    parts = np.array_split(h, 4)
    froude = omega_mech ** 2 * drum_radius / 9.81
    out = {
        "rpm": rpm, "rpm_mech": rpm_mech, "time_scale": time_scale, "fill": fill,
        "count": count, "lost": int(lost), "froude_mech": froude, "dt": dt,
        "h": float(np.mean(h)), "h_windows": [float(np.nanmean(x)) for x in parts],
        "h_std_window": float(np.std([np.nanmean(x) for x in parts], ddof=1)),
        "h_series_after_switch": h_all.tolist(),
        "heat_flow": float(np.mean(q)),
        # the same heat flow over the wetted arc of the measured angle instead of the covered
        # triangles: q / (2 eps R L (T_bed - T_wall))
        "h_arc": float(np.mean(q / (angle_mean(angles) * drum_radius * length
                                    * (tb_window - t_wall)))),
        "covered_area": float(np.mean(area)),
        # the first layer (beads touching the shell): its mean temperature T_1 splits the
        # coefficient into the contact part q/(A (T_w - T_1)) and the bed (penetration) part
        # q/(A (T_1 - T_bed)), 1/h = 1/contact + 1/bed (covered area A, q into the bed)
        "first_layer_count": float(np.mean(first_count)),
        "t_first_layer_mean": float(np.mean(first_layer)),
        "h_contact": float(np.mean(-q / (area * (t_wall - np.asarray(first_layer))))),
        "h_bed": float(np.mean(-q / (area * (np.asarray(first_layer) - tb_window)))),
        "wetted_angle": angle,
        # the riding bed's porosity (the penetration model's bulk density and conductivity)
        "bed_porosity": 1.0 - float(np.nanmean(solid)),
        "ride": float(np.mean(ride_all + ride)),
        "ride_window": float(np.mean(ride)),
        "wetted_angle_from_area": float(np.mean(area)) / (drum_radius * length),
        "wetted_angle_guess": guess,
        "contact_time": angle / omega,
        "t_bed_start": float(tb[start]), "t_bed_end": float(tb[-1]), "t_wall": t_wall,
        "wall_seconds": wall,
    }
    if verbose:
        print({k: v for k, v in out.items() if k != "h_series_after_switch"})
    return out


# The DEM packed-bed conductivities of the same beads with the same gas-gap settings (lens
# 0.2 R, minimum gap 1 um, air 0.0262), measured by tests/verification/packed_bed.py (BENCHMARKS.md
# "Gas-gap conduction"), and that experiment's core porosity: inputs of the DEM-consistent model.
PACKED_BED_K = {"solid_resistance": 0.084, "isothermal": 0.288, "voronoi": 0.124}
PACKED_BED_POROSITY = 0.407


def wall_particle_conductance(model, radius=1e-3, k_gas=0.0262, lens=0.2, min_gap=1e-6,
                              k_solid=GLASS["k"], temperature=333.15):
    """The DEM's gas-gap conductance (W/K) of one bead just touching the shell (thermal/
    gas_gap.py's reference quadrature; the contact spot adds ~1 % and is left out)."""
    from taichi_dem.thermal import gas_gap
    if model == "isothermal":
        return k_gas * gas_gap.plane_gap_integral_reference(radius, radius, lens, min_gap)
    if model == "schlunder":
        from taichi_dem.thermal import first_layer
        from taichi_dem.thermal.correlations import modified_mean_free_path
        return k_gas * first_layer.widened_gap_integral_reference(
            radius, radius, first_layer.wall_reach(lens), modified_mean_free_path(temperature))
    if model == "voronoi":
        return k_gas * gas_gap.plane_voronoi_gap_integral_reference(
            radius, radius, lens, min_gap, k_gas / k_solid, 0.4)
    return k_gas * gas_gap.plane_solid_gap_integral_reference(radius, radius, lens, min_gap,
                                                              k_gas / k_solid)


def models(result, radius=1e-3, k_gas=0.0262, coverage=0.8):
    """The Schlünder-Mollekopf coefficient at the run's measured wetted angle and thermal
    speed, twice: 'physical' (air's modified mean free path at the mean temperature, smooth
    beads, Zehner-Bauer-Schlünder bed conductivity at the packed bed's porosity) and
    'dem_consistent' (the first-layer conductance of the DEM's own gas-gap law per projected
    area, the DEM's minimum gap as l + delta, the DEM's packed-bed conductivity)."""
    from taichi_dem.thermal import correlations as c
    from packed_bed import zehner_schlunder
    model = result["kwargs"].get("model", "solid_resistance") if "kwargs" in result else \
        result.get("model", "solid_resistance")
    d = 2.0 * radius
    # the bed's bulk density and conductivity at the porosity of the DEM's riding bed where it
    # was measured (the penetration model's bed is the one simulated), else the packed bed's
    porosity = result.get("bed_porosity", PACKED_BED_POROSITY)
    if not math.isfinite(porosity):
        porosity = PACKED_BED_POROSITY
    solid_fraction = 1.0 - porosity
    rho_b = GLASS["density"] * solid_fraction
    t_mean = 0.5 * (result["t_wall"] + 0.5 * (result["t_bed_start"] + result["t_bed_end"]))
    k_zbs = zehner_schlunder(GLASS["k"], k_gas, porosity)
    common = dict(rpm=result["rpm"], wetted_angle=result["wetted_angle"], diameter=d,
                  k_gas=k_gas, bed_density=rho_b, heat_capacity=GLASS["c"], temperature=t_mean,
                  coverage=coverage)
    physical = c.schlunder_mollekopf(bed_conductivity=k_zbs, **common)
    physical["bed_conductivity"] = k_zbs
    physical["bed_porosity"] = porosity
    # DEM-consistent: alpha_WS from the DEM's own sphere-wall conductance
    g = wall_particle_conductance(model, radius, k_gas)
    min_gap = 1e-6
    uncovered = 2.0 * k_gas / (math.sqrt(2.0) * d + 2.0 * min_gap)
    a_ws = coverage * g / (math.pi * radius ** 2) + (1.0 - coverage) * uncovered
    k_b = PACKED_BED_K.get(model, PACKED_BED_K["voronoi"])
    a_bed = c.penetration_coefficient(rho_b, GLASS["c"], k_b, physical["contact_time"])
    consistent = {"alpha_ws": a_ws, "alpha_bed": a_bed, "alpha": 1.0 / (1.0 / a_ws + 1.0 / a_bed),
                  "alpha_exact": c.penetration_with_contact_resistance(
                      a_ws, rho_b, GLASS["c"], k_b, physical["contact_time"]),
                  "bed_conductivity": k_b, "wall_particle_conductance": g,
                  "contact_time": physical["contact_time"]}
    return {"physical": physical, "dem_consistent": consistent}


def table_row(result) -> str:
    """One markdown row: rpm, S, fill, wetted angle, t_c, DEM (series; arc), its contact and
    bed parts, the physical model (contact, bed, total) and the DEM-consistent model."""
    m = models(result)
    p, q = m["physical"], m["dem_consistent"]
    return (f"| {result['kwargs'].get('model', 'solid_resistance')} | {result['rpm']:g} "
            f"({result['rpm_mech']:g} x 1/{result['time_scale']:g}) | {result['fill']:.2f} | "
            f"{math.degrees(result['wetted_angle']):.0f} | {result['contact_time']:.2f} | "
            f"**{result['h']:.1f}** ({result['h_arc']:.1f}) | "
            f"{result.get('h_contact', math.nan):.0f} / {result.get('h_bed', math.nan):.0f} | "
            f"{p['alpha_ws']:.0f} / {p['alpha_bed']:.0f} / **{p['alpha']:.1f}** | "
            f"{q['alpha_ws']:.0f} / {q['alpha_bed']:.0f} / {q['alpha']:.1f} | "
            f"{result['h'] / p['alpha']:.2f} | {result['h'] / q['alpha']:.2f} |")


if __name__ == "__main__":
    import argparse
    import json
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
    ap = argparse.ArgumentParser(description="the drum wall-to-bed heat transfer experiment")
    ap.add_argument("--rpm", type=float, default=6.0, help="thermal speed (the model's)")
    ap.add_argument("--time-scale", type=float, default=2.0)
    ap.add_argument("--fill", type=float, default=0.15)
    ap.add_argument("--length", type=float, default=0.008)
    ap.add_argument("--model", default="solid_resistance")
    ap.add_argument("--settle", type=float, default=0.8)
    ap.add_argument("--startup", type=float, default=1.2)
    ap.add_argument("--measure", type=float, default=0.6)
    ap.add_argument("--dt", type=float, default=None)
    ap.add_argument("--radius", type=float, default=1e-3, help="bead radius (m)")
    ap.add_argument("--represented-diameter", type=float, default=None,
                    help="coarse graining: the beads stand for beads of this diameter (m)")
    ap.add_argument("--friction", type=float, default=0.5,
                    help="glass on glass (0.5 reproduces the history's figures; the test uses "
                         "GLASS_FRICTION, 0.092)")
    ap.add_argument("--flights", type=int, default=0, help="low lifters on the shell")
    ap.add_argument("--flight-height", type=float, default=None, help="their height (m)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    kw = dict(rpm=a.rpm, time_scale=a.time_scale, fill=a.fill, length=a.length, model=a.model,
              settle=a.settle, startup=a.startup, measure=a.measure, dt=a.dt, radius=a.radius,
              represented_diameter=a.represented_diameter, friction=a.friction,
              flights=a.flights, flight_height=a.flight_height, seed=a.seed)
    r = drum_wall_heat(**kw)
    r["kwargs"] = kw
    if a.json:
        with open(a.json, "w") as f:
            json.dump(r, f, indent=1)
    print({k: v for k, v in r.items() if k != "h_series_after_switch"})
    print(table_row(r))
