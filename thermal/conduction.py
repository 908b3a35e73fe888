"""Conduction through the contact area (PHYSICS.md; Batchelor & O'Brien 1977, as in EDEM).

    Q = h_c (T_j - T_i),   h_c = 4 k_i k_j / (k_i + k_j) a,   a = (3 F_n R* / (4 E*))^(1/3)

With the Hertz force F_n = 4/3 E* sqrt(R*) d^(3/2), the contact radius is a = sqrt(R* d). A
softened modulus inflates a; when a material gives its real modulus the radius is scaled by
(E*_sim / E*_real)^x, x = 1/3 for enduring (force-controlled) contacts - the default, right
for the slow dense beds of coolers and dryers - or 1/5 for collisions (Morris et al. 2016).
LIGGGHTS instead uses sqrt(A) of the intersection area (1.77x EDEM's h_c); we follow EDEM.

Rough surfaces (materials with ``surface_roughness``, ``surface_slope`` and ``microhardness``):
the apparent (Hertz) spot touches only at the asperities, whose own constriction resistance is
in series with the spot's (Yovanovich 1982's plastic contact conductance, as Lethe's DEM-MP and
Bahrami et al. use it):

    1/G = 1/(2 k_s a) + 1/(h_c pi a^2),   h_c = 1.25 k_s (m / sigma) (P / H_c)^0.95

k_s = 2 k_i k_j / (k_i + k_j), sigma = sqrt(sigma_i^2 + sigma_j^2) the combined RMS roughness,
m = sqrt(m_i^2 + m_j^2) the combined asperity slope, H_c the softer surface's microhardness,
P = F_n / (pi a^2) the spot's mean pressure (F_n the Hertz force of the simulated overlap, a the
real-modulus radius). Smooth surfaces (sigma -> 0) recover 2 k_s a.
"""
import math

import numpy as np
import taichi as ti

from taichi_dem.scene.model import Material
from taichi_dem.setup.pair_tables import effective_youngs_modulus


@ti.func
def contact_conductance(conductivity_factor, radius_correction, r_eff, normal_overlap):
    """h_c, W/K: ``conductivity_factor`` = 4 k_i k_j/(k_i + k_j) W/(m K), ``radius_correction``
    the softened-modulus factor, ``r_eff`` R* m, ``normal_overlap`` d m."""
    return conductivity_factor * radius_correction * ti.sqrt(r_eff * normal_overlap)


@ti.func
def rough_contact_conductance(conductivity_factor, radius_correction, r_eff, normal_overlap,
                              youngs_sim, micro):
    """h_c, W/K, with the asperities' resistance in series: ``youngs_sim`` E* of the
    simulated moduli (Pa), ``micro`` = 1.25 k_s (m / sigma) / H_c^0.95 (W/(m^2 K Pa^0.95));
    0 = smooth."""
    radius = radius_correction * ti.sqrt(r_eff * normal_overlap)
    conductance = conductivity_factor * radius
    if micro > 0.0 and radius > 0.0:
        force = 4.0 / 3.0 * youngs_sim * ti.sqrt(r_eff) * normal_overlap * ti.sqrt(normal_overlap)
        area = math.pi * radius * radius
        micro_conductance = micro * (force / area) ** 0.95 * area
        conductance = 1.0 / (1.0 / conductance + 1.0 / micro_conductance)
    return conductance


def micro_coefficient(k_i, k_j, roughness_i, roughness_j, slope_i, slope_j, hardness_i,
                      hardness_j) -> float:
    """1.25 k_s (m / sigma) / H_c^0.95 of a pair of surfaces (0 where the pair is smooth or
    lacks the keys): k W/(m K), RMS roughness m, asperity slope (1), microhardness Pa (None:
    not given)."""
    sigma = math.hypot(roughness_i or 0.0, roughness_j or 0.0)
    slopes = [x for x in (slope_i, slope_j) if x]
    hardness = [x for x in (hardness_i, hardness_j) if x]
    if sigma <= 0.0 or not slopes or not hardness or not k_i or not k_j:
        return 0.0
    k_s = 2.0 * k_i * k_j / (k_i + k_j)
    slope = math.sqrt(sum(x * x for x in slopes))
    return 1.25 * k_s * slope / sigma / min(hardness) ** 0.95


