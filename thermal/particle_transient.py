"""The particle's own resistance to heat from a wall, resolved once: the heat equation inside one
sphere lying on a heated wall, solved at set-up (plain numpy/scipy, no Taichi), so that the
lumped particle of the DEM takes the heat the resolved one would.

Why: the DEM gives each particle one temperature. A wall law that feeds it through the gas gap
as if its surface stayed at that temperature (Schlünder's alpha_WP, an isothermal sphere) is
right at the first instant of a contact, but the solid behind the gap warms as the contact
lasts, and the heat must then cross the particle to reach the rest of it: for a 2 mm glass bead
about a second (R^2 / a_s ~ 2 s), the time a rolling drum's shell stays under the bed. A lumped
particle fed at alpha_WP takes the heat too easily (the drum's wall coefficient 1.5 x
Schlünder-Mollekopf's); one fed through a steady path to its centre plane too hard (0.6 x).

The problem solved (axisymmetric, in r and theta about the axis through the wall contact):

    rho c dT/dt = div(k grad T)                  inside the sphere, T(t = 0) = 0
    -k dT/dn = h(theta) (T - T_w)                on its surface; T_w = 1
    h = k_g / D,  D = max(gap, 0) + l + delta    where the local gap is within the wall law's
                                                 reach (lines parallel to the axis, as the
                                                 gap law counts them); 0 (adiabatic) elsewhere

by finite volumes on a mesh graded towards the contact point (cells of 0.2 % of R there) and
implicit Euler steps that grow geometrically from 1e-7 of R^2 / a_s. Its output is the
conductance the lumped particle should see,

    G(t) = Q(t) / (T_w - T_mean(t))                                                      [W/K]

Q the heat entering, T_mean the particle's mean temperature. G(0) is the gap law's G_0 (the
surface still at T_mean); it falls as the solid near the contact warms and settles at the
sphere's quasi-steady value (the whole particle warming at one rate). The wall law uses
G(h, t) = G_0(h) G(t) / G_0 (the ratio at contact for every standoff; a particle standing off
conducts less through the gas, so its solid limits it less: the ratio errs low there).
Tables: the ratio against t (thermal seconds since the particle came within reach), once per
kind of particle (material, radius) in a scene, cached.

Checks (tests/verification/test_first_layer.py): a sphere under a uniform h on its whole
surface against the exact series solution (Carslaw & Jaeger 9.4: lambda cot lambda = 1 - Bi),
and G(0) against the closed form of the gap law.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from taichi_dem.setup.memo import disk_cached

RATIO_TIMES = 64          # table nodes, log-spaced in thermal time
FIRST_TIME = 1e-6         # of R^2 / a_s: the table's first node
LAST_TIME = 3.0           # of R^2 / a_s: beyond, the quasi-steady ratio holds


def _graded_edges(total: float, first: float, growth: float, largest: float) -> np.ndarray:
    """Edges from 0 to ``total``: cells from ``first`` growing by ``growth`` up to ``largest``."""
    edges, width = [0.0], first
    while edges[-1] + width < total:
        edges.append(edges[-1] + width)
        width = min(width * growth, largest)
    if total - edges[-1] < 0.3 * width and len(edges) > 1:
        edges[-1] = total
    else:
        edges.append(total)
    return np.array(edges)


@functools.lru_cache(maxsize=8)
def _gauss_legendre(samples: int):
    """Gauss-Legendre nodes and weights on [-1, 1] (numpy computes them by an eigenvalue
    problem: ~1 ms, and a scene's tables call for them hundreds of times)."""
    return np.polynomial.legendre.leggauss(samples)


def _gap_conductance(radius, phi_lo, phi_hi, reach_sin, offset, k_gas, samples=64):
    """k_g Int 2 pi r dr / D over the projected ring of the surface between polar angles
    phi_lo, phi_hi (measured from the contact point) of the hemisphere facing the wall, within
    the reach (W/K): where the projected radius sin(phi) R <= ``reach_sin`` R (the wall law's
    r_out of a touching sphere, first_layer.py)."""
    if phi_lo >= math.pi / 2:
        return 0.0
    phi_hi = min(phi_hi, math.pi / 2)
    x, w = _gauss_legendre(samples)
    phi = 0.5 * (phi_hi - phi_lo) * x + 0.5 * (phi_hi + phi_lo)
    r = radius * np.sin(phi)
    gap = radius * (1.0 - np.cos(phi))
    inside = np.sin(phi) <= reach_sin
    # d(r) = R cos(phi) dphi
    integrand = np.where(inside, 2.0 * math.pi * r * radius * np.cos(phi) / (gap + offset), 0.0)
    return float(k_gas * 0.5 * (phi_hi - phi_lo) * np.sum(w * integrand))


def _sphere_system(radius, k_solid, k_gas, offset, reach_sin, uniform_h=0.0, upto=math.pi):
    """The finite-volume system of the sphere (polar angle phi from the contact point up to
    ``upto``): (conductance matrix with the surface's gap on its diagonal, cell volumes, the
    surface conductance to the wall of each cell, the conductance of each cell of the last
    polar row to the face phi = upto, the gas's own conductance summed over the faces)."""
    from scipy.sparse import coo_matrix, diags
    # mesh: depth from the surface (fine there), polar angle from the contact (fine there)
    depth = _graded_edges(radius, 2e-3 * radius, 1.15, 0.06 * radius)
    r_edges = radius - depth[::-1]
    if uniform_h > 0.0:
        phi_edges = np.linspace(0.0, upto, 25)
    else:
        phi_edges = _graded_edges(upto, 2e-3, 1.15, 0.08)
    nr, nt = len(r_edges) - 1, len(phi_edges) - 1
    rc = 0.5 * (r_edges[:-1] + r_edges[1:])
    pc = 0.5 * (phi_edges[:-1] + phi_edges[1:])
    cos_e = np.cos(phi_edges)
    band = 2.0 * math.pi * (cos_e[:-1] - cos_e[1:])                      # solid angle
    volume = np.outer((r_edges[1:] ** 3 - r_edges[:-1] ** 3) / 3.0, band)  # (nr, nt)

    def index(i, j):
        return i * nt + j

    rows, cols, vals = [], [], []
    diag = np.zeros(nr * nt)

    def link(a, b, g):
        rows.extend((a, b))
        cols.extend((b, a))
        vals.extend((-g, -g))
        diag[a] += g
        diag[b] += g

    for i in range(nr - 1):                    # radial faces at r_edges[i + 1]
        area = r_edges[i + 1] ** 2 * band
        g = k_solid * area / (rc[i + 1] - rc[i])
        for j in range(nt):
            link(index(i, j), index(i + 1, j), g[j])
    for j in range(nt - 1):                    # polar faces at phi_edges[j + 1]
        area = math.pi * math.sin(phi_edges[j + 1]) * (r_edges[1:] ** 2 - r_edges[:-1] ** 2)
        g = k_solid * area / (rc * (pc[j + 1] - pc[j]))
        for i in range(nr):
            link(index(i, j), index(i, j + 1), g[i])
    # the last polar row to the face phi = upto (a fixed temperature there, when it is used)
    end = np.zeros(nr * nt)
    area = math.pi * math.sin(upto) * (r_edges[1:] ** 2 - r_edges[:-1] ** 2)
    for i in range(nr):
        end[index(i, nt - 1)] = k_solid * area[i] / (rc[i] * (upto - pc[-1]))
    # the surface: the gap in series with the outer half cell
    half = radius - rc[-1]
    boundary = np.zeros(nr * nt)
    gas = 0.0
    for j in range(nt):
        area = radius * radius * band[j]
        if uniform_h > 0.0:
            g_gap = uniform_h * area
        else:
            g_gap = _gap_conductance(radius, phi_edges[j], phi_edges[j + 1], reach_sin, offset,
                                     k_gas)
        if g_gap > 0.0:
            gas += g_gap
            g_solid = k_solid * area / half
            boundary[index(nr - 1, j)] = 1.0 / (1.0 / g_gap + 1.0 / g_solid)
    laplacian = (coo_matrix((vals, (rows, cols)), shape=(nr * nt, nr * nt)).tocsc()
                 + diags(diag + boundary).tocsc())
    return laplacian, volume.ravel(), boundary, end, gas


@disk_cached
def half_pair_conductance(radius: float, k_solid: float, k_gas: float, offset: float,
                          reach_sin: float):
    """(G_half, G_gas) (W/K): the steady conductance from a sphere's centre plane to the plane
    midway to a touching neighbour, heat crossing it from one contact to the opposite one (a
    chain: the centre plane is then at the sphere's mean temperature), and the gas's own
    conductance over the same faces (isothermal surfaces). Gaps (to the midplane) widened by
    ``offset`` m, conducting where the projected radius is within ``reach_sin`` R (the Voronoi
    face of the pair law). Their ratio is the particle's share of a pair's resistance."""
    from scipy.sparse import diags
    from scipy.sparse.linalg import spsolve
    laplacian, _, boundary, end, gas = _sphere_system(radius, k_solid, k_gas, offset,
                                                      reach_sin, upto=0.5 * math.pi)
    # the midplane at 1, the centre plane (phi = pi/2, by the chain's antisymmetry) at 0
    temperature = spsolve((laplacian + diags(end)).tocsc(), boundary)
    heat = float(np.sum(boundary * (1.0 - temperature)))
    return heat, gas


@disk_cached
def conductance_ratio(radius: float, k_solid: float, density: float, heat_capacity: float,
                      k_gas: float, offset: float, reach: float, uniform_h: float = 0.0):
    """(times (s), G(t) / G(0)) of a sphere of ``radius`` (m) and the solid's k (W/(m K)),
    rho (kg/m^3), c (J/(kg K)) touching a wall through the gas (k_g W/(m K), gaps widened by
    ``offset`` m, within ``reach`` radii). ``uniform_h`` > 0 instead puts that h (W/(m^2 K))
    on the whole surface (the check against the exact series). Also returns G(0) (W/K)."""
    from scipy.sparse import diags
    from scipy.sparse.linalg import splu
    diffusivity = k_solid / (density * heat_capacity)
    tau = radius * radius / diffusivity
    # a touching sphere's disc within the reach: r_out^2 = ((1 + reach)^2 - 1) R^2, at most R^2
    reach_sin = min(math.sqrt((1.0 + reach) ** 2 - 1.0), 1.0)
    laplacian, volume, boundary, _, _ = _sphere_system(radius, k_solid, k_gas, offset,
                                                       reach_sin, uniform_h)
    capacity = density * heat_capacity * volume
    cap = capacity
    g0 = float(boundary.sum())
    temperature = np.zeros(len(cap))
    times = tau * np.geomspace(FIRST_TIME, LAST_TIME, RATIO_TIMES)
    out = np.empty(RATIO_TIMES)
    t, dt, k = 0.0, 1e-7 * tau, 0
    solve, solved_dt = None, None
    while k < RATIO_TIMES:
        step = min(dt, times[k] - t)
        if solve is None or step != solved_dt:
            solve = splu((laplacian + diags(cap / step)).tocsc()).solve
            solved_dt = step
        temperature = solve(cap / step * temperature + boundary)
        t += step
        if t >= times[k] * (1.0 - 1e-12):
            heat = float(np.sum(boundary * (1.0 - temperature)))
            mean = float(np.sum(cap * temperature) / np.sum(cap))
            out[k] = heat / (1.0 - mean) / g0
            k += 1
        dt = min(dt * 1.25, 0.02 * tau) if step == dt else dt
    return times, out, g0


__all__ = ["conductance_ratio", "half_pair_conductance", "RATIO_TIMES"]
