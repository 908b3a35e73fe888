"""The steady depth-averaged (Savage-Hutter type) model of a chute flow, in plain numpy.

Seed 004 (Cui et al. 2024, eqs. 5-7) solves the shallow-granular-flow equations

    dh/dt + d(h u)/dx = 0
    d(h u)/dt + d(h u^2 + K g cos(zeta) h^2 / 2)/dx = g h (sin(zeta) - tan(delta) cos(zeta))

(x down the slope, h the flow depth normal to the base, u the depth-averaged down-slope
velocity, zeta the inclination, delta the basal friction angle; the paper's eq. 6 writes the
pressure term with K = 1, the earth-pressure coefficient of an isotropic, hydrostatic
depth-averaged stress - Savage & Hutter (1989) derive K from the internal and basal friction
angles; Gray et al. (1999) and Cui & Gray (2013) use K = 1 for chute flows of this kind, and so
does this module by default). Across the chute nothing varies (no obstacle, no side-wall
friction in the model), so the steady state is one-dimensional: the flux q = h u is constant
and

    du/dx = g S u / (u^2 - K g h cos(zeta)),   S = sin(zeta) - tan(delta) cos(zeta),  h = q / u,

integrated from the inlet state (h0, u0) with RK4. Multiplying by u - K g cos(zeta) q / u^2
and integrating gives the exact invariant (a Bernoulli equation with friction)

    u^2 / 2 + K g cos(zeta) h - g S x = u0^2 / 2 + K g cos(zeta) h0,

which the tests use. The right-hand side is singular at the critical Froude number
Fr^2 = u^2 / (K g h cos(zeta)) = 1: a smooth steady solution exists only while the flow stays
on one side of it. A supercritical inflow (seed 004: Fr = 1.33 at the inlet) that accelerates
(S > 0) moves away from it, as does a subcritical one that decelerates; a supercritical flow
braked by delta > zeta, or a subcritical one driven by S < 0, runs into it.
"""
from __future__ import annotations

import math

import numpy as np


def source(inclination_deg: float, friction_deg: float) -> float:
    """S = sin(zeta) - tan(delta) cos(zeta): the net down-slope driving per unit g."""
    z = math.radians(inclination_deg)
    return math.sin(z) - math.tan(math.radians(friction_deg)) * math.cos(z)


def froude(h, u, inclination_deg: float, gravity: float, earth_pressure: float = 1.0):
    """Fr = u / sqrt(K g h cos(zeta)) (dimensionless; h m, u m/s, g m/s^2)."""
    c2 = earth_pressure * gravity * np.asarray(h, float) * math.cos(math.radians(inclination_deg))
    with np.errstate(divide="ignore"):          # K = 0: no wave speed, Fr = inf
        return np.asarray(u, float) / np.sqrt(c2)


def steady_profile(x, h0: float, u0: float, inclination_deg: float, friction_deg: float,
                   gravity: float = 9.81, earth_pressure: float = 1.0, substeps: int = 200) -> dict:
    """The steady depth and velocity at the down-slope positions ``x`` (m, increasing, from
    the inlet at x[0]), for the inlet depth ``h0`` (m) and velocity ``u0`` (m/s).

    Returns ``{"x", "h" (m), "u" (m/s), "q" (m^2/s, = h0 u0), "froude"}`` as arrays. RK4 with
    ``substeps`` steps between successive x (the solution is smooth: 200 reach round-off on a
    chute's 150 mm). Raises ValueError if the flow would cross Fr = 1, where no smooth steady
    solution exists (a jump forms)."""
    x = np.asarray(x, float)
    if np.any(np.diff(x) <= 0.0):
        raise ValueError("x must increase")
    if not (h0 > 0.0 and u0 > 0.0):
        raise ValueError("the inlet depth and velocity must be > 0")
    q = h0 * u0
    c = earth_pressure * gravity * math.cos(math.radians(inclination_deg))   # K g cos(zeta)
    gs = gravity * source(inclination_deg, friction_deg)
    fr0 = u0 / math.sqrt(c * h0) if c > 0.0 else math.inf
    side = 1.0 if fr0 > 1.0 else -1.0

    def rate(u: float) -> float:
        denominator = u * u - c * q / u
        if denominator * side <= 0.0:
            raise ValueError(f"the steady flow reaches the critical Froude number 1 (inlet Fr = "
                             f"{fr0:.3g}): no smooth steady solution beyond it")
        return gs * u / denominator

    u = np.empty_like(x)
    u[0] = u0
    for i in range(1, len(x)):
        dx = (x[i] - x[i - 1]) / substeps
        v = u[i - 1]
        for _ in range(substeps):
            k1 = rate(v)
            k2 = rate(v + 0.5 * dx * k1)
            k3 = rate(v + 0.5 * dx * k2)
            k4 = rate(v + dx * k3)
            v = v + dx / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        u[i] = v
    h = q / u
    return {"x": x, "h": h, "u": u, "q": q,
            "froude": froude(h, u, inclination_deg, gravity, earth_pressure)}


def invariant(x, h, u, inclination_deg: float, friction_deg: float, gravity: float = 9.81,
              earth_pressure: float = 1.0):
    """u^2/2 + K g cos(zeta) h - g S x (m^2/s^2): constant along an exact steady solution."""
    c = earth_pressure * gravity * math.cos(math.radians(inclination_deg))
    return (0.5 * np.asarray(u, float) ** 2 + c * np.asarray(h, float)
            - gravity * source(inclination_deg, friction_deg) * np.asarray(x, float))


def position_between(value, low_curve, high_curve):
    """Where ``value`` lies between two model curves: 0 on ``low_curve``, 1 on ``high_curve``
    (outside [0, 1] beyond them); arrays broadcast."""
    low, high = np.asarray(low_curve, float), np.asarray(high_curve, float)
    return (np.asarray(value, float) - low) / (high - low)
