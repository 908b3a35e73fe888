"""A whole rotary dryer (or cooler with a gas) as a steady 1-D march along its axis: the solids
(dry flow F kg/s, moisture X kg/kg dry, temperature T_s) and the gas (dry flow G kg/s, humidity
Y kg/kg dry gas, temperature T_g), counter- or co-current, exchanging heat through the
gas-solids conductance per metre of drum ha' (W/(m K)) and losing heat through the shell.

The solids are the existing particle drying model (thermal/moisture.py) applied to the mean
parcel of solids as it moves down the drum: below the evaporation temperature T_e heat warms
it; heat that would take a wet parcel above T_e evaporates water instead (the constant-rate
period); below the critical moisture X_cr only the fraction X/X_cr of that heat evaporates water
and the rest warms the solids (the falling-rate period, a linear characteristic drying curve).
Enthalpies are counted from 0 K as the particle model does: the solids carry
h_s = (c_s + X c_w) T_s per kg dry solid, the vapour leaves them with h_v(T_e) = c_w T_e + L,
and the gas carries H_g = c_g T_g + Y h_v(T_g), h_v(T) = c_w T_e + L + c_v (T - T_e) per kg dry
gas (vapour formed at T_e, then heated as vapour).

Per metre, the solids gain q = ha' (T_g - T_s) and the gas also loses
U_shell pi D (T_g - T_ambient) through the shell. Both streams are stepped with the same q, loss
and evaporation in every cell, so the discrete energy balance closes to round-off:
F h_s + G H_g in = F h_s + G H_g out + shell loss. A counter-current dryer is a two-point
problem (the solids known at x = 0, the gas at x = L): it is shot from the gas's outlet state
(T_g, Y at x = 0) until the gas arrives at x = L in its inlet state.

The closures (what a slice gives, or a correlation where no slice has been mapped):
- residence time tau, hence the dry hold-up per metre F tau / L, from Friedman & Marshall (1949,
  in Perry's handbook): tau = 0.23 L / (S N^0.9 D) +- 0.6 B L G / F minutes (L, D in ft in the
  second term; B = 5 d_p^-0.5, d_p in um; G and F the gas and feed mass velocities in
  lb/(h ft2); + for counter-current gas, which holds the solids back);
- the volumetric gas-solids coefficient Ua = K G^0.67 / D (Perry's handbook, K ~ 0.5 in
  Btu/(h ft3 F) with G in lb/(h ft2) and D in ft), ha' = Ua A for the drum's cross-section A, G
  the local gas mass velocity (dry gas and its vapour).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import SceneError

# unit conversions for the correlations in Perry's (exact definitions)
FOOT = 0.3048                    # m
POUND = 0.45359237               # kg
BTU = 1055.05585262              # J (International Table Btu)
RANKINE = 5.0 / 9.0              # K per degree F
LB_PER_H_FT2 = POUND / 3600.0 / FOOT ** 2      # kg/(s m^2) in one lb/(h ft2)
BTU_PER_H_FT3_F = BTU / 3600.0 / FOOT ** 3 / RANKINE   # W/(m^3 K) in one Btu/(h ft3 F)


def friedman_marshall_residence(length: float, diameter: float, incline: float, rpm: float,
                                particle_diameter: float, gas_mass_velocity: float,
                                feed_mass_velocity: float, counter_current: bool) -> float:
    """Mean residence time (s) of the solids in a flighted drum, Friedman & Marshall (1949):
    tau = 0.23 L / (S N^0.9 D) +- 0.6 B L G / F minutes. ``length``, ``diameter`` and
    ``particle_diameter`` in m, ``incline`` in rad (S = tan), ``rpm`` in rev/min, the mass
    velocities in kg/(s m^2) per drum cross-section; counter-current gas adds its term."""
    slope = math.tan(incline)
    minutes = 0.23 * length / (slope * rpm ** 0.9 * diameter)
    if gas_mass_velocity > 0.0:
        b = 5.0 * (particle_diameter * 1e6) ** -0.5
        gas_term = 0.6 * b * (length / FOOT) * (gas_mass_velocity / LB_PER_H_FT2) / (
            feed_mass_velocity / LB_PER_H_FT2)
        minutes += gas_term if counter_current else -gas_term
    return 60.0 * minutes


def perry_volumetric_coefficient(gas_mass_velocity: float, diameter: float, k: float = 0.5) -> float:
    """Ua (W/(m^3 K)) of a flighted rotary dryer, Perry's handbook: Ua = K G^0.67 / D in
    Btu/(h ft3 F) with G in lb/(h ft2) and D in ft; here G in kg/(s m^2) and D in m, K in the
    handbook's units (~0.5)."""
    g = gas_mass_velocity / LB_PER_H_FT2
    return k * g ** 0.67 / (diameter / FOOT) * BTU_PER_H_FT3_F


