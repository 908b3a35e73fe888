"""Pooling a short sample with the interval before it (taichi_dem/sensors/pooling.py), on
synthetic series whose answers are known exactly: rates and counts of a pooled sample are
those over both intervals, an outlet temperature is mass-weighted over both, and the running
integral of a pooled rate series gives back the cumulative mass to round-off."""
import math

import numpy as np
import pytest

from taichi_dem.sensors.pooling import (amounts, cumulative_of_rate, pool, rate_of_cumulative,
                                        should_pool)

NOMINAL = 0.02


def test_pooled_rate_count_and_weighted_mean():
    """Previous interval: 0.02 s, 3 g removed at 400 K, 6 crossings; short interval: 0.002 s,
    1 g removed at 500 K, 0 crossings. Pooled: 4 g over 0.022 s; (3 x 400 + 1 x 500) / 4 K;
    6 crossings per 0.022 s given per 0.02 s; a vector load time-averaged."""
    prev = {"outlets/o/mass_flow": 0.003 / 0.02, "outlets/o/mean_temperature": 400.0,
            "sensors/p/crossings": 6.0, "bodies/b/force": np.array([1.0, 2.0, 3.0]),
            "particles/count": 10.0}
    short = {"outlets/o/mass_flow": 0.001 / 0.002, "outlets/o/mean_temperature": 500.0,
             "sensors/p/crossings": 0.0, "bodies/b/force": np.array([4.0, 0.0, 0.0]),
             "particles/count": 11.0}
    tail = amounts(prev, 0.02)
    assert "particles/count" not in tail          # an instantaneous value is left alone
    pool(short, 0.002, tail, NOMINAL)
    assert short["outlets/o/mass_flow"] == pytest.approx(0.004 / 0.022, rel=1e-12)
    assert short["outlets/o/mean_temperature"] == pytest.approx(1700.0 / 4.0, rel=1e-12)
    assert short["sensors/p/crossings"] == pytest.approx(6.0 * 0.02 / 0.022, rel=1e-12)
    assert np.allclose(short["bodies/b/force"],
                       (np.array([1.0, 2.0, 3.0]) * 0.02 + np.array([4.0, 0, 0]) * 0.002) / 0.022)
    assert short["particles/count"] == 11.0


def test_nothing_removed_in_either_interval_gives_nan_temperature():
    prev = {"outlets/o/mass_flow": 0.0, "outlets/o/mean_temperature": math.nan}
    short = {"outlets/o/mass_flow": 0.0, "outlets/o/mean_temperature": math.nan}
    pool(short, 0.002, amounts(prev, 0.02), NOMINAL)
    assert math.isnan(short["outlets/o/mean_temperature"])
    assert short["outlets/o/mass_flow"] == 0.0


def test_only_short_samples_with_a_predecessor_pool():
    dt = 1e-4
    assert should_pool(0.0019, NOMINAL, dt, {"interval": 0.02})
    assert not should_pool(NOMINAL - 0.4 * dt, NOMINAL, dt, {"interval": 0.02})
    assert not should_pool(0.0019, NOMINAL, dt, None)       # nothing before it (run < interval)
    assert not should_pool(0.0, NOMINAL, dt, {"interval": 0.02})


def test_rates_and_integrals_of_a_pooled_series_are_exact():
    """A cumulative mass M(t) sampled every 0.02 s and at a closing 0.0019 s later: the
    rates the sensors would write (the last pooled over 0.0219 s) integrate back to M at
    every sample, and the rates of M over what each sample covers are those rates."""
    rng = np.random.default_rng(1)
    t = np.concatenate([np.arange(0.0, 0.2 + 1e-9, NOMINAL), [0.2019]])
    mass = np.concatenate([[0.0], np.cumsum(rng.uniform(0.0, 1e-3, len(t) - 1))])
    covered = np.concatenate([[0.0], np.diff(t)])
    covered[-1] = t[-1] - t[-3]
    rate = np.zeros_like(t)
    for i in range(1, len(t)):
        start = t[i] - covered[i]
        rate[i] = (mass[i] - np.interp(start, t, mass)) / covered[i]
    assert np.allclose(cumulative_of_rate(t, rate, covered), mass, rtol=0, atol=1e-15)
    times, back = rate_of_cumulative(t, mass, covered)
    assert np.array_equal(times, t[1:])
    assert np.allclose(back, rate[1:], rtol=1e-12, atol=0)
    # without what each sample covers, the integral charges the short sample's pooled rate
    # to its own 1.9 ms only: off by the interval before it
    plain = cumulative_of_rate(t, rate)
    assert abs(plain[-1] - mass[-1]) > 1e-6
