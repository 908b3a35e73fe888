"""The measuring helpers of taichi_dem.app.analysis on synthetic data with known answers."""
from __future__ import annotations

import math

import numpy as np
import pytest

from taichi_dem.app import analysis


def test_segment_centroid_limits_and_half_fill():
    # half-full drum: h = 0, centroid of a half disc at 4R/(3 pi)
    fill, r_cg = analysis.segment_centroid(1.0, 0.0)
    assert fill == pytest.approx(0.5)
    assert r_cg == pytest.approx(4 / (3 * math.pi))
    # a thin segment's centroid tends to the wall
    fill, r_cg = analysis.segment_centroid(1.0, 0.999)
    assert fill < 1e-3 and r_cg == pytest.approx(1.0, abs=2e-3)


def test_segment_centroid_against_a_sampled_segment():
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1, 1, (400_000, 2))
    R, h = 1.0, 0.35
    inside = (np.hypot(pts[:, 0], pts[:, 1]) < R) & (pts[:, 1] < -h)
    fill, r_cg = analysis.segment_centroid(R, h)
    assert fill == pytest.approx(inside.sum() / (len(pts) * math.pi / 4), rel=0.01)
    assert r_cg == pytest.approx(-pts[inside, 1].mean(), rel=0.005)


def test_bed_surface_recovers_a_tilted_plane():
    rng = np.random.default_rng(1)
    theta, h, r = math.radians(33.0), 0.03, 0.002
    # particles filling the region below the line z = y tan(theta) - h / cos(theta) in a disc
    pts = rng.uniform(-0.1, 0.1, (60_000, 2))
    line = pts[:, 0] * math.tan(theta) - h / math.cos(theta)
    keep = (np.hypot(pts[:, 0], pts[:, 1]) < 0.1) & (pts[:, 1] < line - r)
    y, z = pts[keep, 0], pts[keep, 1]
    t_fit, h_fit = analysis.bed_surface(y, z, np.full(len(y), r), 2 * r)
    assert math.degrees(t_fit) == pytest.approx(33.0, abs=0.5)
    assert h_fit == pytest.approx(h, abs=0.002)


def test_heap_angle_of_a_cone():
    rng = np.random.default_rng(2)
    angle, base, r = 37.0, 0.2, 0.005
    n = 40_000
    xy = rng.uniform(-base, base, (n, 2))
    rho = np.hypot(xy[:, 0], xy[:, 1])
    surface = (base - rho) * math.tan(math.radians(angle))
    z = rng.uniform(0, 1, n) * surface - r          # below the cone surface by one radius
    keep = (rho < base) & (z > 0)
    p = {"position": np.column_stack([xy[keep], z[keep]]), "radius": np.full(keep.sum(), r)}
    fitted, height, rings = analysis.heap_angle(p)
    assert fitted == pytest.approx(angle, abs=1.0)
    assert rings >= 8


def test_rates_and_beverloo():
    t = np.linspace(0, 1, 51)
    m = 2.0 * t + 0.01 * np.sin(40 * t)
    assert analysis.linear_rate(t, m, 0.2, 0.8) == pytest.approx(2.0, rel=0.02)
    assert analysis.steady_window(t, 2.0 * t, 2.0, 0.15, 0.6) == pytest.approx((0.15, 0.6))
    w = analysis.beverloo_rate(0.07, 0.01, 1500.0, 9.81)
    assert w == pytest.approx(0.58 * 1500 * math.sqrt(9.81) * 0.055 ** 2.5)
    n, a = analysis.fit_power_law(np.array([1.0, 2.0, 4.0]), 3.0 * np.array([1.0, 2.0, 4.0]) ** 2.5)
    assert n == pytest.approx(2.5) and a == pytest.approx(3.0)


def test_counter_current_balance_closes():
    # dry solids warming 300 -> 400 K at 1 kg/s (c 800) take 80 kW; gas at 2 kg/s (c 1000)
    # entering at 900 K must leave 40 K cooler where the solids enter; where they are at
    # 350 K, half of that. With evaporation the latent heat comes on top.
    from taichi_dem.app.analysis import counter_current_gas_temperature
    t = counter_current_gas_temperature([300.0, 350.0, 400.0], [0.0, 0.0, 0.0], 400.0, 0.0,
                                        1.0, 2.0, 800.0, 1000.0, 900.0, 2.26e6, 4186.0, 373.15)
    np.testing.assert_allclose(t, [860.0, 880.0, 900.0], rtol=1e-12)
    wet = counter_current_gas_temperature([300.0], [0.01], 400.0, 0.0, 1.0, 2.0, 800.0, 1000.0,
                                          900.0, 2.26e6, 4186.0, 373.15)
    sensible = 1.0 * (800.0 * 400.0 - (800.0 + 0.01 * 4186.0) * 300.0)
    latent = 0.01 * (2.26e6 + 4186.0 * 373.15)
    assert wet[0] == pytest.approx(900.0 - (sensible + latent) / 2000.0, rel=1e-12)


def test_longer_cooler_outlet_is_the_plug_flow_exponential():
    import math
    from taichi_dem.app.analysis import longer_cooler_outlet
    # a 0.5 m cooler whose shell takes 534 W from a bed at 723 K over a 303 K shell:
    # UA' = 534 / (0.5 x 420) = 2.543 W/(m K); 6 m at 13 t/h of c = 800: NTU = 15.26 / 2889
    q = np.full(40, 534.0)
    bed = np.full(40, 723.0)
    est = longer_cooler_outlet(q, 0.5, bed, 303.0, 723.15, 13000 / 3600, 800.0, 6.0)
    ua = 534.0 / (0.5 * 420.0)
    ntu = ua * 6.0 / (13000 / 3600 * 800.0)
    assert est["conductance_per_metre"] == pytest.approx(ua, rel=1e-12)
    assert est["ntu"] == pytest.approx(ntu, rel=1e-12)
    assert est["outlet_temperature"] == pytest.approx(303.0 + 420.15 * math.exp(-ntu), rel=1e-12)
    assert est["outlet_temperature_error"] == 0.0       # no scatter, no error
    # scatter between blocks becomes an error of the right size
    noisy = q * np.repeat([0.9, 1.1, 0.9, 1.1], 10)
    est = longer_cooler_outlet(noisy, 0.5, bed, 303.0, 723.15, 13000 / 3600, 800.0, 6.0)
    assert est["conductance_per_metre_error"] == pytest.approx(ua * 0.1 * 2 / math.sqrt(3) / 2,
                                                              rel=1e-9)
    assert 0.0 < est["outlet_temperature_error"] < 723.15 - est["outlet_temperature"]