def saturation_pressure(temperature: float) -> float:
    """Water's saturation vapour pressure (Pa) at ``temperature`` (K): Buck (1981) over water,
    0.05 % from 0 to 50 C and within 1 % to 100 C."""
    c = temperature - 273.15
    return 611.21 * math.exp((18.678 - c / 234.5) * (c / (257.14 + c)))


def dew_point(humidity: float, pressure: float = 101325.0) -> float:
    """The dew point (K) of gas with ``humidity`` kg water per kg dry gas (air's molar mass) at
    ``pressure`` Pa (bisection on saturation_pressure, -40 to 150 C)."""
    if humidity <= 0.0:
        return float("nan")
    partial = humidity * pressure / (0.622 + humidity)
    lo, hi = 233.15, 423.15
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if saturation_pressure(mid) < partial else (lo, mid)
    return 0.5 * (lo + hi)


@dataclass
class Dryer:
    """A rotary dryer's design and operating point (SI units; see demos/dryers/*.toml)."""
    diameter: float                  # m, the drum's inside
    length: float                    # m
    incline: float                   # rad, the discharge end lower
    rpm: float                       # rev/min
    feed: float                      # kg/s of dry solids
    feed_moisture: float             # kg water / kg dry solid
    feed_temperature: float          # K
    particle_diameter: float         # m
    solids_heat_capacity: float      # J/(kg K)
    bulk_density: float              # kg/m^3 of the dry bulk (fill fraction)
    gas_flow: float                  # kg/s of dry gas
    gas_temperature: float           # K, at the gas inlet
    gas_humidity: float = 0.0        # kg water / kg dry gas at the gas inlet
    gas_heat_capacity: float = 1100.0            # J/(kg K), dry gas
    counter_current: bool = True
    critical_moisture: float = 0.0   # kg/kg: the falling-rate period below it (0: none)
    target_moisture: float = 0.005   # kg/kg: the product's aim (reported, not imposed)
    evaporation_temperature: float = 373.15      # K (as [thermal]'s default)
    latent_heat: float = 2.26e6      # J/kg at T_e
    water_heat_capacity: float = 4186.0          # J/(kg K), liquid
    vapour_heat_capacity: float = 1900.0         # J/(kg K), steam
    shell_loss_coefficient: float = 0.0          # W/(m^2 K), gas to the surroundings
    ambient_temperature: float = 288.15          # K
    perry_k: float = 0.5             # Btu/(h ft3 F) in Ua = K G^0.67 / D
    # what of a map's solids meets the gas: "curtains" (the airborne particles) or "surface"
    # (those and the bed's and the flights' loads' surface open to the gas)
    exposure: str = "curtains"
    residence_time: float | None = None          # s: given (a map's), else Friedman-Marshall
    conductance_per_metre: float | None = None   # W/(m K): given (a map's), else Perry's Ua
    uncertainty: float = 0.25        # relative, of each closure (for the sensitivity)
    cells: int = 800
    source: str = "<dryer>"
    # the gas's transport properties (a map's closure: h from Ranz-Marshall); air at 400 C
    gas_density: float = 0.52        # kg/m^3
    gas_viscosity: float = 3.3e-5    # Pa s
    gas_conductivity: float = 0.051  # W/(m K)
    # from a map (app/dryer_map.py): each closure's own relative uncertainty, the drive torque
    residence_uncertainty: float | None = None
    conductance_uncertainty: float | None = None
    drive_torque: float | None = None            # N m
    map_info: dict | None = None
    # the closures moved by these factors (the sensitivity, the capacity's)
    residence_factor: float = 1.0
    conductance_factor: float = 1.0

    @property
    def area(self) -> float:
        """The drum's cross-section (m^2)."""
        return math.pi * self.diameter ** 2 / 4.0

    def residence(self) -> float:
        """Mean residence time of the solids (s): the given one, or Friedman-Marshall's."""
        if self.residence_time is not None:
            return self.residence_time * self.residence_factor
        return self.residence_factor * friedman_marshall_residence(
            self.length, self.diameter, self.incline, self.rpm, self.particle_diameter,
            self.gas_flow * (1.0 + self.gas_humidity) / self.area,
            self.feed * (1.0 + self.feed_moisture) / self.area, self.counter_current)

    def conductance(self, gas_flow_with_vapour: float) -> float:
        """Gas-solids conductance per metre of drum (W/(m K)) at a local gas flow (kg/s)."""
        if self.conductance_per_metre is not None:
            return self.conductance_per_metre * self.conductance_factor
        return self.conductance_factor * perry_volumetric_coefficient(
            gas_flow_with_vapour / self.area, self.diameter, self.perry_k) * self.area


