"""A dryer's closures from the map of its flighted drum's slices (``taichi-dem map`` of a
slice such as demos/dryers/dryer_slice.toml) instead of the correlations (app/dryer.py).

A flighted drum conveys by its flights' cascading at a rate set by its hold-up: the slice
measures the axial mass flow q(H) at the drum's incline (with the gas's drag when the slice has
a [gas]). A whole drum fed F kg/s of dry solids is marched from its discharge back to its feed
as `taichi-dem machine` marches a cooler (app/machine.py): at each position the hold-up H(x)
whose flow, with the pull of the bed's axial depth gradient, carries the feed. A direct run of
the dryer slice's drum 0.72 m long, inlet to outlet (bench/dryer_direct.py,
docs/machine/dryer_slice/direct.md), holds what that march gives (hold-up and residence within
6 %, torque 13 %); a hold-up where |q(H)| = F all along the drum holds twice as much there (its
discharge end drains the bed the march's depth gradient accounts for). Then
    residence time  tau = M / F,  M = int H dx (kg),
    gas-solids conductance per metre  ha' = h a'(H_mean),  h = k_g Nu / d, H_mean = M / L,
      Nu = 2 + 0.6 Re^(1/2) Pr^(1/3) (Ranz-Marshall), Re = rho_g d s(H) / mu_g,
    with a'(H) the curtains' surface per metre and s(H) their speed through the gas
    (app/curtains.py): only the airborne particles meet the gas; d is the dryer's particle
    diameter, and a map of coarser spheres (d_map) has its a' scaled by d_map / d (the same
    airborne mass in the dryer's particles),
    drive torque  int T(H) dx  from the drum's torque per metre.
Each figure is interpolated linearly in H between the mapped hold-ups; a feed whose uniform
hold-up (|q(H)| = F) lies outside the map is refused (map more hold-ups). The relative standard errors of q, a' and s at
H become the closures' uncertainties (the report's +- column). Maps of the same drum blown at
several gas speeds (each map records its [gas]) are interpolated in the gas speed as well
(``closures_over_gas``): the map over hold-up and gas mass velocity.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError


def _interpolate(rows, x_name, x, name):
    """(value, standard error) of ``name`` at ``x_name`` = x, linear between rows."""
    xs = np.array([r[x_name] for r in rows], float)
    ys = np.array([r.get(name, math.nan) for r in rows], float)
    es = np.array([r.get(name + "_standard_error", math.nan) or 0.0 for r in rows], float)
    return float(np.interp(x, xs, ys)), float(np.interp(x, xs, es))


def closures(path, design: dict, source: str) -> dict:
    """The residence time (s), conductance per metre (W/(m K)), drive torque (N m) and their
    relative uncertainties from the map at ``path`` for ``design`` (the Dryer's fields so far:
    diameter, length, incline rad, rpm, feed kg/s and the gas's density, viscosity,
    conductivity and heat capacity). SceneError (``source``, closure.map) when the map is not
    of this drum or cannot carry the feed."""
    from .machine import read_map
    key = "closure.map"
    p, doc = read_map(path)
    info, rows = doc.get("machine"), doc.get("rows") or []
    if not isinstance(info, dict) or not rows:
        raise SceneError(source, key, f"{p} is not a map of `taichi-dem map` (no machine "
                         "section or no rows)")
    if abs(2.0 * float(info["shell_radius"]) - design["diameter"]) > 0.01 * design["diameter"]:
        raise SceneError(source, key, f"the map's drum is {2 * info['shell_radius']:.4g} m "
                         f"across, the dryer's {design['diameter']:.4g} m: map a slice of this "
                         "drum")
    speeds = [abs(v) for v in info.get("angular_speeds", {}).values() if v]
    rpm = max(speeds) * 60.0 / (2.0 * math.pi) if speeds else 0.0
    if abs(rpm - design["rpm"]) > 0.01 * design["rpm"]:
        raise SceneError(source, key, f"the map's drum turns at {rpm:.4g} rpm, the dryer's at "
                         f"{design['rpm']:.4g} rpm")
    incline = math.degrees(design["incline"])
    mapped = sorted({round(float(r["incline_deg"]), 6) for r in rows})
    near = min(mapped, key=lambda a: abs(a - incline))
    if abs(near - incline) > 0.05:
        raise SceneError(source, key, f"the map's inclines are {mapped} deg, the dryer's "
                         f"{incline:.4g} deg: map the slice at the dryer's incline")
    rows = sorted((r for r in rows if abs(float(r["incline_deg"]) - near) <= 1e-6),
                  key=lambda r: float(r["holdup_kg_per_m"]))
    for r in rows:
        r["conveyed"] = abs(float(r["axial_mass_flow"]))
    conveyed = [r["conveyed"] for r in rows]
    feed = design["feed"]
    if not conveyed[0] <= feed <= conveyed[-1] or np.any(np.diff(conveyed) <= 0.0):
        raise SceneError(source, key, f"the feed {feed * 3.6:.4g} t/h needs a hold-up outside "
                         f"the map (it conveys {conveyed[0] * 3.6:.3g} - {conveyed[-1] * 3.6:.3g} "
                         "t/h, rising with the hold-up): map more hold-ups")
    uniform = float(np.interp(feed, conveyed, [float(r["holdup_kg_per_m"]) for r in rows]))
    marched = _march(p, {round(float(r["axial_slope"]), 9) for r in rows}, design["length"],
                     feed, source)
    holdup = marched.holdup / design["length"]          # the mean hold-up per metre
    flow, flow_error = _interpolate(rows, "holdup_kg_per_m", holdup, "axial_mass_flow")
    area, area_error = _interpolate(rows, "holdup_kg_per_m", holdup, "curtain_area_per_metre")
    slip, slip_error = _interpolate(rows, "holdup_kg_per_m", holdup, "curtain_slip_speed")
    if not (math.isfinite(area) and math.isfinite(slip)):
        raise SceneError(source, key, f"{p} has no curtain figures (map the slice again with "
                         "this version of taichi-dem map)")
    # the map's spheres may be coarser than the dryer's solids (a sphere size is a modelling
    # choice, the map's transport and airborne mass are bulk figures): the same airborne mass
    # in particles of the dryer's diameter d shows the gas d_map / d times the surface, each
    # particle exchanging heat at its own h(d)
    size_notes = []
    d_map = float(info["particle_diameter"])
    d = float(design.get("particle_diameter") or d_map)
    if abs(d - d_map) > 1e-3 * d_map:
        area, area_error = area * d_map / d, area_error * d_map / d
        size_notes.append(f"the map's spheres are {d_map * 1e3:.3g} mm, the dryer's solids "
                          f"{d * 1e3:.3g} mm: the curtains' surface is scaled by "
                          f"{d_map / d:.3g} (the same airborne mass in the dryer's particles) "
                          "and h is theirs")
    h, slip_share = ranz_marshall(design, d, slip)
    conductance = h * area
    variance = ((area_error / area if area else 0.0) ** 2
                + (slip_share * slip_error / slip if slip else 0.0) ** 2) * conductance ** 2
    surface = None
    if design.get("exposure", "curtains") == "surface":
        s_area, s_area_error = _interpolate(rows, "holdup_kg_per_m", holdup,
                                            "surface_area_per_metre")
        s_slip, s_slip_error = _interpolate(rows, "holdup_kg_per_m", holdup, "surface_slip_speed")
        if not (math.isfinite(s_area) and math.isfinite(s_slip)):
            raise SceneError(source, "closure.exposure", f"{p} has no surface figures (map the "
                             "slice again with this version of taichi-dem map)")
        # the bed's and the loads' open surface is a layer over their free surfaces: its area
        # per metre does not change with the particles' size (unlike the curtains'), and each
        # particle there exchanges at its own h(d) at the surface's speed against the gas
        h_surface, s_share = ranz_marshall(design, d, s_slip)
        surface = h_surface * s_area
        conductance += surface
        variance += ((s_area_error / s_area if s_area else 0.0) ** 2
                     + (s_share * s_slip_error / s_slip if s_slip else 0.0) ** 2) * surface ** 2
    notes = list(size_notes)
    gas = info.get("gas")
    if gas:
        speed = design["gas_flow"] / (design["gas_density"] * math.pi * design["diameter"] ** 2 / 4)
        if abs(speed - abs(gas["axial_velocity"])) > 0.25 * abs(gas["axial_velocity"]):
            notes.append(f"the dryer's gas moves at {speed:.3g} m/s (its mass flow over its "
                         f"density and the drum's section), the map's at "
                         f"{abs(gas['axial_velocity']):.3g} m/s: the curtains' exposure and the "
                         "drag on the transport were measured at another gas speed")
        if gas.get("through_bed", True) and abs(gas["axial_velocity"]) > 0.0:
            notes.append("the map's gas was forced through the bed (gas.through_bed, or a map "
                         "made before the key): in a drum it goes round it, and the transport "
                         "under-states what the slope conveys (5 % at 3.7 m/s in the real-size "
                         "slices: docs/machine/dryer_slice/dryer.md)")
    return {
        "residence_time": marched.residence_time,
        "residence_uncertainty": abs(flow_error / flow) if flow else 0.0,
        "conductance_per_metre": conductance,
        "conductance_uncertainty": math.sqrt(variance) / conductance if conductance else 0.0,
        "map_surface_conductance_per_metre": surface,
        "drive_torque": abs(sum(marched.torques.values())),
        "map_holdup": holdup,
        "map_uniform_holdup": uniform,
        "map_airborne_fraction": _interpolate(rows, "holdup_kg_per_m", holdup,
                                              "airborne_fraction")[0],
        "map_heat_transfer_coefficient": h,
        "map_source": str(p),
        "map_notes": notes,
        "map_size_notes": size_notes,
        "map_feed_range": (conveyed[0], conveyed[-1]),
        "map_gas_speed": abs(float(gas["axial_velocity"])) if gas else None,
    }


def ranz_marshall(design: dict, diameter: float, slip: float) -> tuple[float, float]:
    """h = k_g Nu / d (W/(m^2 K)), Nu = 2 + 0.6 Re^(1/2) Pr^(1/3), Re = rho_g d s / mu_g, for
    particles of ``diameter`` m moving at ``slip`` m/s through the ``design``'s gas; and dh/h
    per ds/s, 0.3 Re^(1/2) Pr^(1/3) / Nu (the share of the slip's error in h's)."""
    reynolds = design["gas_density"] * diameter * slip / design["gas_viscosity"]
    prandtl = design["gas_heat_capacity"] * design["gas_viscosity"] / design["gas_conductivity"]
    nusselt = 2.0 + 0.6 * math.sqrt(reynolds) * prandtl ** (1.0 / 3.0)
    return (design["gas_conductivity"] * nusselt / diameter,
            0.3 * math.sqrt(reynolds) * prandtl ** (1.0 / 3.0) / nusselt)


def _march(path, slopes: set, length: float, feed: float, source: str):
    """machine.answer for the map at ``path``, its rows at the axial ``slopes`` only (those of
    the drum's incline, rounded to 1e-9), ``length`` m at ``feed`` kg/s; a march the map
    cannot carry is a SceneError (``source``, closure.map)."""
    from .machine import MachineMap, answer
    machine = MachineMap.load(path)
    machine.rows = [r for r in machine.rows if round(r.axial_slope, 9) in slopes]
    try:
        return answer(machine, length, feed, machine.rows[0].axial_slope)
    except SceneError as err:
        raise SceneError(source, "closure.map", f"the march along the drum on {path}: "
                         f"{err.reason}") from None


def closures_over_gas(paths, design: dict, source: str) -> dict:
    """``closures`` from several maps of the same drum blown at different gas speeds (each
    map's ``machine.gas``): each figure interpolated linearly in the gas's axial speed at the
    dryer's (its dry gas and vapour at the inlet over its density and the drum's section); a
    dryer outside the mapped speeds takes the nearest map's, with a note."""
    if isinstance(paths, str):
        return closures(paths, design, source)
    found = []
    for path in paths:
        c = closures(path, design, source)
        if c["map_gas_speed"] is None:
            raise SceneError(source, "closure.map", f"{c['map_source']} does not record its "
                             "gas (map it again with this version of taichi-dem map): with "
                             "several maps each must say its gas speed")
        found.append(c)
    found.sort(key=lambda c: c["map_gas_speed"])
    speeds = [c["map_gas_speed"] for c in found]
    if len(set(speeds)) != len(speeds):
        raise SceneError(source, "closure.map", f"two maps at the same gas speed ({speeds} m/s)")
    speed = design["gas_flow"] * (1.0 + design["gas_humidity"]) / (
        design["gas_density"] * math.pi * design["diameter"] ** 2 / 4.0)
    notes = []
    if not speeds[0] <= speed <= speeds[-1]:
        notes.append(f"the dryer's gas ({speed:.3g} m/s) is outside the maps' {speeds[0]:.3g} - "
                     f"{speeds[-1]:.3g} m/s: the nearest map's figures are used")
    out = dict(found[0])
    for name in ("residence_time", "residence_uncertainty", "conductance_per_metre",
                 "conductance_uncertainty", "drive_torque", "map_holdup", "map_uniform_holdup",
                 "map_airborne_fraction", "map_heat_transfer_coefficient"):
        out[name] = float(np.interp(speed, speeds, [c[name] for c in found]))
    if found[0]["map_surface_conductance_per_metre"] is not None:
        out["map_surface_conductance_per_metre"] = float(np.interp(
            speed, speeds, [c["map_surface_conductance_per_metre"] for c in found]))
    out["map_source"] = " + ".join(f"{c['map_source']} ({c['map_gas_speed']:.3g} m/s)" for c in found)
    # the maps' notes on the spheres' size (once; their gas notes give way to the
    # interpolation in the gas speed), then the gas's
    out["map_notes"] = list(dict.fromkeys(n for c in found for n in c["map_size_notes"])) + notes
    out["map_feed_range"] = (max(c["map_feed_range"][0] for c in found),
                             min(c["map_feed_range"][1] for c in found))
    out["map_gas_speed"] = speed
    return out
