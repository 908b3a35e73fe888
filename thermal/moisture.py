"""Moisture and drying (PHYSICS.md): a particle of dry mass m carries water X m (X kg water per
kg dry solid). Its thermal mass is C = m (c + X c_w) (c_w liquid water). Below the evaporation
temperature T_e it heats as any particle; heat that would take it above T_e while it is wet
evaporates water instead (the latent heat L), so it holds at T_e until dry, then heats again:

    surplus = C (T + Q dt / C - T_e) > 0:   dm = min(surplus / L, X m),
    C' = C - dm c_w,   T' = T_e + (surplus - dm L) / C'

which balances the enthalpy C T exactly, the vapour leaving with dm (L + c_w T_e). A particle
wetter and hotter than T_e (inserted hot) flashes its excess sensible heat into vapour in one
step. The mechanical mass stays the dry mass (the water is a small, neglected load).
"""
import taichi as ti


@ti.func
def heat_and_dry(temperature, moisture, inverse_thermal_mass, dry_mass, energy,
                 evaporation_temperature, latent_heat, water_heat_capacity):
    """One explicit step with ``energy`` = Q dt J into the particle. Returns (temperature K,
    moisture kg/kg, inverse thermal mass 1/(J/K), evaporated water kg)."""
    t_new = temperature + energy * inverse_thermal_mass
    x_new = moisture
    inv_new = inverse_thermal_mass
    evaporated = 0.0 * energy
    if moisture > 0.0 and t_new > evaporation_temperature:
        thermal_mass = 1.0 / inverse_thermal_mass
        surplus = thermal_mass * (t_new - evaporation_temperature)
        water = moisture * dry_mass
        evaporated = surplus / latent_heat
        x_new = moisture - evaporated / dry_mass
        if evaporated >= water:
            evaporated = water
            x_new = 0.0
        dry_thermal_mass = thermal_mass - evaporated * water_heat_capacity
        t_new = evaporation_temperature + (surplus - evaporated * latent_heat) / dry_thermal_mass
        inv_new = 1.0 / dry_thermal_mass
    return t_new, x_new, inv_new, evaporated