# ---- the parcel of solids: thermal/moisture.py's step, with the falling rate ---------------

def heat_and_dry(temperature, moisture, energy, d: Dryer):
    """One step of ``energy`` J per kg dry solid into the parcel at ``temperature`` K with
    ``moisture`` kg/kg: (temperature K, moisture kg/kg, evaporated kg per kg dry solid), the
    enthalpy (c_s + X c_w) T balanced exactly with the vapour leaving at c_w T_e + L. The same
    arithmetic as thermal/moisture.py's particle step (tested to round-off)."""
    capacity = d.solids_heat_capacity + moisture * d.water_heat_capacity
    t_new = temperature + energy / capacity
    if moisture <= 0.0 or t_new <= d.evaporation_temperature:
        return t_new, moisture, 0.0
    above = capacity * (t_new - d.evaporation_temperature)       # the enthalpy above T_e
    evaporated = above / d.latent_heat                           # constant rate
    if d.critical_moisture > 0.0 and moisture < d.critical_moisture:
        # falling rate: this step's heat above T_e only, a fraction X / X_cr of it
        evaporated = (moisture / d.critical_moisture * capacity
                      * (t_new - max(temperature, d.evaporation_temperature)) / d.latent_heat)
    x_new = moisture - evaporated
    if evaporated >= moisture:
        evaporated, x_new = moisture, 0.0
    dry_capacity = capacity - evaporated * d.water_heat_capacity
    t_out = d.evaporation_temperature + (above - evaporated * d.latent_heat) / dry_capacity
    return t_out, x_new, evaporated


def vapour_enthalpy(temperature: float, d: Dryer) -> float:
    """J/kg of water vapour at ``temperature`` K, from liquid at 0 K (formed at T_e)."""
    return (d.water_heat_capacity * d.evaporation_temperature + d.latent_heat
            + d.vapour_heat_capacity * (temperature - d.evaporation_temperature))


def gas_enthalpy(temperature: float, humidity: float, d: Dryer) -> float:
    """J per kg dry gas, with its vapour."""
    return d.gas_heat_capacity * temperature + humidity * vapour_enthalpy(temperature, d)


def gas_temperature(enthalpy: float, humidity: float, d: Dryer) -> float:
    """The inverse of gas_enthalpy (K)."""
    offset = humidity * (d.water_heat_capacity * d.evaporation_temperature + d.latent_heat
                         - d.vapour_heat_capacity * d.evaporation_temperature)
    return (enthalpy - offset) / (d.gas_heat_capacity + humidity * d.vapour_heat_capacity)


# ---- the march --------------------------------------------------------------------------

@dataclass
class Profile:
    """The marched dryer: arrays at the cell faces from the feed (x = 0) to the discharge."""
    x: np.ndarray                   # m
    solids_temperature: np.ndarray  # K
    moisture: np.ndarray            # kg/kg dry
    gas_temperature: np.ndarray     # K
    humidity: np.ndarray            # kg/kg dry gas
    heat_to_solids: np.ndarray      # W per cell (len - 1)
    shell_loss: np.ndarray          # W per cell
    evaporation: np.ndarray         # kg/s per cell
    extras: dict = field(default_factory=dict)


