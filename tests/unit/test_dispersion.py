"""Axial dispersion (issue 44 item 6): D_ax from the variance growth of unwrapped axial
displacements, and E(t) of the axial dispersion model against the closed vessel's analytic
moments (Levenspiel, Chemical Reaction Engineering, 3rd ed., ch. 13, eq. 13.12: mean tau,
variance tau^2 (2/Pe - 2/Pe^2 (1 - e^-Pe)))."""
import math

import numpy as np
import pytest

from taichi_dem.app.dispersion import (AxialDisplacements, closed_vessel_variance,
                                       dispersion_coefficient, residence_time_distribution)


def test_random_walkers_on_a_periodic_axis_give_their_diffusivity():
    """Walkers with diffusivity D and a drift, wrapped into a 0.25 m period and sampled every
    0.1 s for 40 s: the unwrapped variance grows as 2 D t. 4000 walkers: the variance's
    relative noise is sqrt(2/4000) = 2.2 %, so D within 8 % (over 3 sigma)."""
    rng = np.random.default_rng(7)
    D, drift, dt, period = 2e-4, 0.03, 0.1, 0.25
    x = rng.uniform(0, period, 4000)
    walk = AxialDisplacements(period)
    for k in range(401):
        walk.add(k * dt, np.mod(x, period))
        x = x + drift * dt + rng.normal(0.0, math.sqrt(2 * D * dt), x.size)
    value, error = dispersion_coefficient(walk.times, walk.variances)
    assert value == pytest.approx(D, rel=0.08)
    assert 0.0 < error < 0.1 * D
    # the wrap is undone: no variance of order the period squared
    assert max(walk.variances) < 2.5 * 2 * D * 40.0


def test_a_short_record_gives_no_coefficient():
    assert math.isnan(dispersion_coefficient([0.0, 0.1, 0.2], [0.0, 1e-5, 2e-5])[0])


@pytest.mark.parametrize("peclet", [5.0, 20.0, 80.0])
def test_the_uniform_machine_has_the_closed_vessel_moments(peclet):
    """A 6 m machine at 60 kg/m fed 1.8 kg/s (tau = 200 s): mean within 0.1 % (the pulse
    leaves through a closed end: the mean is tau exactly, up to the time step), variance
    within 2 % of the analytic one (the implicit time step spreads it a little: 1 % at Pe 80)."""
    length, holdup, feed = 6.0, 60.0, 1.8
    tau = length * holdup / feed
    d = feed / holdup * length / peclet
    rtd = residence_time_distribution(np.array([0.0, length]), np.array([holdup, holdup]),
                                      np.array([d, d]), feed)
    assert rtd.mean == pytest.approx(tau, rel=1e-3)
    assert rtd.variance == pytest.approx(closed_vessel_variance(tau, peclet), rel=0.02)
    assert rtd.t10 < rtd.t50 < rtd.t90
    # what left is the whole pulse
    assert np.trapezoid(rtd.density, rtd.time) == pytest.approx(1.0, abs=2e-3)


def test_a_machine_of_two_hold_ups_keeps_its_mean_residence():
    """An inlet end at 90 kg/m falling to 30 kg/m: the mean residence is the hold-up over the
    feed whatever the dispersion (the integral of h over F), and a weaker dispersion narrows
    the distribution."""
    x = np.linspace(0.0, 6.0, 13)
    h = np.interp(x, [0.0, 2.0, 6.0], [90.0, 40.0, 30.0])
    feed = 1.5
    tau = np.trapezoid(h, x) / feed
    wide = residence_time_distribution(x, h, np.full_like(x, 5e-3), feed)
    narrow = residence_time_distribution(x, h, np.full_like(x, 5e-4), feed)
    for rtd in (wide, narrow):
        assert rtd.mean == pytest.approx(tau, rel=2e-3)
    assert narrow.variance < 0.3 * wide.variance
    assert narrow.t90 - narrow.t10 < wide.t90 - wide.t10


