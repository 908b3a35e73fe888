"""Measurements for the demos and regression tests: discharge rates, Beverloo's law, the free
surface of a drum bed and its circular-segment torque estimate, the flank of a heap.

Everything here reads a :class:`~taichi_dem.run.simulation.Simulation` (its ``series`` and
``particles()``) or plain numpy arrays; nothing changes the state. Units SI.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

# Beverloo, Leniger & van de Velde (1961), Chem. Eng. Sci. 15:260 fitted C = 0.58 and k = 1.4
# for seeds and sands through flat-bottomed bins. Nedderman, Tuzun, Savage & Houlsby (1982),
# Chem. Eng. Sci. 37:1597 (review; also Nedderman, "Statics and kinematics of granular
# materials", 1992, ch. 10) give 0.55 < C < 0.65 and k of about 1.5 for spheres.
BEVERLOO_C = 0.58
BEVERLOO_K = 1.5
BEVERLOO_C_RANGE = (0.55, 0.65)


# ------------------------------------------------------------------------------ discharge
def initial_masses(sim) -> np.ndarray:
    """Mass of every particle placed at the start, kg (from the placed radii and densities)."""
    placed = sim.placed
    density = np.array([sim.scene.materials[name].density for name in sim.tables.names])
    return 4.0 / 3.0 * math.pi * placed.radius ** 3 * density[placed.material]


def discharged_mass(sim, sensor: Optional[str] = None) -> tuple[np.ndarray, np.ndarray]:
    """(time s, cumulative discharged mass kg) at every output sample.

    With ``sensor`` and a ``sensors/<sensor>/mass_flow`` series (kg/s over each output
    interval): its running integral. Otherwise the particles that left the domain
    (``particles/lost``) times the mean particle mass of the initial fill - exact for the
    monodisperse demos, an estimate for a size distribution."""
    s = sim.series
    t = s["time"]
    key = f"sensors/{sensor}/mass_flow"
    if sensor is not None and key in s:
        from ..sensors.pooling import cumulative_of_rate
        return t, cumulative_of_rate(t, s[key], s.get("sample_interval"))
    return t, s["particles/lost"] * float(np.mean(initial_masses(sim)))


def linear_rate(t: np.ndarray, m: np.ndarray, t0: float, t1: float) -> float:
    """Least-squares slope of ``m`` against ``t`` over t0 <= t <= t1 (kg/s for a mass)."""
    sel = (t >= t0 - 1e-12) & (t <= t1 + 1e-12)
    if sel.sum() < 2:
        raise ValueError(f"fewer than two samples between {t0} and {t1} s")
    return float(np.polyfit(t[sel], m[sel], 1)[0])


def steady_window(t: np.ndarray, m: np.ndarray, total: float, lo=0.15, hi=0.6) -> tuple[float, float]:
    """The time span over which the discharged mass goes from ``lo`` to ``hi`` of ``total``:
    past the start-up transient, before the head over the orifice runs low."""
    t0 = float(np.interp(lo * total, m, t))
    t1 = float(np.interp(hi * total, m, t))
    return t0, t1


def beverloo_rate(orifice: float, diameter: float, bulk_density: float, g: float = 9.81,
                  C: float = BEVERLOO_C, k: float = BEVERLOO_K) -> float:
    """Beverloo's discharge rate through a circular orifice, kg/s:
    W = C rho_b sqrt(g) (D - k d)^(5/2)."""
    return C * bulk_density * math.sqrt(g) * max(orifice - k * diameter, 0.0) ** 2.5


def fit_power_law(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(exponent n, prefactor a) of the least-squares fit y = a x^n in log-log."""
    n, ln_a = np.polyfit(np.log(x), np.log(y), 1)
    return float(n), float(math.exp(ln_a))


def solid_fraction_in_cylinder(p: dict, radius: float, z0: float, z1: float) -> float:
    """Volume fraction of particle centres' spheres inside the vertical cylinder r < radius,
    z0 < z < z1 (centred on the z axis): sum of sphere volumes / cylinder volume."""
    x = p["position"]
    r = np.hypot(x[:, 0], x[:, 1])
    sel = (r < radius) & (x[:, 2] > z0) & (x[:, 2] < z1)
    vol = math.pi * radius ** 2 * (z1 - z0)
    return float(np.sum(4.0 / 3.0 * math.pi * p["radius"][sel] ** 3) / vol) if vol > 0 else 0.0