def _march(d: Dryer, gas_at_feed_end: tuple[float, float]) -> Profile:
    """March from x = 0 with the gas at the feed end at (T K, Y kg/kg); the gas flows towards
    x = 0 (counter-current) or away from it (co-current)."""
    n = d.cells
    dx = d.length / n
    sign = 1.0 if d.counter_current else -1.0     # d(G H_g)/dx = sign (q + loss - e h_v)
    perimeter = math.pi * d.diameter
    ts = np.empty(n + 1)
    xs = np.empty(n + 1)
    tg = np.empty(n + 1)
    ys = np.empty(n + 1)
    heat = np.empty(n)
    loss = np.empty(n)
    evap = np.empty(n)
    ts[0], xs[0] = d.feed_temperature, d.feed_moisture
    tg[0], ys[0] = gas_at_feed_end
    hg = gas_enthalpy(tg[0], ys[0], d)
    hv_e = vapour_enthalpy(d.evaporation_temperature, d)
    for k in range(n):
        g_local = d.gas_flow * (1.0 + ys[k])
        ha = d.conductance(g_local)
        q1 = ha * (tg[k] - ts[k])
        l1 = d.shell_loss_coefficient * perimeter * (tg[k] - d.ambient_temperature)
        # Heun: the rates at the start, a trial step, the rates at its end, their mean
        t_try, x_try, e_try = heat_and_dry(ts[k], xs[k], q1 * dx / d.feed, d)
        h_try = hg + sign * (q1 + l1 - e_try * d.feed / dx * hv_e) * dx / d.gas_flow
        y_try = ys[k] - sign * e_try * d.feed / d.gas_flow
        tg_try = gas_temperature(h_try, y_try, d)
        q = 0.5 * (q1 + ha * (tg_try - t_try))
        lo = 0.5 * (l1 + d.shell_loss_coefficient * perimeter * (tg_try - d.ambient_temperature))
        ts[k + 1], xs[k + 1], e = heat_and_dry(ts[k], xs[k], q * dx / d.feed, d)
        heat[k], loss[k], evap[k] = q * dx, lo * dx, e * d.feed
        hg += sign * (heat[k] + loss[k] - evap[k] * hv_e) / d.gas_flow
        ys[k + 1] = ys[k] - sign * evap[k] / d.gas_flow
        tg[k + 1] = gas_temperature(hg, ys[k + 1], d)
    return Profile(np.linspace(0.0, d.length, n + 1), ts, xs, tg, ys, heat, loss, evap)


def solve(d: Dryer) -> Profile:
    """The steady dryer: co-current is marched directly; counter-current is shot from the gas
    outlet state at the feed end until the gas arrives in its inlet state (scipy's hybrid
    Newton on T_g and Y, to 1e-9 K and 1e-12 kg/kg)."""
    if not d.counter_current:
        return _march(d, (d.gas_temperature, d.gas_humidity))
    from scipy.optimize import root
    # a first guess from the overall balance: all water evaporated, the solids leaving at T_e
    y0 = d.gas_humidity + d.feed * d.feed_moisture / d.gas_flow
    need = d.feed * (d.solids_heat_capacity * (d.evaporation_temperature - d.feed_temperature)
                     + d.feed_moisture * d.latent_heat)
    h_in = gas_enthalpy(d.gas_temperature, d.gas_humidity, d)
    t0 = max(gas_temperature(h_in - need / d.gas_flow, y0, d), d.feed_temperature + 1.0)
    scale = np.array([d.gas_temperature, max(d.feed_moisture * d.feed / d.gas_flow, 1e-6)])

    def residual(z):
        p = _march(d, (z[0] * scale[0], d.gas_humidity + z[1] * scale[1]))
        return [(p.gas_temperature[-1] - d.gas_temperature) / scale[0],
                (p.humidity[-1] - d.gas_humidity) / scale[1]]

    best = None
    for start in ([t0, y0], [0.5 * (t0 + d.gas_temperature), d.gas_humidity],
                  [d.feed_temperature + 5.0, d.gas_humidity]):
        z0 = [start[0] / scale[0], (start[1] - d.gas_humidity) / scale[1]]
        sol = root(residual, z0, method="hybr", options={"xtol": 1e-13})
        err = max(abs(v) for v in residual(sol.x))
        if best is None or err < best[1]:
            best = (sol.x, err)
        if err < 1e-11:
            break
    z, err = best
    if err > 1e-7:
        raise SceneError(d.source, "", f"the counter-current march did not converge (the gas "
                         f"misses its inlet state by {err:.2g} relative): the gas may be too "
                         "small a flow to carry the drying (its outlet would be below the "
                         "feed's temperature); raise [gas] mass_flow or temperature")
    return _march(d, (z[0] * scale[0], d.gas_humidity + z[1] * scale[1]))


