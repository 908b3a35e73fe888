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

2. The particle's transient resistance. G_0 holds while the particle's surface facing the wall
   is still at the particle's temperature: at the start of a contact. The heat that crosses the
   gap then warms the solid behind it, and that solid's resistance grows as the heated layer
   deepens (for glass, about a second to cross a 2 mm bead: R^2 / a_s ~ 2 s). Along each line
   parallel to the axis (as the series models take the solid's path, Cheng, Yu & Zulli 1999),
   the gap's conductance k_g / D feeds a semi-infinite solid of the particle's effusivity
   e_s = rho_s c_s k_s; its flux after a contact of thermal time t is the exact one of a
   semi-infinite body behind a surface conductance (Carslaw & Jaeger 1959, sec. 2.7),

       q / dT = (k_g / D) erfcx((k_g / D) sqrt(t / e_s))                          [W/(m^2 K)]

   which starts at k_g / D and falls as sqrt(e_s / (pi t)) once the solid limits it. The
   steady path through the solid to the centre plane bounds it from below once the layer has
   crossed the particle: k_g / (D + (k_g / k_s) u). So

       G(t) = k_g Int 2 pi r dr max(erfcx(beta / D) / D, 1 / (D + g u)),
       beta = k_g sqrt(t / e_s),  g = k_g / k_s                                          [W/K]

   G(0) = G_0 (the first-layer check, Schlünder's alpha_WP), G(inf) = the steady series law.
   t is the thermal time since the particle came within the reach of a heat-exchanging wall
   or body and stayed there (WallContactAge). Limits: the solid is taken 1-D along each line
   (no spreading sideways, which would lower the resistance), and a particle that rolls along
   the wall renews the surface it shows the wall, which the particle's age does not see.
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from . import gas_gap
from .coarse_grained import erfcx
from .correlations import erfcx as erfcx_reference

REACH = math.sqrt(2.0) - 1.0
NODES = 24
_X, _W = np.polynomial.legendre.leggauss(NODES)
GAUSS_X = tuple(float(x) for x in _X)
GAUSS_W = tuple(float(w) for w in _W)


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


@ti.func
def _local(w, distance, r2, offset, gas_over_solid, depth):
    """1 / D_eff at w = r^2: max(erfcx(beta / D) / D, 1 / (D + g u)) (1/m)."""
    u = ti.sqrt(ti.max(r2 - w, 0.0))
    d = ti.max(distance - u, 0.0) + offset
    return ti.max(erfcx(depth / d) / d, 1.0 / (d + gas_over_solid * u))


@ti.func
def transient_gap_integral(radius, distance, reach, offset, gas_over_solid, depth):
    """G(t) / k_g (m): the first layer's conductance integral after a contact whose solid
    penetration is ``depth`` = k_g sqrt(t / e_s) (m); ``gas_over_solid`` = k_g / k_s. Gauss-
    Legendre in q = ln D (D nearly linear in w = r^2: the integrand is smooth in q)."""
    r2 = radius * radius
    reach_radius = radius * (1.0 + reach)
    result = 0.0 * radius
    if distance < reach_radius:
        w1 = ti.min(reach_radius * reach_radius - distance * distance, r2)
        w0 = ti.max(r2 - distance * distance, 0.0)
        if w1 > w0:
            d0 = ti.max(distance - ti.sqrt(r2 - w0), 0.0) + offset
            d1 = ti.max(distance - ti.sqrt(ti.max(r2 - w1, 0.0)), 0.0) + offset
            slope = (d1 - d0) / (w1 - w0)
            q0 = ti.log(d0)
            half = 0.5 * (ti.log(d1) - q0)
            total = 0.0 * radius
            for k in ti.static(range(NODES)):
                line = ti.exp(q0 + half * (ti.static(GAUSS_X[k]) + 1.0))
                w = ti.min(ti.max(w0 + (line - d0) / slope, w0), w1)
                total += ti.static(GAUSS_W[k]) * line * _local(w, distance, r2, offset,
                                                               gas_over_solid, depth)
            result = math.pi * half * total / slope
    return result


# ---------------------------------------------------------------- references (numpy, slow)
def widened_gap_integral_reference(radius, distance, reach, offset, panels=4000):
    """G_0 / k_g by brute-force quadrature (m); for the tests."""
    return transient_gap_integral_reference(radius, distance, reach, offset, 0.0, 0.0, panels)


def transient_gap_integral_reference(radius, distance, reach, offset, gas_over_solid, depth,
                                     panels=4000):
    """G(t) / k_g by brute-force quadrature (m); ``depth`` 0: G_0."""
    reach_radius = radius * (1.0 + reach)
    if distance >= reach_radius:
        return 0.0
    r_out = math.sqrt(min(reach_radius ** 2 - distance ** 2, radius ** 2))
    r_in = math.sqrt(max(radius ** 2 - distance ** 2, 0.0))

    def effective_gap(r):
        """D_eff(r) = 1 / max(erfcx(beta / D) / D, 1 / (D + g u)) (m)."""
        u = np.sqrt(np.maximum(radius ** 2 - r ** 2, 0.0))
        d = np.maximum(distance - u, 0.0) + offset
        transient = (np.vectorize(erfcx_reference)(depth / d) / d) if depth > 0.0 else 1.0 / d
        return 1.0 / np.maximum(transient, 1.0 / (d + gas_over_solid * u))
    return gas_gap._integrate(effective_gap, r_in, r_out, panels)


def penetration_depth(k_gas: float, time: float, density: float, heat_capacity: float,
                      k_solid: float) -> float:
    """beta = k_g sqrt(t / (rho_s c_s k_s)) (m) after a contact of ``time`` s (thermal)."""
    return k_gas * math.sqrt(time / (density * heat_capacity * k_solid))


__all__ = ["REACH", "wall_reach", "widened_gap_integral", "transient_gap_integral",
           "widened_gap_integral_reference", "transient_gap_integral_reference",
           "penetration_depth"]