def rough_contact_conductance_reference(k_i, k_j, radius_correction, r_eff, normal_overlap,
                                        youngs_sim, micro) -> float:
    """numpy twin of :func:`rough_contact_conductance`, for tests."""
    radius = radius_correction * math.sqrt(r_eff * normal_overlap)
    smooth = 4.0 * k_i * k_j / (k_i + k_j) * radius
    if micro <= 0.0:
        return smooth
    force = 4.0 / 3.0 * youngs_sim * math.sqrt(r_eff) * normal_overlap ** 1.5
    area = math.pi * radius * radius
    return 1.0 / (1.0 / smooth + 1.0 / (micro * (force / area) ** 0.95 * area))


# --- collisions: the heat that penetrates the two bodies during a short contact ---------------
#
# Sun & Chen (1988): a collision of Hertz duration t_c and largest contact radius a_max passes
#
#     Q = 0.87 (T_j - T_i) pi a_max^2 t_c^(1/2) / ((rho c k)_i^(-1/2) + (rho c k)_j^(-1/2))
#
# (transient conduction into two semi-infinite bodies through the growing spot: valid while the
# contact's Fourier number Fo = kappa t_c / a^2 is small). Zhou, Yu & Zulli (2010) spread it over
# the steps of the contact as the flux  q = c' (T_j - T_i) pi a(t)^2 t_c^(-1/2) / (...).  With
# c' = 0.87 that flux integrates over a Hertz collision to only 0.625 of Sun & Chen's Q (the mean
# of a^2 = R* d over an elastic Hertz impact is B(4/5,1/2)/B(2/5,1/2) = 0.6249 of a_max^2), so we
# take c' = 0.87 / 0.6249 = 1.392: one elastic collision conducts Sun & Chen's Q exactly, and the
# flux follows the contact's real a(t) (a damped collision conducts a little less).
#
# A softened modulus E*_sim < E*_real lengthens the contact (t_c ~ E*^-2/5) and widens the spot
# (a ~ E*^-1/5 at a given impact speed): the flux uses the real radius a = (E*_sim/E*_real)^(1/5)
# sqrt(R* d) and the real t_c, scaled by t_c,real / t_c,sim so that the longer simulated contact
# passes the heat of the real collision (Zhou et al.'s correction, here from the Hertz scalings).
# The steady spot law, in the same real terms, is the floor of the transient one (its long-time
# limit): while the contact is a collision it conducts the larger of the two. A softened
# modulus makes the simulated spot law itself pass too much over a collision (a wider spot for a
# longer time: x (E*_real/E*_sim)^(4/15) with the "static" radius correction), and during the
# collision this real-terms heat replaces it (smooth spots: the collision law assumes intimate
# contact, the asperities' resistance of rough materials is not applied to it).
SUN_CHEN = 0.87
HERTZ_MEAN_SQUARE_RADIUS = 0.6249        # mean of a^2/a_max^2 over an elastic Hertz collision
COLLISION_COEFFICIENT = SUN_CHEN / HERTZ_MEAN_SQUARE_RADIUS
HERTZ_TIME = 2.87                         # t_c = 2.87 (m*^2 / (R* E*^2 v))^(1/5)
SLOWEST_IMPACT = 1e-6                     # m/s: a contact that forms at rest counts as this slow


@ti.func
def hertz_contact_time(m_eff, r_eff, youngs, impact_speed):
    """t_c s of an elastic Hertz impact at ``impact_speed`` m/s (m* kg, R* m, E* Pa)."""
    return HERTZ_TIME * (m_eff * m_eff / (r_eff * youngs * youngs * impact_speed)) ** 0.2


