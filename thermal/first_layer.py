"""The "schlunder" wall law: the first layer of particles against a heated wall or body, as
Schlünder measured it, with the particle's own resistance growing as the contact lasts.

1. The gas gap, Schlünder's first layer (Schlünder 1984; VDI Heat Atlas M7). An isothermal
   sphere touching an isothermal wall conducts through the gas over the whole disc it shows
   the wall, every local gap widened by l + delta (l the gas's modified mean free path: the
   temperature jumps at the two surfaces, the Smoluchowski effect, make a gap below ~1 um
   conduct as if it were l wider; delta the surfaces' roughness):

       G_0 = k_g Int_{r_in}^{R} 2 pi r dr / D(r),   D = max(gap(r), 0) + l + delta
           = alpha_WP pi d^2 / 4                                                    [W/K]

   closed form with u = sqrt(R^2 - r^2), H = h + l + delta (h the centre's distance):
   2 pi k_g [u_out - u_in + H ln((H - u_out) / (H - u_in))], u_in = min(h, R), u_out where the
   reach (at least sqrt(2) - 1 radii, so that a touching sphere counts its whole disc) meets
   the sphere.

2. The particle's own resistance as the contact lasts: G_0 holds while the particle's surface
   facing the wall is still at the particle's temperature, at the start of a contact. The wall
   law multiplies G_0 by the ratio G(t) / G(0) that the heat equation inside the sphere gives
   (thermal/particle_transient.py, solved once per material at set-up), read at the particle's
   Fourier number a_s t / R^2, t the thermal time since it came within the reach of a
   heat-exchanging wall or body and stayed there (WallContactAge). A particle that rolls along
   the wall renews the surface it shows the wall, which its age does not see.
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from . import gas_gap

REACH = math.sqrt(2.0) - 1.0


def wall_reach(lens: float) -> float:
    """The wall law's reach (radii): the lens, at least sqrt(2) - 1 (a touching sphere's whole
    disc)."""
    return max(float(lens), REACH)


@ti.func
def widened_gap_integral(radius, distance, reach, offset):
    """G_0 / k_g (m): Int 2 pi r dr / (max(gap, 0) + ``offset``) for a sphere of ``radius``
    (m) whose centre is ``distance`` (m) from a plane, over its disc within ``reach`` radii;
    0 beyond the reach."""
    r2 = radius * radius
    reach_radius = radius * (1.0 + reach)
    result = 0.0 * radius
    if distance < reach_radius:
        out2 = ti.min(reach_radius * reach_radius - distance * distance, r2)
        u_in = ti.min(distance, radius)
        u_out = ti.sqrt(ti.max(r2 - out2, 0.0))
        big_h = distance + offset
        result = 2.0 * math.pi * (u_out - u_in + big_h * ti.log((big_h - u_out) / (big_h - u_in)))
    return result


# ---------------------------------------------------------------- references (numpy, slow)
def widened_gap_integral_reference(radius, distance, reach, offset, panels=4000):
    """G_0 / k_g by brute-force quadrature in r (m); for the tests."""
    reach_radius = radius * (1.0 + reach)
    if distance >= reach_radius:
        return 0.0
    r_out = math.sqrt(min(reach_radius ** 2 - distance ** 2, radius ** 2))
    r_in = math.sqrt(max(radius ** 2 - distance ** 2, 0.0))

    def gap(r):
        return np.maximum(distance - np.sqrt(np.maximum(radius ** 2 - r ** 2, 0.0)), 0.0) + offset
    return gas_gap._integrate(gap, r_in, r_out, panels)


__all__ = ["REACH", "wall_reach", "widened_gap_integral", "widened_gap_integral_reference"]
