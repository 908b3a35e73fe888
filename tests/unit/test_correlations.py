"""thermal/correlations.py: the Schlünder-Mollekopf wall-to-bed model of a rotating drum, its
parts checked against independent quadrature and its limits (contact-controlled at short
contact times, penetration-controlled at long ones)."""
import math

import numpy as np
import pytest

from taichi_dem.thermal import correlations as c

GLASS_BED = dict(density=1500.0, heat_capacity=800.0, conductivity=0.165)
D, K_G = 2e-3, 0.0262


def test_wetted_angle_of_a_half_full_drum_is_pi():
    assert c.wetted_angle_from_fill(0.5) == pytest.approx(math.pi, rel=1e-12)
    for f in (0.05, 0.1, 0.15, 0.2, 0.35):
        x = c.wetted_angle_from_fill(f)
        assert x - math.sin(x) == pytest.approx(2 * math.pi * f, rel=1e-12)
    with pytest.raises(ValueError):
        c.wetted_angle_from_fill(1.2)


def test_contact_time():
    # a wall element under a bed spanning 90 deg at 1 rpm stays covered a quarter minute
    assert c.contact_time(math.pi / 2, 1.0) == pytest.approx(15.0, rel=1e-12)


def test_wall_particle_coefficient_is_the_sphere_plane_gas_integral():
    # alpha_WP = k_g Int_0^R 2 pi r dr / (R - sqrt(R^2 - r^2) + gap) / (pi R^2), by quadrature
    r_p = D / 2
    for gap in (1e-7, 3e-7, 1e-6, 1e-5):
        u = np.linspace(0.0, r_p, 400001)           # in u = sqrt(R^2 - r^2): r dr = -u du
        f = 2 * math.pi * u / (r_p - u + gap)
        integral = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u)))
        expected = K_G * integral / (math.pi * r_p ** 2)
        assert c.wall_particle_coefficient(D, K_G, gap) == pytest.approx(expected, rel=1e-4)


def test_modified_mean_free_path_of_air():
    # a few tenths of a micrometre at 1 atm, inversely proportional to pressure
    l1 = c.modified_mean_free_path(330.0)
    assert 1e-7 < l1 < 1e-6
    assert c.modified_mean_free_path(330.0, pressure=101325.0 / 10) == pytest.approx(10 * l1)
    g = c.accommodation_coefficient(330.0)
    assert 0.8 < g < 0.95


def test_radiation_is_off_without_emissivities_and_sigma_t3_with():
    assert c.radiation_coefficient(350.0, 0.0, 0.9) == 0.0
    assert c.radiation_coefficient(350.0, 1.0, 1.0) == pytest.approx(4 * c.SIGMA * 350.0 ** 3)


def test_exact_series_limits():
    a_ws = 300.0
    e = GLASS_BED["density"] * GLASS_BED["heat_capacity"] * GLASS_BED["conductivity"]
    # t_c -> 0: only the contact resistance
    short = c.penetration_with_contact_resistance(a_ws, *GLASS_BED.values(), 1e-9)
    assert short == pytest.approx(a_ws, rel=1e-4)
    # t_c -> inf: penetration alone
    for t in (1e4, 1e6):
        pen = c.penetration_coefficient(*GLASS_BED.values(), t)
        exact = c.penetration_with_contact_resistance(a_ws, *GLASS_BED.values(), t)
        assert exact == pytest.approx(pen, rel=3 * pen / a_ws)
    # both branches of the evaluation agree where they meet (b = 1e-4)
    t_b = (1e-4 / a_ws) ** 2 * e
    lo = c.penetration_with_contact_resistance(a_ws, *GLASS_BED.values(), t_b * (1 - 1e-9))
    hi = c.penetration_with_contact_resistance(a_ws, *GLASS_BED.values(), t_b * (1 + 1e-9))
    assert lo == pytest.approx(hi, rel=1e-8)


@pytest.mark.parametrize("t_c", [0.1, 1.0, 3.0, 10.0, 100.0])
def test_exact_series_between_the_simple_series_and_either_resistance_alone(t_c):
    a_ws = 300.0
    pen = c.penetration_coefficient(*GLASS_BED.values(), t_c)
    simple = 1 / (1 / a_ws + 1 / pen)
    exact = c.penetration_with_contact_resistance(a_ws, *GLASS_BED.values(), t_c)
    assert simple < exact < min(a_ws, pen)
    assert exact < 1.25 * simple


def test_schlunder_mollekopf_limits_and_rpm_scaling():
    common = dict(wetted_angle=c.wetted_angle_from_fill(0.15), diameter=D, k_gas=K_G,
                  bed_density=1500.0, heat_capacity=800.0, bed_conductivity=0.165,
                  temperature=330.0)
    fast = c.schlunder_mollekopf(rpm=1e9, **common)          # t_c -> 0: contact-controlled
    assert fast["alpha"] == pytest.approx(fast["alpha_ws"], rel=1e-3)
    slow = c.schlunder_mollekopf(rpm=1e-6, **common)         # t_c -> inf: penetration
    assert slow["alpha"] == pytest.approx(slow["alpha_bed"], rel=1e-3)
    # the penetration part goes as sqrt(n)
    a2, a8 = (c.schlunder_mollekopf(rpm=n, **common)["alpha_bed"] for n in (2.0, 8.0))
    assert a8 / a2 == pytest.approx(2.0, rel=1e-12)
    # 2 mm glass in air at 1-9 rpm, 10-20 % fill: ~100-190 W/(m^2 K) (PHYSICS.md)
    for fill in (0.1, 0.2):
        for rpm in (1.0, 9.0):
            h = c.schlunder_mollekopf(rpm=rpm, **dict(common, wetted_angle=c.wetted_angle_from_fill(fill)))
            assert 70.0 < h["alpha"] < 230.0
