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

import taichi as ti


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