def test_a_feed_spread_over_a_stretch():
    """The feed falling evenly over x0..x1 instead of at the closed end: every parcel still
    passes the whole bed in the mean (a closed vessel's mean is V / F wherever the tracer
    enters, 1e-3), the pulse starting spread widens the distribution and cuts its early
    part short, and a stretch shrunk towards the end gives the point inlet back (1 %).
    Nearly plug flow (Pe 200) along L = 6 m, the feed over the first a = L / 3: the flow grows
    as F x / a there, so a parcel fed at x_e takes (a / u) ln(a / x_e) to reach a (u = F / h),
    then (L - a) / u; with x_e even on (0, a), ln(a / x_e) is exponential with mean and
    variance 1: the mean stays tau and the variance gains (tau a / L)^2 over the point
    inlet's (5 %: the dispersion and the feed's spread are not quite independent)."""
    length, holdup, feed = 6.0, 60.0, 1.8
    tau = length * holdup / feed
    x = np.array([0.0, length])
    h = np.array([holdup, holdup])
    d = np.full(2, feed / holdup * length / 200.0)
    point = residence_time_distribution(x, h, d, feed)
    spread = residence_time_distribution(x, h, d, feed, inlet=(0.0, length / 3))
    near = residence_time_distribution(x, h, d, feed, inlet=(0.0, 0.01))
    assert spread.mean == pytest.approx(tau, rel=1e-3)
    assert near.mean == pytest.approx(point.mean, rel=1e-3)
    assert near.variance == pytest.approx(point.variance, rel=0.01)
    plug_spread = (tau / 3.0) ** 2
    assert spread.variance == pytest.approx(plug_spread + point.variance, rel=0.05)
    assert spread.t10 < point.t10
    with pytest.raises(ValueError):
        residence_time_distribution(x, h, d, feed, inlet=(-0.1, 1.0))


def test_outlet_temperatures_of_the_parcels():
    """Each parcel cools as exp(-NTU t / tau): the median parcel (t50 just below tau for a
    closed vessel) leaves near the plug's outlet; by Jensen's inequality (exp is convex) the
    mixed outlet is warmer than the plug's; and a narrow distribution (Pe 400) gives the plug's
    outlet back within 0.5 K, where a wide one (Pe 5) does not."""
    from taichi_dem.app.dispersion import outlet_temperatures
    length, holdup, feed = 6.0, 60.0, 1.8
    tau = length * holdup / feed
    t_in, wall, plug = 723.15, 303.15, 600.0
    got = {}
    for pe in (5.0, 400.0):
        d = feed / holdup * length / pe
        rtd = residence_time_distribution(np.array([0.0, length]), np.array([holdup, holdup]),
                                          np.array([d, d]), feed)
        mixed, q = outlet_temperatures(rtd, tau, t_in, wall, plug)
        assert mixed > plug
        assert q[0.1] < q[0.5] < q[0.9]
        got[pe] = (mixed, q)
    assert got[400.0][0] == pytest.approx(plug, abs=0.5)
    assert got[5.0][0] - plug > 2.0
    assert got[5.0][1][0.9] - got[5.0][1][0.1] > 5 * (got[400.0][1][0.9] - got[400.0][1][0.1])


def test_kaplan_meier_without_censoring_is_the_sample_itself():
    """Every particle seen to leave: the survival estimate is the empirical one, so its mean,
    spread and quantiles are the sample's exactly (no tolerance beyond rounding)."""
    from taichi_dem.app.dispersion import rtd_figures
    stay = np.array([3.0, 1.0, 2.0, 2.0, 7.0, 5.0, 4.0, 6.0, 9.0, 8.0])
    got = rtd_figures(stay, np.ones(stay.size, bool))
    assert got["mean"] == pytest.approx(np.mean(stay), rel=1e-12)
    assert got["standard_deviation"] == pytest.approx(np.std(stay), rel=1e-12)
    assert (got["t10"], got["t50"], got["t90"]) == (1.0, 4.0, 8.0)
    assert got["unseen_tail"] == 0.0


def test_kaplan_meier_recovers_a_censored_gamma_distribution():
    """Residence times drawn from a gamma distribution (shape 4, mean 12 s: a dispersed plug),
    entering uniformly over 60 s of a run that ends at 60 s, so the late entrants are cut off
    (censored) while inside: about a fifth of them. The estimate must give the distribution's
    own mean 12 s, standard deviation 6 s and quantiles; dropping the censored ones instead
    biases the mean low by ~6 % (checked too, so the test can fail). 20,000 particles: the
    mean's sampling error is 0.3 %, the quantiles' ~1 %: 3 % tolerances."""
    from scipy import stats
    from taichi_dem.app.dispersion import rtd_figures
    rng = np.random.default_rng(3)
    n, end = 20000, 60.0
    dist = stats.gamma(4.0, scale=3.0)
    t_in = rng.uniform(0.0, end, n)
    true = dist.rvs(size=n, random_state=rng)
    left = t_in + true <= end
    stay = np.where(left, true, end - t_in)
    assert 0.1 < 1.0 - left.mean() < 0.3
    got = rtd_figures(stay, left)
    assert got["mean"] == pytest.approx(12.0, rel=0.03)
    assert got["standard_deviation"] == pytest.approx(6.0, rel=0.03)
    for q in (0.1, 0.5, 0.9):
        assert got[f"t{int(q * 100)}"] == pytest.approx(dist.ppf(q), rel=0.03)
    naive = rtd_figures(stay[left], left[left])
    assert naive["mean"] < 0.96 * 12.0