def answer(d: Dryer) -> dict:
    """A dryer's answers (SI): residence, hold-up, outlet states, heat duty, energy balance."""
    p = solve(d)
    tau = d.residence()
    holdup = d.feed * tau                                  # kg dry solids inside
    fill = holdup / d.bulk_density / (d.area * d.length)
    gas_out_t = float(p.gas_temperature[0 if d.counter_current else -1])
    gas_out_y = float(p.humidity[0 if d.counter_current else -1])
    hv_e = vapour_enthalpy(d.evaporation_temperature, d)
    solids_in = d.feed * (d.solids_heat_capacity + d.feed_moisture * d.water_heat_capacity) * d.feed_temperature
    solids_out = d.feed * (d.solids_heat_capacity + p.moisture[-1] * d.water_heat_capacity) * p.solids_temperature[-1]
    gas_in_flow = d.gas_flow * gas_enthalpy(d.gas_temperature, d.gas_humidity, d)
    gas_out_flow = d.gas_flow * gas_enthalpy(gas_out_t, gas_out_y, d)
    shell = float(np.sum(p.shell_loss))
    imbalance = (solids_in + gas_in_flow) - (solids_out + gas_out_flow + shell)
    burner = d.gas_flow * (gas_enthalpy(d.gas_temperature, d.gas_humidity, d)
                           - gas_enthalpy(d.ambient_temperature, d.gas_humidity, d))
    evaporated = float(np.sum(p.evaporation))
    to_solids = float(np.sum(p.heat_to_solids))
    return {
        "profile": p,
        "residence_time": tau, "holdup": holdup, "holdup_per_metre": holdup / d.length,
        "fill_fraction": fill,
        "solids_outlet_temperature": float(p.solids_temperature[-1]),
        "solids_outlet_moisture": float(p.moisture[-1]),
        "gas_outlet_temperature": gas_out_t, "gas_outlet_humidity": gas_out_y,
        "gas_outlet_dew_point": dew_point(gas_out_y),
        "evaporation": evaporated,
        "heat_to_solids": to_solids,
        "evaporation_heat": evaporated * hv_e,
        "shell_loss": shell,
        "burner_duty": burner,
        "thermal_efficiency": to_solids / burner if burner > 0 else math.nan,
        "energy_in": solids_in + gas_in_flow,
        "energy_imbalance": imbalance,
        "energy_closure": imbalance / burner if burner else math.nan,
        "conductance_per_metre": d.conductance(d.gas_flow * (1.0 + d.gas_humidity)),
        "drive_torque": d.drive_torque if d.drive_torque is not None else math.nan,
    }


# the figures each closure moves, reported with their sensitivity
FIGURES = ("residence_time", "holdup", "solids_outlet_temperature", "solids_outlet_moisture",
           "gas_outlet_temperature", "evaporation", "burner_duty")


def sensitivity(d: Dryer, base: dict | None = None) -> dict:
    """Each figure's change (max of up and down) when each closure is moved by
    +- d.uncertainty: {closure: {figure: change}} and their root sum of squares."""
    base = base or answer(d)
    out = {}
    own = {"residence": d.residence_uncertainty, "conductance": d.conductance_uncertainty}
    for name, changed in (("residence", lambda f: replace(d, residence_factor=f)),
                          ("conductance", lambda f: replace(d, conductance_factor=f))):
        moved = {}
        u = d.uncertainty if own[name] is None else own[name]
        for f in (1.0 + u, 1.0 - u):
            a = answer(changed(f))
            for key in FIGURES:
                moved[key] = max(moved.get(key, 0.0), abs(a[key] - base[key]))
        out[name] = moved
    out["combined"] = {k: math.hypot(*(out[c][k] for c in ("residence", "conductance")))
                       for k in FIGURES}
    return out


def drying_capacity(at_feed, low: float, high: float, target: float, cells: int = 200,
                    tolerance: float = 0.01) -> tuple[float, str]:
    """The largest dry feed (kg/s) in [low, high] whose product leaves at or below ``target``
    moisture (kg/kg): bisection to ``tolerance`` (relative) on ``at_feed(feed) -> Dryer`` (the
    dryer at that feed, its closures re-derived: a map's hold-up changes with the feed) marched
    in ``cells`` cells. Returns (feed, "") or the bound with why: (high, "above") when even the
    highest dries, (low, "below") when even the lowest does not."""
    def dries(feed):
        return answer(replace(at_feed(feed), cells=cells))["solids_outlet_moisture"] <= target
    if dries(high):
        return high, "above"
    if not dries(low):
        return low, "below"
    while high - low > tolerance * high:
        mid = 0.5 * (low + high)
        low, high = (mid, high) if dries(mid) else (low, mid)
    return low, ""
