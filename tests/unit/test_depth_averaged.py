"""The steady depth-averaged chute model (taichi_dem/app/depth_averaged.py) against its exact
limits: uniform flow when tan(delta) = tan(zeta); free acceleration u^2 = u0^2 + 2 g S x without
the depth gradient (K = 0); the exact Bernoulli-with-friction invariant with it (K = 1)."""
import math

import numpy as np
import pytest

from taichi_dem.app import depth_averaged as da

X = np.linspace(0.0, 0.15, 61)          # m: the seed's chute, inlet at x = 0
H0, U0, ZETA, G = 0.022, 0.5492, 38.0, 9.80   # seed 004's inlet and slope


def test_friction_equal_to_slope_gives_uniform_flow():
    # S = 0: no net driving force, the inlet state is the steady state everywhere
    p = da.steady_profile(X, H0, U0, ZETA, ZETA, gravity=G)
    assert np.allclose(p["u"], U0, rtol=1e-12) and np.allclose(p["h"], H0, rtol=1e-12)


def test_without_depth_gradient_the_flow_accelerates_freely():
    # K = 0: u du/dx = g S exactly, u^2 = u0^2 + 2 g S x; h = q / u
    for delta in (23.0, 30.0):
        p = da.steady_profile(X, H0, U0, ZETA, delta, gravity=G, earth_pressure=0.0)
        exact = np.sqrt(U0 ** 2 + 2.0 * G * da.source(ZETA, delta) * X)
        assert np.allclose(p["u"], exact, rtol=1e-10)
        assert np.allclose(p["h"] * p["u"], H0 * U0, rtol=1e-12)


@pytest.mark.parametrize("delta", [23.0, 30.0, 38.3])
def test_bernoulli_invariant_with_the_depth_gradient(delta):
    # K = 1: u^2/2 + g cos(zeta) h - g S x is constant along the exact solution; RK4's error is
    # far below 1e-9 of the inlet value (the solution is smooth, 200 substeps per 2.5 mm).
    # delta = 38.3 deg > zeta: a supercritical flow that decelerates (it would reach Fr = 1
    # after about 0.19 m; the chute is 0.15 m)
    p = da.steady_profile(X, H0, U0, ZETA, delta, gravity=G)
    e = da.invariant(X, p["h"], p["u"], ZETA, delta, gravity=G)
    assert np.max(np.abs(e - e[0])) < 1e-9 * abs(e[0])
    assert np.allclose(p["h"] * p["u"], H0 * U0, rtol=1e-12)
    # accelerating flow thins for delta < zeta, thickens (decelerates) for delta > zeta
    assert (np.all(np.diff(p["u"]) > 0) if delta < ZETA else np.all(np.diff(p["u"]) < 0))


def test_the_depth_gradient_slows_the_thinning_of_a_supercritical_flow():
    # with K = 1 part of the potential g cos(zeta) h is released as the flow thins: it ends
    # faster than the K = 0 flow (the invariant: u^2/2 = u0^2/2 + g S x + g cos(zeta)(h0 - h))
    a = da.steady_profile(X, H0, U0, ZETA, 23.0, gravity=G, earth_pressure=0.0)
    b = da.steady_profile(X, H0, U0, ZETA, 23.0, gravity=G)
    assert b["u"][-1] > a["u"][-1]
    assert da.froude(H0, U0, ZETA, G) == pytest.approx(U0 / math.sqrt(G * H0 * math.cos(math.radians(ZETA))))


def test_flows_driven_to_the_critical_froude_number_are_refused():
    # Fr0 < 1 with S < 0 accelerates (du/dx = g S u / (u^2 - K g h cos) > 0) and thins towards
    # Fr = 1; Fr0 > 1 with S < 0 decelerates towards it: both are singular there
    with pytest.raises(ValueError, match="critical Froude"):
        da.steady_profile(np.linspace(0, 1.0, 11), 0.05, 0.2, ZETA, 45.0, gravity=G)
    with pytest.raises(ValueError, match="critical Froude"):
        da.steady_profile(X, H0, U0, ZETA, 40.0, gravity=G)
    # subcritical with S > 0 decelerates and thickens, away from Fr = 1: fine
    p = da.steady_profile(np.linspace(0, 1.0, 11), 0.05, 0.2, ZETA, 23.0, gravity=G)
    assert np.all(np.diff(p["froude"]) < 0)


def test_position_between():
    assert da.position_between(1.5, 1.0, 2.0) == pytest.approx(0.5)
    assert da.position_between(0.5, 1.0, 2.0) == pytest.approx(-0.5)
