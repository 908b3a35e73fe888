"""Conduction through the contact area (PHYSICS.md; Batchelor & O'Brien 1977, as in EDEM).

    Q = h_c (T_j - T_i),   h_c = 4 k_i k_j / (k_i + k_j) a,   a = (3 F_n R* / (4 E*))^(1/3)

With the Hertz force F_n = 4/3 E* sqrt(R*) d^(3/2), the contact radius is a = sqrt(R* d). A
softened modulus inflates a; when a material gives its real modulus the radius is scaled by
(E*_sim / E*_real)^x, x = 1/3 for enduring (force-controlled) contacts - the default, right
for the slow dense beds of coolers and dryers - or 1/5 for collisions (Morris et al. 2016).
LIGGGHTS instead uses sqrt(A) of the intersection area (1.77x EDEM's h_c); we follow EDEM.
"""
import taichi as ti


@ti.func
def contact_conductance(conductivity_factor, radius_correction, r_eff, normal_overlap):
    """h_c, W/K: ``conductivity_factor`` = 4 k_i k_j/(k_i + k_j) W/(m K), ``radius_correction``
    the softened-modulus factor, ``r_eff`` R* m, ``normal_overlap`` d m."""
    return conductivity_factor * radius_correction * ti.sqrt(r_eff * normal_overlap)