@ti.func
def collision_conductance(collision_factor, conductivity_factor, spot_scale, r_eff,
                          normal_overlap, t_sim):
    """What the real collision passes at this phase of it, W/K: the larger of Sun & Chen's flux
    and the spot law 2 k_s a, both with the real spot radius and spread over the simulated
    contact's Hertz duration ``t_sim`` s instead of the real one. ``collision_factor`` = c' pi /
    ((rho c k)_i^-1/2 + (rho c k)_j^-1/2) (W s^1/2/(m^2 K)), ``conductivity_factor`` = 2 k_s
    (W/(m K)), ``spot_scale`` = (E*_sim/E*_real)^1/5, R* m, d m.

    At a given impact speed a ~ E*^-1/5 and t_c ~ E*^-2/5: the real radius is spot_scale
    sqrt(R* d), the real duration t_real = spot_scale^2 t_sim."""
    radius = spot_scale * ti.sqrt(r_eff * normal_overlap)
    stretch = spot_scale * spot_scale                      # t_real / t_sim
    # q_real = c' pi a^2 t_real^-1/2 / (...) and 2 k_s a, passed over t_sim instead of t_real
    penetration = collision_factor * radius * radius * spot_scale / ti.sqrt(t_sim)
    spot = conductivity_factor * radius * stretch
    return ti.max(penetration, spot)


def collision_factor(density_i, heat_capacity_i, k_i, density_j, heat_capacity_j, k_j) -> float:
    """c' pi / ((rho c k)_i^-1/2 + (rho c k)_j^-1/2), W s^1/2/(m^2 K), of a pair of materials
    (0 where a property is missing)."""
    if not (density_i and heat_capacity_i and k_i and density_j and heat_capacity_j and k_j):
        return 0.0
    return COLLISION_COEFFICIENT * math.pi / ((density_i * heat_capacity_i * k_i) ** -0.5
                                              + (density_j * heat_capacity_j * k_j) ** -0.5)


def sun_chen_heat(delta_t, a_max, t_c, density_i, heat_capacity_i, k_i, density_j,
                  heat_capacity_j, k_j) -> float:
    """Sun & Chen's heat of one collision, J (for tests and reports)."""
    return (SUN_CHEN * delta_t * math.pi * a_max ** 2 * math.sqrt(t_c)
            / ((density_i * heat_capacity_i * k_i) ** -0.5
               + (density_j * heat_capacity_j * k_j) ** -0.5))


# ------------------------------------------------------------------ host-side tables
CONTACT_RADIUS_EXPONENTS = {"static": 1.0 / 3.0, "collision": 1.0 / 5.0, "none": 0.0}


def conduction_tables(scene, names: list[str]):
    """(conductance factor 4 k_i k_j / (k_i + k_j) W/(m K), contact radius correction
    (E*_sim / E*_real)^x) per material pair; zero where a conductivity is missing. Host
    side (numpy), for the conduction effect's ``table_values``."""
    m = len(names)
    factor = np.zeros((m, m))
    correction = np.ones((m, m))
    exponent = CONTACT_RADIUS_EXPONENTS[scene.settings.get("thermal").contact_radius_correction]
    for a in range(m):
        for b in range(m):
            ma, mb = scene.materials[names[a]], scene.materials[names[b]]
            ka, kb = ma.thermal_conductivity, mb.thermal_conductivity
            if ka and kb:
                factor[a, b] = 4.0 * ka * kb / (ka + kb)
            real_a = Material(ma.name, ma.density, ma.real_youngs_modulus or ma.youngs_modulus,
                              ma.poisson_ratio)
            real_b = Material(mb.name, mb.density, mb.real_youngs_modulus or mb.youngs_modulus,
                              mb.poisson_ratio)
            correction[a, b] = (effective_youngs_modulus(ma, mb)
                                / effective_youngs_modulus(real_a, real_b)) ** exponent
    return factor, correction