# ------------------------------------------------------------------------------ drum
def bed_surface(y: np.ndarray, z: np.ndarray, radius: np.ndarray, bin_width: float,
                keep=(0.2, 0.8)) -> tuple[float, float]:
    """Free surface of a bed in a drum turning about the x axis, from particle centres (y, z):
    the highest sphere top (z + r) in each y bin, a straight line fitted through the bins
    between the ``keep`` quantiles of the chord (the ends bend up and down along the wall).
    Returns (theta, h): the surface's angle to the horizontal (rad, > 0 when it rises towards
    +y) and its distance from the axis (m)."""
    edges = np.arange(y.min(), y.max() + bin_width, bin_width)
    idx = np.digitize(y, edges)
    top = z + radius
    ys, zs = [], []
    for k in np.unique(idx):
        sel = np.flatnonzero(idx == k)
        if len(sel) >= 3:
            j = sel[np.argmax(top[sel])]
            ys.append(y[j])
            zs.append(top[j])
    ys, zs = np.asarray(ys), np.asarray(zs)
    lo, hi = np.quantile(ys, keep)
    m = (ys >= lo) & (ys <= hi)
    slope, intercept = np.polyfit(ys[m], zs[m], 1)
    return math.atan(slope), abs(intercept) / math.sqrt(1.0 + slope * slope)


def segment_centroid(drum_radius: float, h: float) -> tuple[float, float]:
    """Circular segment cut from a circle of radius R by a chord at distance h from the centre
    (the bed below its free surface): (fill fraction of the circle, distance of the segment's
    centroid from the centre, m). With half-angle a = acos(h/R):
    area = R^2 (2a - sin 2a)/2, r_cg = 4 R sin^3 a / (3 (2a - sin 2a))."""
    a = math.acos(min(max(h / drum_radius, -1.0), 1.0))
    s = 2 * a - math.sin(2 * a)
    return s / (2 * math.pi), 4 * drum_radius * math.sin(a) ** 3 / (3 * s)


def segment_torque(mass: float, g: float, drum_radius: float, h: float, theta: float) -> float:
    """Torque of a bed held as a rigid circular segment tilted by its dynamic angle of repose
    theta: M g r_cg sin(theta), N m (the classic drum-power estimate)."""
    return mass * g * segment_centroid(drum_radius, h)[1] * math.sin(theta)


def drum_dynamic_angle(position: np.ndarray, radius: np.ndarray, axis_point, axis_direction,
                       bin_width: Optional[float] = None, keep=(0.2, 0.8)) -> float:
    """Dynamic angle of repose of the bed in a drum turning about a horizontal axis (gravity
    along -z), deg: the particle centres seen along the axis (the horizontal coordinate across
    the axis and z, both from ``axis_point``), their free surface fitted by :func:`bed_surface`
    over the ``keep`` quantiles of the chord (bins one diameter wide by default). The angle is
    given as a magnitude, whichever way the drum turns."""
    x = np.asarray(position, float) - np.asarray(axis_point, float)
    a = np.asarray(axis_direction, float)
    a = a / np.linalg.norm(a)
    across = np.cross(a, [0.0, 0.0, 1.0])
    if np.linalg.norm(across) < 1e-9:
        raise ValueError("the drum's axis is vertical: no dynamic angle of repose")
    across /= np.linalg.norm(across)
    r = np.asarray(radius, float)
    if len(r) < 10:
        return float("nan")
    if bin_width is None:
        bin_width = 2.0 * float(np.median(r))
    theta, _ = bed_surface(x @ across, x[:, 2], r, bin_width, keep)
    return abs(math.degrees(theta))


# ------------------------------------------------------------------------------ heap
def heap_angle(p: dict, centre=(0.0, 0.0), bin_width: Optional[float] = None,
               keep=(0.2, 0.8)) -> tuple[float, float, int]:
    """Angle of repose of a heap on the plane z = 0, by fitting its flank: the highest sphere
    top in each radial ring around ``centre`` (width: one diameter), then a line through the
    rings whose top lies between ``keep`` fractions of the heap's height (the rounded apex and
    the scattered toe are left out). Returns (angle deg, heap height m, rings fitted)."""
    x = p["position"]
    rad = p["radius"]
    if bin_width is None:
        bin_width = 2.0 * float(np.median(rad))
    r = np.hypot(x[:, 0] - centre[0], x[:, 1] - centre[1])
    top = x[:, 2] + rad
    ring = (r / bin_width).astype(int)
    rs, zs = [], []
    for k in np.unique(ring):
        sel = ring == k
        if sel.sum() >= 3:
            rs.append((k + 0.5) * bin_width)
            zs.append(top[sel].max())
    rs, zs = np.asarray(rs), np.asarray(zs)
    height = float(zs.max())
    m = (zs >= keep[0] * height) & (zs <= keep[1] * height) & (rs > rs[np.argmax(zs)])
    if m.sum() < 2:
        return float("nan"), height, int(m.sum())
    slope = np.polyfit(rs[m], zs[m], 1)[0]
    return math.degrees(math.atan(-slope)), height, int(m.sum())


