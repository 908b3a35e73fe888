"""Conduction through the gas gap near a contact (PHYSICS.md "Gas-gap conduction"): the models.

Isothermal-surface fluid-lens model (Rong & Horio 1999 as extended by Musser 2011 for two
spheres; Morris, Pannala, Ma & Hrenya 2015 for a sphere and a plane): the gas conducts along
lines parallel to the line of centres, across the local gap between the two surfaces, within a
lens of radius R (1 + lens) around the particle (the larger one of a pair),

    G = k_g Int_{r_in}^{r_out} 2 pi r dr / max(S, gap(r))                               [W/K]

    sphere-plane:  gap(r) = h - sqrt(R^2 - r^2),                h the centre-plane distance
    sphere-sphere: gap(r) = d - sqrt(Ri^2 - r^2) - sqrt(Rj^2 - r^2), d the centre distance

r_in is the contact radius when the surfaces overlap (the spot itself conducts through the
solid, thermal/conduction.py) and 0 otherwise; r_out where the lens meets the other surface
(at most the smaller radius); S the minimum gap (surface roughness, the gas's mean free path).
The surfaces are taken isothermal: an upper bound where the solid's own resistance matters
(ash: k = 0.3 W/(m K), Biot ~0.5).

Sphere-plane has a closed form: with u = sqrt(R^2 - r^2), 2 pi r dr = -2 pi u du and

    Int 2 pi u du / (h - u) = 2 pi [u_out - u_S + h ln((h - u_out) / (h - u_S))]

over the part where the gap exceeds S (u_S = min(R, h - S)), plus pi (r_S^2 - r_in^2) / S
where it is clamped to S. Sphere-sphere is integrated numerically: in w = r^2 the gap is nearly
linear, g(w) ~ S + g'(w_S) (w - w_S), so with q = ln of that line the integrand is smooth
(the ratio of the line to the true gap) and NODES-point Gauss-Legendre reaches 1e-4 of the
integral for the gaps and overlaps of a DEM contact (tests/verification/test_gas_gap.py).
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from taichi_dem.setup.memo import disk_cached

NODES = 12
_X, _W = np.polynomial.legendre.leggauss(NODES)
GAUSS_X = tuple(float(x) for x in _X)
GAUSS_W = tuple(float(w) for w in _W)


@ti.func
def plane_gap_integral(radius, distance, lens, min_gap):
    """Int 2 pi r dr / max(S, gap) for a sphere of ``radius`` (m) whose centre is ``distance``
    (m) from a plane, the fluid lens ``lens`` radii thick, the minimum gap ``min_gap`` (m).
    Returns m (multiply by the gas conductivity for W/K); 0 beyond the lens."""
    r2 = radius * radius
    lens_radius = radius * (1.0 + lens)
    result = 0.0 * radius
    if distance < lens_radius:
        out2 = ti.min(lens_radius * lens_radius - distance * distance, r2)
        in2 = ti.max(r2 - distance * distance, 0.0)
        u_gap = ti.max(ti.min(radius, distance - min_gap), 0.0)
        gap2 = r2 - u_gap * u_gap                    # r^2 where the gap reaches min_gap
        if out2 <= gap2:
            result = math.pi * ti.max(out2 - in2, 0.0) / min_gap
        else:
            u_out = ti.sqrt(r2 - out2)
            result = (math.pi * ti.max(gap2 - in2, 0.0) / min_gap
                      + 2.0 * math.pi * (u_out - u_gap
                                         + distance * ti.log((distance - u_out) / (distance - u_gap))))
    return result


@ti.func
def _pair_gap(w, distance, ri2, rj2):
    return distance - ti.sqrt(ri2 - w) - ti.sqrt(rj2 - w)


@ti.func
def _pair_lens(radius_i, radius_j, distance, lens):
    """The fluid lens between two spheres ``distance`` (m) apart: (larger radius, smaller
    radius, their squares, w = r^2 where the surfaces overlap (0 apart), w where the lens of
    the larger sphere meets the smaller one, whether it reaches it at all)."""
    big = ti.max(radius_i, radius_j)
    small = ti.min(radius_i, radius_j)
    ri2 = big * big
    rj2 = small * small
    lens_radius = big * (1.0 + lens)
    # where the lens sphere (about the larger centre) meets the smaller sphere: law of cosines;
    # a smaller sphere wholly inside the lens (a large size ratio) faces it with its whole disk
    # (MFiX's des_thermo_cond counts nothing there)
    cos_out = (lens_radius * lens_radius - rj2 + distance * distance) / (2.0 * lens_radius * distance)
    engulfed = distance + small <= lens_radius
    reaches = cos_out < 1.0 or engulfed
    out2 = rj2
    if not engulfed:
        out2 = ti.min(lens_radius * lens_radius * ti.max(1.0 - cos_out * cos_out, 0.0), rj2)
    in2 = 0.0 * distance
    if distance < big + small:
        cos_in = (ri2 - rj2 + distance * distance) / (2.0 * big * distance)
        in2 = ri2 * ti.max(1.0 - cos_in * cos_in, 0.0)
    return big, small, ri2, rj2, in2, out2, reaches


@ti.func
def pair_gap_integral(radius_i, radius_j, distance, lens, min_gap):
    """Int 2 pi r dr / max(S, gap) between two spheres of radii ``radius_i``, ``radius_j`` (m)
    whose centres are ``distance`` (m) apart, in the fluid lens (``lens`` radii of the larger
    sphere) with the minimum gap ``min_gap`` (m). Returns m; 0 when the lens does not reach
    the smaller sphere."""
    big, small, ri2, rj2, in2, out2, reaches = _pair_lens(radius_i, radius_j, distance, lens)
    result = 0.0 * distance
    if reaches:
        # w_gap: r^2 where the gap reaches min_gap (the gap grows with r); Newton from the
        # parabolic estimate, clamped to [in2, out2]
        r_eff = big * small / (big + small)
        w_gap = ti.max(2.0 * r_eff * (min_gap - (distance - big - small)), in2)
        for _ in range(8):
            g = _pair_gap(w_gap, distance, ri2, rj2) - min_gap
            slope = 0.5 / ti.sqrt(ri2 - w_gap) + 0.5 / ti.sqrt(rj2 - w_gap)
            w_gap = ti.min(ti.max(w_gap - g / slope, in2), out2)
        if _pair_gap(in2, distance, ri2, rj2) >= min_gap:
            w_gap = in2                              # nowhere closer than min_gap
        result = math.pi * ti.max(w_gap - in2, 0.0) / min_gap
        if out2 > w_gap:
            # Int_{w_gap}^{out2} pi dw / g(w) with q = ln(line(w)), line = S + slope (w - w_gap):
            # dw = line dq / slope, so the integrand pi line / (slope g) is smooth in q
            slope = 0.5 / ti.sqrt(ri2 - w_gap) + 0.5 / ti.sqrt(rj2 - w_gap)
            base = ti.max(_pair_gap(w_gap, distance, ri2, rj2), min_gap)
            q0 = ti.log(base)
            q1 = ti.log(base + slope * (out2 - w_gap))
            half = 0.5 * (q1 - q0)
            total = 0.0 * distance
            for k in ti.static(range(NODES)):
                q = q0 + half * (ti.static(GAUSS_X[k]) + 1.0)
                line = ti.exp(q)
                w = ti.min(w_gap + (line - base) / slope, out2)
                total += ti.static(GAUSS_W[k]) * line / ti.max(_pair_gap(w, distance, ri2, rj2), min_gap)
            result += math.pi * half * total / slope
    return result


# ------------------------------------------------- with the solid's own resistance
# Cheng, Yu & Zulli (1999) and Zhou, Yu & Zulli (2009) add the particle's resistance in series
# with the gas along each line parallel to the line of centres: from the particle's centre
# plane (isothermal, the particle's temperature) through the solid to its surface, then across
# the gap. Per unit area the line's resistance is u_i/k_si + gap/k_g + u_j/k_sj with
# u = sqrt(R^2 - r^2) the solid path, so
#
#     G = k_g Int 2 pi r dr / (g_i u_i + g_j u_j + max(S, gap)),   g = k_g / k_s
#
# (a wall: g_w = 0, the wall isothermal). For k_s >> k_g (steel/air, g ~ 6e-4) it tends to the
# isothermal-surface model; for glass (g ~ 0.026) or ash (g ~ 0.09) the solid limits the
# near-contact gas conduction, where the gap is narrower than g 2R. The integrand is bounded
# (by pi / (g 2R) at contact) and nearly a straight line's reciprocal in w = r^2, integrated
# with the same log-line substitution.
NODES_SOLID = 16
_XS, _WS = np.polynomial.legendre.leggauss(NODES_SOLID)
GAUSS_X_SOLID = tuple(float(x) for x in _XS)
GAUSS_W_SOLID = tuple(float(w) for w in _WS)


@ti.func
def _solid_denominator(w, distance, ri2, rj2, gi, gj, min_gap, ci, cj):
    """g_i p_i + g_j p_j + max(gap, S) at w = r^2 (a plane: rj2 = 0, gj = 0), m, with the
    solid paths p = u - c r (c = 0: from the centre plane; c > 0: from the cone of the
    "voronoi" model, never negative)."""
    ui = ti.sqrt(ti.max(ri2 - w, 0.0))
    uj = ti.sqrt(ti.max(rj2 - w, 0.0))
    r = ti.sqrt(ti.max(w, 0.0))
    return (gi * ti.max(ui - ci * r, 0.0) + gj * ti.max(uj - cj * r, 0.0)
            + ti.max(distance - ui - uj, min_gap))


@ti.func
def _solid_integral(w0, w1, distance, ri2, rj2, gi, gj, min_gap, ci, cj):
    """Int_{w0}^{w1} pi dw / denominator(w) for the positive, nearly linear denominator:
    Gauss-Legendre in q = ln(line), line the chord of the denominator through its ends."""
    d0 = _solid_denominator(w0, distance, ri2, rj2, gi, gj, min_gap, ci, cj)
    d1 = _solid_denominator(w1, distance, ri2, rj2, gi, gj, min_gap, ci, cj)
    result = 0.0 * w0
    if w1 > w0:
        slope = (d1 - d0) / (w1 - w0)
        if ti.abs(d1 - d0) < 1e-6 * d0:
            # (nearly) constant: the midpoint rule is exact enough
            result = math.pi * (w1 - w0) / _solid_denominator(0.5 * (w0 + w1), distance, ri2,
                                                              rj2, gi, gj, min_gap, ci, cj)
        else:
            q0 = ti.log(d0)
            half = 0.5 * (ti.log(d1) - q0)
            total = 0.0 * w0
            for k in ti.static(range(NODES_SOLID)):
                line = ti.exp(q0 + half * (ti.static(GAUSS_X_SOLID[k]) + 1.0))
                w = ti.min(ti.max(w0 + (line - d0) / slope, w0), w1)
                total += ti.static(GAUSS_W_SOLID[k]) * line / _solid_denominator(
                    w, distance, ri2, rj2, gi, gj, min_gap, ci, cj)
            result = math.pi * half * total / slope
    return result


@ti.func
def plane_solid_gap_integral(radius, distance, lens, min_gap, gas_over_solid):
    """As ``plane_gap_integral`` with the particle's own resistance in series (``gas_over_solid``
    = k_g / k_s of the particle; the wall isothermal). Returns m (times k_g: W/K)."""
    r2 = radius * radius
    lens_radius = radius * (1.0 + lens)
    result = 0.0 * radius
    if distance < lens_radius:
        out2 = ti.min(lens_radius * lens_radius - distance * distance, r2)
        in2 = ti.max(r2 - distance * distance, 0.0)
        result = _solid_integral(in2, out2, distance, r2, 0.0 * r2, gas_over_solid, 0.0 * r2,
                                 min_gap, 0.0 * r2, 0.0 * r2)
    return result


@ti.func
def pair_solid_gap_integral(radius_i, radius_j, distance, lens, min_gap, gas_over_solid_i,
                            gas_over_solid_j):
    """As ``pair_gap_integral`` with each particle's own resistance in series
    (``gas_over_solid_*`` = k_g / k_s of particle i, j). Returns m (times k_g: W/K)."""
    g_big, g_small = gas_over_solid_i, gas_over_solid_j
    if radius_j > radius_i:
        g_big, g_small = gas_over_solid_j, gas_over_solid_i
    big, small, ri2, rj2, in2, out2, reaches = _pair_lens(radius_i, radius_j, distance, lens)
    result = 0.0 * distance
    if reaches:
        result = _solid_integral(in2, out2, distance, ri2, rj2, g_big, g_small, min_gap,
                                 0.0 * ri2, 0.0 * ri2)
    return result


# ------------------------------------------------- Voronoi cones (Cheng, Yu & Zulli 1999)
# Cheng, Yu & Zulli (1999, Chem. Eng. Sci. 54:4199) confine the heat between two neighbours to
# the double cone whose apexes are the particle centres and whose base is their shared Voronoi
# face, and take the cone surfaces (not the centre planes) as each particle's isotherm: along a
# line parallel to the line of centres at radius r the solid path runs from the cone to the
# sphere's surface, p = u - r D / r_ij, then the gas gap, then the partner's path:
#
#     G = k_g Int_{r_in}^{r_sf} 2 pi r dr / (g_i p_i + g_j p_j + max(S, gap)),   g = k_g / k_s
#
# D the distance from the centre to the face (the radical plane, (R_i^2 - R_j^2 + d^2) / (2 d)),
# r_ij the face's radius from the packing's porosity e (Yang, Zou & Yu 2000 for random
# packings: r_ij = 0.56 R (1 - e)^(-1/3)), r_sf = R r_ij / sqrt(r_ij^2 + D^2) where the cone
# leaves the (smaller) sphere; the other particle's cone is taken through the same circle
# (p = 0 there for both: c = sqrt(R^2 - r_sf^2) / r_sf), as Gan, Zhou & Yu (2016) do for unequal
# spheres. A wall is the mirror plane of an equal pair (D = the centre's distance, g_w = 0). The
# solid paths are shorter than the centre-plane ones ("solid_resistance") away from the axis,
# so the conductance lies between that model's and the isothermal one's.
VORONOI_FACE = 0.56


def voronoi_face_radius(radius: float, porosity: float) -> float:
    """r_ij (m) of a random packing of spheres of ``radius`` (m) at ``porosity`` (1)."""
    return VORONOI_FACE * radius * (1.0 - porosity) ** (-1.0 / 3.0)


@ti.func
def _voronoi_cone(radius_small, radius_big, distance, porosity):
    """(r_sf^2, cone slope of the smaller sphere, of the larger) of a pair (m^2, 1, 1)."""
    face = VORONOI_FACE * 0.5 * (radius_small + radius_big) * (1.0 - porosity) ** (-1.0 / 3.0)
    d_small = (radius_small * radius_small - radius_big * radius_big + distance * distance) / (
        2.0 * distance)
    sf2 = radius_small * radius_small * face * face / (face * face + d_small * d_small)
    sf = ti.sqrt(sf2)
    return (sf2, ti.sqrt(ti.max(radius_small * radius_small - sf2, 0.0)) / sf,
            ti.sqrt(ti.max(radius_big * radius_big - sf2, 0.0)) / sf)


@ti.func
def pair_voronoi_gap_integral(radius_i, radius_j, distance, lens, min_gap, gas_over_solid_i,
                              gas_over_solid_j, porosity):
    """The Voronoi-cone conductance integral of two spheres (m; times k_g: W/K); 0 beyond
    ``lens`` radii of the larger sphere (the neighbour list's reach)."""
    return _pair_voronoi(radius_i, radius_j, distance, distance, lens, min_gap,
                         gas_over_solid_i, gas_over_solid_j, porosity)


@ti.func
def pair_voronoi_widened_gap_integral(radius_i, radius_j, distance, lens, offset,
                                      gas_over_solid_i, gas_over_solid_j, porosity):
    """As :func:`pair_voronoi_gap_integral` with every gap widened by ``offset`` (m: max(gap,
    0) + l + delta, the "schlunder" law) rather than clamped to a minimum gap."""
    return _pair_voronoi(radius_i, radius_j, distance, distance + offset, lens, offset,
                         gas_over_solid_i, gas_over_solid_j, porosity)


@ti.func
def _pair_voronoi(radius_i, radius_j, distance, gap_distance, lens, min_gap, gas_over_solid_i,
                  gas_over_solid_j, porosity):
    """The Voronoi-cone integral; the gap term max(gap_distance - u_i - u_j, min_gap)."""
    g_big, g_small = gas_over_solid_i, gas_over_solid_j
    if radius_j > radius_i:
        g_big, g_small = gas_over_solid_j, gas_over_solid_i
    big = ti.max(radius_i, radius_j)
    small = ti.min(radius_i, radius_j)
    result = 0.0 * distance
    if distance < big + small + lens * big:
        sf2, c_small, c_big = _voronoi_cone(small, big, distance, porosity)
        in2 = 0.0 * distance
        if distance < big + small:
            cos_in = (big * big - small * small + distance * distance) / (2.0 * big * distance)
            in2 = big * big * ti.max(1.0 - cos_in * cos_in, 0.0)
        result = _solid_integral(in2, sf2, gap_distance, big * big, small * small, g_big,
                                 g_small, min_gap, c_big, c_small)
    return result


@ti.func
def plane_voronoi_gap_integral(radius, distance, lens, min_gap, gas_over_solid, porosity):
    """The Voronoi-cone integral of a sphere and a wall (the mirror plane of an equal pair),
    m; 0 beyond the lens."""
    result = 0.0 * radius
    if distance < radius * (1.0 + lens):
        face = VORONOI_FACE * radius * (1.0 - porosity) ** (-1.0 / 3.0)
        sf2 = radius * radius * face * face / (face * face + distance * distance)
        in2 = ti.max(radius * radius - distance * distance, 0.0)
        result = _solid_integral(in2, sf2, distance, radius * radius, 0.0 * radius,
                                 gas_over_solid, 0.0 * radius, min_gap, distance / face,
                                 0.0 * radius)
    return result


def pair_voronoi_gap_integral_reference(radius_i, radius_j, distance, lens, min_gap,
                                        gas_over_solid_i, gas_over_solid_j, porosity,
                                        panels=4000, widen=False):
    """The Voronoi-cone pair integral by brute-force quadrature in r (m); for tests, tables.
    ``widen``: gaps widened by ``min_gap`` rather than clamped to it."""
    if radius_j > radius_i:
        radius_i, radius_j = radius_j, radius_i
        gas_over_solid_i, gas_over_solid_j = gas_over_solid_j, gas_over_solid_i
    big, small = radius_i, radius_j
    if distance >= big + small + lens * big:
        return 0.0
    face = voronoi_face_radius(0.5 * (big + small), porosity)
    d_small = (small ** 2 - big ** 2 + distance ** 2) / (2 * distance)
    r_sf = small * face / math.sqrt(face ** 2 + d_small ** 2)
    c_small = math.sqrt(max(small ** 2 - r_sf ** 2, 0.0)) / r_sf
    c_big = math.sqrt(max(big ** 2 - r_sf ** 2, 0.0)) / r_sf
    r_in = _overlap_radius(big, small, distance)

    def denominator(r):
        ui = np.sqrt(np.maximum(big ** 2 - r ** 2, 0.0))
        uj = np.sqrt(np.maximum(small ** 2 - r ** 2, 0.0))
        return (gas_over_solid_i * np.maximum(ui - c_big * r, 0.0)
                + gas_over_solid_j * np.maximum(uj - c_small * r, 0.0)
                + np.maximum(distance + (min_gap if widen else 0.0) - ui - uj, min_gap))
    return _integrate(denominator, r_in, r_sf, panels)


def plane_voronoi_gap_integral_reference(radius, distance, lens, min_gap, gas_over_solid,
                                         porosity, panels=4000):
    """The Voronoi-cone sphere-wall integral by brute-force quadrature (m)."""
    if distance >= radius * (1.0 + lens):
        return 0.0
    face = voronoi_face_radius(radius, porosity)
    r_sf = radius * face / math.sqrt(face ** 2 + distance ** 2)
    r_in = math.sqrt(max(radius ** 2 - distance ** 2, 0.0))

    def denominator(r):
        u = np.sqrt(np.maximum(radius ** 2 - r ** 2, 0.0))
        return (gas_over_solid * np.maximum(u - distance / face * r, 0.0)
                + np.maximum(distance - u, min_gap))
    return _integrate(denominator, r_in, r_sf, panels)


# The "schlunder" model's pair law is the Voronoi-cone one with every gap widened by l +
# delta_i + delta_j (max(gap, 0) + l + delta, the Smoluchowski effect) rather than clamped
# to a minimum gap; its wall law is thermal/first_layer.py's.


# ---------------------------------------------------------------- references (numpy, slow)
def plane_gap_integral_reference(radius, distance, lens, min_gap, panels=4000):
    """The sphere-plane integral by brute-force quadrature in r (m); for the tests."""
    lens_radius = radius * (1.0 + lens)
    if distance >= lens_radius:
        return 0.0
    r_out = math.sqrt(min(lens_radius ** 2 - distance ** 2, radius ** 2))
    r_in = math.sqrt(max(radius ** 2 - distance ** 2, 0.0))

    def gap(r):
        return np.maximum(distance - np.sqrt(np.maximum(radius ** 2 - r ** 2, 0.0)), min_gap)
    return _integrate(gap, r_in, r_out, panels)


def pair_gap_integral_reference(radius_i, radius_j, distance, lens, min_gap, panels=4000):
    """The sphere-sphere integral by brute-force quadrature in r (m); for the tests."""
    big, small = max(radius_i, radius_j), min(radius_i, radius_j)
    lens_radius = big * (1.0 + lens)
    cos_out = (lens_radius ** 2 - small ** 2 + distance ** 2) / (2 * lens_radius * distance)
    if distance + small <= lens_radius:
        r_out = small                          # the smaller sphere wholly inside the lens
    elif cos_out >= 1.0:
        return 0.0
    else:
        r_out = min(lens_radius * math.sqrt(1 - cos_out ** 2), small)
    r_in = _overlap_radius(big, small, distance)

    def gap(r):
        return np.maximum(distance - np.sqrt(np.maximum(big ** 2 - r ** 2, 0.0))
                          - np.sqrt(np.maximum(small ** 2 - r ** 2, 0.0)), min_gap)
    return _integrate(gap, r_in, r_out, panels)


def _overlap_radius(big, small, distance):
    """Radius (m) of the circle where two overlapping spheres' surfaces meet; 0 apart."""
    if distance >= big + small:
        return 0.0
    cos_in = (big ** 2 - small ** 2 + distance ** 2) / (2 * big * distance)
    return big * math.sqrt(max(1 - cos_in ** 2, 0.0))


def _integrate(gap, a, b, panels):
    """Int_a^b 2 pi r / gap(r) dr: Gauss-Legendre on panels graded towards a (where the gap is
    smallest and the integrand peaks)."""
    if b <= a:
        return 0.0
    x, w = np.polynomial.legendre.leggauss(8)
    edges = a + (b - a) * np.linspace(0.0, 1.0, panels + 1) ** 3
    lo, hi = edges[:-1, None], edges[1:, None]
    r = 0.5 * (hi - lo) * x[None, :] + 0.5 * (hi + lo)
    f = 2.0 * math.pi * r / gap(r)
    return float(np.sum(0.5 * (hi - lo) * w[None, :] * f))


def plane_solid_gap_integral_reference(radius, distance, lens, min_gap, gas_over_solid,
                                       panels=4000):
    """The sphere-plane integral with the solid's resistance, brute force (m); for tests."""
    lens_radius = radius * (1.0 + lens)
    if distance >= lens_radius:
        return 0.0
    r_out = math.sqrt(min(lens_radius ** 2 - distance ** 2, radius ** 2))
    r_in = math.sqrt(max(radius ** 2 - distance ** 2, 0.0))

    def gap(r):
        u = np.sqrt(np.maximum(radius ** 2 - r ** 2, 0.0))
        return gas_over_solid * u + np.maximum(distance - u, min_gap)
    return _integrate(gap, r_in, r_out, panels)


def pair_solid_gap_integral_reference(radius_i, radius_j, distance, lens, min_gap,
                                      gas_over_solid_i, gas_over_solid_j, panels=4000):
    """The sphere-sphere integral with the solids' resistance, brute force (m); for tests."""
    if radius_j > radius_i:
        radius_i, radius_j = radius_j, radius_i
        gas_over_solid_i, gas_over_solid_j = gas_over_solid_j, gas_over_solid_i
    big, small = radius_i, radius_j
    lens_radius = big * (1.0 + lens)
    cos_out = (lens_radius ** 2 - small ** 2 + distance ** 2) / (2 * lens_radius * distance)
    if distance + small <= lens_radius:
        r_out = small
    elif cos_out >= 1.0:
        return 0.0
    else:
        r_out = min(lens_radius * math.sqrt(1 - cos_out ** 2), small)
    r_in = _overlap_radius(big, small, distance)

    def gap(r):
        ui = np.sqrt(np.maximum(big ** 2 - r ** 2, 0.0))
        uj = np.sqrt(np.maximum(small ** 2 - r ** 2, 0.0))
        return gas_over_solid_i * ui + gas_over_solid_j * uj + np.maximum(distance - ui - uj, min_gap)
    return _integrate(gap, r_in, r_out, panels)


# ---------------------------------------------------------------- tables (the step's path)
# In the step the integrals above are looked up, not integrated: for each pair of particle
# kinds (material, radius) in a scene, and each kind against a wall, the integral is tabulated
# once at set-up against the surface separation s (m) - the brute-force references above, in
# f64 - and interpolated linearly. Nodes: uniform in s over overlaps down to TABLE_OVERLAP of
# the smaller radius, uniform in ln(1 + s / S) over the gaps up to the lens (dense where the
# gap is smallest and the integral varies fastest), one node at contact (s = 0) where the
# integral has a kink. Interpolation error: below 1e-4 of the contact value
# (tests/verification/test_gas_gap_table.py). Deeper overlaps fall back to the quadrature;
# a scene whose factories sample radii from a distribution has no finite set of kinds and
# integrates every contact (``species`` None).
TABLE_OVERLAP = 0.1
TABLE_NODES_OVERLAP = 129
TABLE_NODES_GAP = 896
TABLE_NODES = TABLE_NODES_OVERLAP + TABLE_NODES_GAP - 1
TABLE_PANELS = 400


def table_range(radius_small, radius_big, lens, min_gap):
    """(s_lo, s_hi, gap nodes per unit ln(1 + s/S)) of a table, m, m, 1."""
    s_lo = -TABLE_OVERLAP * radius_small
    s_hi = lens * radius_big
    return s_lo, s_hi, (TABLE_NODES_GAP - 1) / math.log1p(s_hi / min_gap)


def table_separations(radius_small, radius_big, lens, min_gap) -> np.ndarray:
    """The TABLE_NODES separations s (m) a table holds the integral at."""
    s_lo, s_hi, per_log = table_range(radius_small, radius_big, lens, min_gap)
    overlap = np.linspace(s_lo, 0.0, TABLE_NODES_OVERLAP)
    gap = min_gap * np.expm1(np.arange(1, TABLE_NODES_GAP) / per_log)
    gap[-1] = s_hi
    return np.concatenate([overlap, gap])


@disk_cached
def pair_table(radius_i, radius_j, lens, min_gap, model, gas_over_solid_i=0.0,
               gas_over_solid_j=0.0, porosity=0.4) -> np.ndarray:
    """The pair integral (m) at ``table_separations`` for two kinds of sphere; ``model``
    "isothermal", "solid_resistance" or "voronoi" (with k_g / k_s of each; the packing's
    porosity for "voronoi")."""
    small, big = min(radius_i, radius_j), max(radius_i, radius_j)
    s = table_separations(small, big, lens, min_gap)
    if model == "schlunder":
        return np.array([pair_voronoi_gap_integral_reference(
            radius_i, radius_j, radius_i + radius_j + x, lens, min_gap, gas_over_solid_i,
            gas_over_solid_j, porosity, TABLE_PANELS, widen=True) for x in s])
    if model == "voronoi":
        return np.array([pair_voronoi_gap_integral_reference(
            radius_i, radius_j, radius_i + radius_j + x, lens, min_gap, gas_over_solid_i,
            gas_over_solid_j, porosity, TABLE_PANELS) for x in s])
    if model == "solid_resistance":
        return np.array([pair_solid_gap_integral_reference(
            radius_i, radius_j, radius_i + radius_j + x, lens, min_gap, gas_over_solid_i,
            gas_over_solid_j, TABLE_PANELS) for x in s])
    return np.array([pair_gap_integral_reference(radius_i, radius_j, radius_i + radius_j + x,
                                                 lens, min_gap, TABLE_PANELS) for x in s])


def plane_table(radius, lens, min_gap, gas_over_solid, model="solid_resistance",
                porosity=0.4) -> np.ndarray:
    """The sphere-plane integral with the solid's resistance (m) at ``table_separations``
    ("solid_resistance" or "voronoi")."""
    s = table_separations(radius, radius, lens, min_gap)
    if model == "voronoi":
        return np.array([plane_voronoi_gap_integral_reference(
            radius, radius + x, lens, min_gap, gas_over_solid, porosity, TABLE_PANELS)
            for x in s])
    return np.array([plane_solid_gap_integral_reference(radius, radius + x, lens, min_gap,
                                                        gas_over_solid, TABLE_PANELS)
                     for x in s])


@ti.func
def table_position(s, s_lo, s_hi, per_log, min_gap):
    """(index, fraction) of separation ``s`` (m) between two nodes of a table; index -1 below
    the table (deeper overlap: integrate), TABLE_NODES beyond it (no gas conduction)."""
    index = -1
    fraction = 0.0 * s
    if s >= s_hi:
        index = TABLE_NODES
    elif s >= s_lo:
        x = 0.0 * s
        if s < 0.0:
            x = (s - s_lo) / (-s_lo) * (TABLE_NODES_OVERLAP - 1)
        else:
            x = (TABLE_NODES_OVERLAP - 1) + ti.log(1.0 + s / min_gap) * per_log
        index = ti.min(ti.cast(x, ti.i32), TABLE_NODES - 2)
        fraction = ti.min(x - index, 1.0)
    return index, fraction
