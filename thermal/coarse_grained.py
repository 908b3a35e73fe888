"""The wall heat law of coarse-grained particles: a particle that stands for a bed of much finer
ones takes heat from a wall as that bed would (Schlünder's contact resistance of the fine
particles in series with penetration into the bed), not as one big sphere would.

Why: a wall-to-bed coefficient is set by the particles touching the wall. A sphere's gas-gap
conductance to a wall grows only like its radius (times a logarithm), so per wall area it falls
like 1/d: 30 mm spheres cool tens of times slower than the 100 um ash they stand for. Scaling
the sphere's own conductance by the size ratio would not help either: for a fine powder the
contact resistance is small and the bed itself limits the flux (the heat penetrates a few
millimetres in the seconds a patch of bed rests on the wall), while a lumped 30 mm sphere would
store that heat without resistance. So the law follows the penetration model the dryer and
cooler designers use (Schlünder & Mollekopf 1984; VDI Heat Atlas M7), with the time the
particle has rested against a wall taken from the DEM:

    G = w A_p h(t)                                                               [W/K]
    h(t) = alpha_WS erfcx(alpha_WS sqrt(t / e)),   e = rho_b c k_bed            [W/(m^2 K)]

the exact flux of a semi-infinite body behind a surface conductance alpha_WS, held at the
wall's temperature from t = 0 (Carslaw & Jaeger sec. 2.7): alpha_WS at t = 0, sqrt(e / (pi t))
once the bed limits it. t is the thermal time (time_scale x simulated) since the particle
came within ``reach`` of a heat-exchanging wall or body and stayed there; the heat it takes is
mixed into it at once (one temperature per particle), as the real bed mixes the layer a
wall element warmed when the paddles or the drum renew it.

    alpha_WS = phi_A alpha_WP + (1 - phi_A) 2 k_g / (sqrt(2) d + 2 (l + delta))   Schlünder's
    first-layer coefficient of particles of the represented diameter d (correlations.py)
    rho_b = rho_s (1 - eps), k_bed = Zehner-Bauer-Schlünder (k_s, k_g, eps) of the real bed
    A_p = pi R^2 / phi_A: the wall area per particle of the first layer, at the coverage
        phi_A (``surface_coverage``, 0.8) that alpha_WS assumes (a random monolayer of spheres
        at a wall covers about 0.8 of it; a hexagonal one 0.91)
    w = 1 touching, falling linearly to 0 at a gap of ``reach`` R (no jump as a particle
    lifts off)

Limits (stated, not hidden): the penetration must stay shallower than the particle (depth
sqrt(pi a t) << 2 R, a = k_bed/(rho_b c)); otherwise the lumped particle's own warming
counts the bed's resistance twice. The contact-spot and gas-gap laws of the big sphere are
not added for such particles (they describe a 30 mm sphere, not the bed). Radiation in the
gap is not in alpha_WS here.
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from .correlations import erfcx as erfcx_reference
from .correlations import wall_contact_coefficient, zehner_schlunder


def wall_area_per_particle(radius: float, coverage: float) -> float:
    """A_p = pi R^2 / phi_A (m^2): the wall area each first-layer particle of radius R (m)
    stands for at the coverage phi_A."""
    return math.pi * radius * radius / coverage


# Numerical Recipes' Chebyshev fit of erfc (Press et al., "erfcc", fractional error below
# 1.2e-7 for every x >= 0): erfc(x) = t exp(-x^2 + P(t)), t = 1/(1 + x/2), so exp(x^2) erfc(x)
# = t exp(P(t)) - no overflow at large x, one exponential
_ERFCC = (-1.26551223, 1.00002368, 0.37409196, 0.09678418, -0.18628806, 0.27886807,
          -1.13520398, 1.48851587, -0.82215223, 0.17087277)


@ti.func
def erfcx(x):
    """exp(x^2) erfc(x) for x >= 0, relative error below 1.2e-7."""
    t = 1.0 / (1.0 + 0.5 * x)
    poly = ti.static(_ERFCC[9]) + 0.0 * x
    for k in ti.static(range(8, -1, -1)):
        poly = ti.static(_ERFCC[k]) + t * poly
    return t * ti.exp(poly)


@ti.func
def bed_coefficient(alpha_ws, effusivity_sq, age):
    """h(t) = alpha_WS erfcx(alpha_WS sqrt(t / e)) (W/(m^2 K)): the flux per kelvin into a
    semi-infinite bed (e = rho c k, J^2/(s m^4 K^2)) behind a contact coefficient alpha_WS, t
    (s, thermal) after its surface met the wall."""
    return alpha_ws * erfcx(alpha_ws * ti.sqrt(age / effusivity_sq))


def bed_coefficient_reference(alpha_ws: float, effusivity_sq: float, age: float) -> float:
    """numpy/math twin of :func:`bed_coefficient` (math.erfc), for tests."""
    return alpha_ws * erfcx_reference(alpha_ws * math.sqrt(age / effusivity_sq))


def bed_heat_reference(alpha_ws: float, effusivity_sq: float, age: float) -> float:
    """The integral of h over 0..t (J/(m^2 K)): (e / alpha_WS) [erfcx(b) - 1 + 2 b / sqrt(pi)],
    b = alpha_WS sqrt(t / e) (Carslaw & Jaeger 2.7), for tests."""
    if age <= 0.0:
        return 0.0
    b = alpha_ws * math.sqrt(age / effusivity_sq)
    if b < 1e-4:
        return alpha_ws * age * (1.0 - 4.0 * b / (3.0 * math.sqrt(math.pi)) + 0.5 * b * b)
    return effusivity_sq / alpha_ws * (erfcx_reference(b) - 1.0 + 2.0 * b / math.sqrt(math.pi))


def represented_bed(material, coarse, k_gas: float, temperature: float) -> dict:
    """What the law needs of a coarse-grained material (a scene Material with its
    ``coarse_grained`` settings): alpha_WS (W/(m^2 K)) of particles of the represented diameter
    at ``temperature`` (K, for the gas's mean free path), the bed's density rho_b (kg/m^3),
    conductivity k_bed (W/(m K)), e = rho_b c k_bed, and A_p / R^2 (the kernel's factor)."""
    ws = wall_contact_coefficient(coarse.represented_diameter, k_gas, temperature,
                                  roughness=coarse.roughness, coverage=coarse.surface_coverage)
    density = material.density * (1.0 - coarse.bed_porosity)
    k_bed = zehner_schlunder(material.thermal_conductivity, k_gas, coarse.bed_porosity)
    return {"alpha_ws": ws["alpha_ws"], "free_path": ws["free_path"], "bed_density": density,
            "bed_conductivity": k_bed,
            "area_over_r2": wall_area_per_particle(1.0, coarse.surface_coverage),
            "effusivity_sq": density * material.heat_capacity * k_bed}


def reference_temperature(scene, material: str) -> float:
    """K, for the gas's mean free path in alpha_WS: the mean of the heat-exchanging walls'
    and bodies' mean temperature and the hottest temperature the material's particles
    are filled or fed at."""
    hot = [w.temperature for w in list(scene.walls) + list(scene.bodies)
           if w.temperature is not None]
    fed = [_hottest(f) for f in list(scene.fills) + list(scene.factories)
           if f.material == material]
    fed = [t for t in fed if t is not None]
    wall = sum(hot) / len(hot)
    return 0.5 * (wall + (max(fed) if fed else wall))


def _hottest(source):
    """A fill's or factory's temperature, K: the one it gives, else the hottest of the
    particles a results file gives a fill (None when neither)."""
    if source.temperature is not None:
        return source.temperature
    given = getattr(source, "frame_values", {}).get("temperature")
    return float(np.max(given)) if given is not None and len(given) else None


def represented(scene) -> dict:
    """{material name: coarse_grained.represented_bed(...) at its reference temperature}."""
    th = scene.settings.get("thermal")
    out = {}
    for name, mat in scene.materials.items():
        if mat.coarse_grained is not None:
            out[name] = represented_bed(
                mat, mat.coarse_grained, th.gap_gas_conductivity,
                reference_temperature(scene, name))
    return out


def tables_for(scene, tables) -> dict:
    """(M, M) tables: [a, :] = alpha_WS (W/(m^2 K)) and e = rho_b c k_bed of material a's
    represented bed and its wall area per particle A_p / R^2 = pi / phi_A, 0 where a is
    not coarse-grained."""
    beds = represented(scene)
    m = len(tables.names)
    alpha, effusivity, area = np.zeros((m, m)), np.zeros((m, m)), np.zeros((m, m))
    for a, name in enumerate(tables.names):
        if name in beds:
            alpha[a, :] = beds[name]["alpha_ws"]
            effusivity[a, :] = beds[name]["effusivity_sq"]
            area[a, :] = beds[name]["area_over_r2"]
    return {"coarse_alpha_ws": alpha, "coarse_effusivity_sq": effusivity,
            "coarse_area_over_r2": area}


__all__ = ["wall_area_per_particle", "erfcx", "bed_coefficient", "bed_coefficient_reference",
           "bed_heat_reference", "represented_bed", "reference_temperature", "represented",
           "tables_for"]