# ------------------------------------------------------------------------------ chute profiles
def sphere_volume_below(z: np.ndarray, centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Volume (m^3) of each sphere (``centre`` heights, ``radius``) below the height ``z``
    (broadcast): pi (r^2 t - t^3 / 3 + 2 r^3 / 3) with t = clip(z - centre, -r, r)."""
    t = np.clip(z - centre, -radius, radius)
    return math.pi * (radius ** 2 * t - t ** 3 / 3.0 + 2.0 * radius ** 3 / 3.0)


def chute_station(p: dict, x0: float, x1: float, width: float, dz: float = 2.5e-4,
                  z_max: float = 0.06) -> Optional[dict]:
    """The flow at one down-slope station, from the particles whose centres lie in x0 <= x < x1
    (m) of a chute ``width`` (m) wide whose base is z = 0 (x down the slope, z normal to it).

    * solid fraction profile phi(z): each sphere's exact volume in slices ``dz`` thick, over
      the slab volume (x1 - x0) width dz;
    * flow depth ``h``: where phi falls below half the flow body's solid fraction (the mean of
      phi between one diameter above the base and the height holding half of the slab's solid
      volume), linearly interpolated: a free surface defined by density, insensitive to the few
      spheres that saltate above it;
    * ``u_mean``: the mass-weighted mean down-slope velocity (the depth average of phi u over
      that of phi: what the mass flux divides by); ``u_surface``: the mean of the spheres whose
      tops lie within one diameter of h; ``u_base``: of the spheres whose centres lie within one
      diameter of the base;
    * ``flux``: sum(m u) / (x1 - x0), kg/s through the station (steady flow: the feed rate);
      ``phi``: the body's solid fraction; ``count``.
    Returns None for fewer than 20 spheres."""
    x, v, r, m = p["position"], p["velocity"], p["radius"], p["mass"]
    sel = (x[:, 0] >= x0) & (x[:, 0] < x1)
    if sel.sum() < 20:
        return None
    zc, rr, u, mm = x[sel, 2].astype(float), r[sel].astype(float), v[sel, 0].astype(float), m[sel]
    edges = np.arange(0.0, z_max + dz, dz)
    below = np.array([sphere_volume_below(e, zc, rr).sum() for e in edges])
    phi = np.diff(below) / ((x1 - x0) * width * dz)
    mid = 0.5 * (edges[1:] + edges[:-1])
    d = 2.0 * float(np.median(rr))
    half = edges[np.searchsorted(below, 0.5 * below[-1])]
    body = (mid > d) & (mid < max(half, d + 2 * dz))
    phi_body = float(phi[body].mean()) if body.any() else float(phi.max())
    above = np.nonzero((mid > half) & (phi < 0.5 * phi_body))[0]
    if len(above):
        k = above[0]
        # interpolate between slice k-1 (>= half) and slice k (< half)
        f0, f1 = phi[k - 1], phi[k]
        h = mid[k - 1] + (f0 - 0.5 * phi_body) / max(f0 - f1, 1e-30) * dz
    else:
        h = float(zc.max() + rr.max())
    top = zc + rr > h - d
    return {"h": float(h), "u_mean": float(np.sum(mm * u) / np.sum(mm)),
            "u_surface": float(u[top].mean()) if top.any() else float("nan"),
            "u_base": float(u[zc < d].mean()) if np.any(zc < d) else float("nan"),
            "flux": float(np.sum(mm * u) / (x1 - x0)), "phi": phi_body, "count": int(sel.sum())}


def axial_profile(sim, sections: int, axis_point, axis_direction, length: float) -> dict:
    """The solids along a drum's axis now: per section of ``length``/``sections`` (m) from
    ``axis_point`` along unit ``axis_direction``, the particle count, the mass-weighted mean
    temperature (K) and moisture (kg/kg, when drying) and the section centres (m)."""
    p = sim.particles()
    axis = np.asarray(axis_direction, float)
    s = (p["position"] - np.asarray(axis_point, float)) @ axis
    k = np.floor(s / length * sections).astype(int)
    inside = (k >= 0) & (k < sections)
    mass = p["mass"] if "mass" in p else p["radius"] ** 3
    out = {"centre": (np.arange(sections) + 0.5) * length / sections,
           "count": np.bincount(k[inside], minlength=sections)}
    weight = np.bincount(k[inside], weights=mass[inside], minlength=sections)
    with np.errstate(invalid="ignore", divide="ignore"):
        if "temperature" in p:
            out["temperature"] = np.bincount(k[inside], weights=(mass * p["temperature"])[inside],
                                             minlength=sections) / weight
        if "moisture" in p:
            out["moisture"] = np.bincount(k[inside], weights=(mass * p["moisture"])[inside],
                                          minlength=sections) / weight
    return out


def counter_current_gas_temperature(solids_temperature, solids_moisture, outlet_temperature,
                                    outlet_moisture, solids_flow, gas_flow, solids_heat_capacity,
                                    gas_heat_capacity, gas_inlet_temperature, latent_heat,
                                    water_heat_capacity, evaporation_temperature):
    """The steady 1-D heat balance of a counter-current dryer, section by section: the gas
    temperature (K) at a cross-section where the solids are at ``solids_temperature`` (K) with
    ``solids_moisture`` (kg/kg), from the balance of the part between it and the solids'
    outlet (where the gas enters at ``gas_inlet_temperature``):

        m_g c_g (T_g,in - T_g) = m_s [(c_s + X_out c_w) T_out - (c_s + X c_w) T_s]
                                 + m_s (X - X_out) (L + c_w T_e)

    m_s the dry solids' flow, m_g the gas's (kg/s), c in J/(kg K), L J/kg; the vapour leaves
    with L + c_w T_e per kg (thermal/moisture.py). No heat from elsewhere (a burner's
    radiation, walls) enters it: where the DEM's gas is hotter than this, the solids got heat
    the gas did not give."""
    t = np.asarray(solids_temperature, float)
    x = np.asarray(solids_moisture, float)
    gain = solids_flow * ((solids_heat_capacity + outlet_moisture * water_heat_capacity) * outlet_temperature
                          - (solids_heat_capacity + x * water_heat_capacity) * t)
    gain += solids_flow * (x - outlet_moisture) * (latent_heat + water_heat_capacity * evaporation_temperature)
    return gas_inlet_temperature - gain / (gas_flow * gas_heat_capacity)


def longer_cooler_outlet(heat_flows, length: float, bed_temperatures, wall_temperature: float,
                         inlet_temperature: float, mass_rate: float, heat_capacity: float,
                         full_length: float, blocks: int = 4) -> dict:
    """Plug-flow estimate of where the solids of a longer indirect cooler leave, from a short
    one's run: the short run's conductance per metre of shell, UA' = Q / (L (T_bed - T_wall))
    (W/(m K); Q W into the shell, L m, T_bed the mean temperature of the solids inside, K),
    held along ``full_length`` (m); then T_out = T_w + (T_in - T_w) exp(-NTU) with
    NTU = UA' L_full / (m_dot c) (mass_rate kg/s, heat_capacity J/(kg K)). The same bed along
    the whole length (fill, mixing, shell contact) is the assumption; the stated error is the
    scatter of UA' between ``blocks`` consecutive parts of the samples (one standard
    deviation of the block means, over sqrt(blocks)). Returns conductance_per_metre,
    its error, ntu, outlet_temperature and its error (K)."""
    q = np.asarray(heat_flows, float)
    t_bed = np.asarray(bed_temperatures, float)
    per_metre = q / (length * (t_bed - wall_temperature))
    parts = [float(np.mean(p)) for p in np.array_split(per_metre, max(1, min(blocks, len(per_metre))))]
    mean = float(np.mean(per_metre))
    error = float(np.std(parts, ddof=1) / math.sqrt(len(parts))) if len(parts) > 1 else 0.0
    capacity_rate = mass_rate * heat_capacity

    def outlet(ua):
        return wall_temperature + (inlet_temperature - wall_temperature) * math.exp(
            -ua * full_length / capacity_rate)
    t_out = outlet(mean)
    spread = 0.5 * abs(outlet(max(mean - error, 0.0)) - outlet(mean + error))
    return {"conductance_per_metre": mean, "conductance_per_metre_error": error,
            "ntu": mean * full_length / capacity_rate, "outlet_temperature": t_out,
            "outlet_temperature_error": spread}
