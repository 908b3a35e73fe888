"""Moisture and drying (PHYSICS.md): a particle of dry mass m carries water X m (X kg water per
kg dry solid). Its thermal mass is C = m (c + X c_w) (c_w liquid water). Below the evaporation
temperature T_e it heats as any particle; heat that would take it above T_e while it is wet
evaporates water instead (the latent heat L), so it holds at T_e until dry, then heats again:

    surplus = C (T + Q dt / C - T_e) > 0:   dm = min(surplus / L, X m),
    C' = C - dm c_w,   T' = T_e + (surplus - dm L) / C'

which balances the enthalpy C T exactly, the vapour leaving with dm (L + c_w T_e). A particle
wetter and hotter than T_e (inserted hot) flashes its excess sensible heat into vapour in one
step. The mechanical mass stays the dry mass (the water is a small, neglected load).

Below a critical moisture X_cr (the falling-rate period: the water left is inside the grain and
reaches the surface ever more slowly) only the fraction X / X_cr of this step's heat above T_e
evaporates water, and the rest warms the particle (a linear characteristic drying curve):

    surplus = C (T + Q dt / C - max(T, T_e)),   dm = min((X / X_cr) surplus / L, X m)

with the same enthalpy balance. X_cr = 0 (the default) has no falling rate.
"""
import taichi as ti


@ti.func
def heat_and_dry(temperature, moisture, inverse_thermal_mass, dry_mass, energy,
                 evaporation_temperature, latent_heat, water_heat_capacity,
                 critical_moisture, falling_rate: ti.template()):
    """One explicit step with ``energy`` = Q dt J into the particle. Returns (temperature K,
    moisture kg/kg, inverse thermal mass 1/(J/K), evaporated water kg). ``critical_moisture``
    kg/kg, read only when ``falling_rate`` (a Python bool: False compiles the falling rate
    away; the scene's X_cr > 0)."""
    t_new = temperature + energy * inverse_thermal_mass
    x_new = moisture
    inv_new = inverse_thermal_mass
    evaporated = 0.0 * energy
    if moisture > 0.0 and t_new > evaporation_temperature:
        thermal_mass = 1.0 / inverse_thermal_mass
        surplus = thermal_mass * (t_new - evaporation_temperature)     # the enthalpy above T_e
        water = moisture * dry_mass
        evaporated = surplus / latent_heat
        if ti.static(falling_rate):
            if moisture < critical_moisture:
                # falling rate: this step's heat above T_e only, a fraction X / X_cr of it
                evaporated = (moisture / critical_moisture * thermal_mass
                              * (t_new - ti.max(temperature, evaporation_temperature))
                              / latent_heat)
        x_new = moisture - evaporated / dry_mass
        if evaporated >= water:
            evaporated = water
            x_new = 0.0
        dry_thermal_mass = thermal_mass - evaporated * water_heat_capacity
        t_new = evaporation_temperature + (surplus - evaporated * latent_heat) / dry_thermal_mass
        inv_new = 1.0 / dry_thermal_mass
    return t_new, x_new, inv_new, evaporated
