"""Steady-state detection and the standard error of a steady mean (app/steady_state.py),
against series whose answer is known: an AR(1) process (its mean's variance is analytic), a
transient decaying into it, and a drift that never settles."""
import numpy as np
import pytest

from taichi_dem.app.steady_state import block_standard_error, steady_mean, steady_start


def ar1(n, phi, sigma, mean, rng, start=None):
    """x_t = mean + phi (x_{t-1} - mean) + sigma e_t, started in its stationary law."""
    e = rng.standard_normal(n) * sigma
    x = np.empty(n)
    x[0] = (mean + e[0] / np.sqrt(1.0 - phi * phi)) if start is None else start
    for t in range(1, n):
        x[t] = mean + phi * (x[t - 1] - mean) + e[t]
    return x


def ar1_mean_standard_error(n, phi, sigma):
    """The standard deviation of the mean of n samples of a stationary AR(1), exactly:
    var(mean) = gamma0 / n^2 (n + 2 sum_k (n - k) phi^k), gamma0 = sigma^2 / (1 - phi^2)."""
    k = np.arange(1, n)
    gamma0 = sigma * sigma / (1.0 - phi * phi)
    return np.sqrt(gamma0 / n ** 2 * (n + 2.0 * np.sum((n - k) * phi ** k)))


def test_blocking_recovers_the_analytic_standard_error_of_a_correlated_mean():
    """AR(1), phi 0.9 (correlation time ~19 samples), 2^14 samples: the naive standard error
    is 4.4x too small; blocking must find the analytic one. Over 40 series the median
    estimate is within 10 % of it (one estimate at the plateau, with >= 16 blocks, scatters by
    1/sqrt(2 (M - 1)) <= 18 %; the median of 40 by ~3 %), and the mean lies within two
    estimated standard errors of the truth in 85 - 100 % of them (95 % expected)."""
    rng = np.random.default_rng(1)
    n, phi, sigma, mu = 2 ** 14, 0.9, 1.0, 3.0
    exact = ar1_mean_standard_error(n, phi, sigma)
    estimates, covered = [], 0
    for _ in range(40):
        x = ar1(n, phi, sigma, mu, rng)
        err = block_standard_error(x)
        assert err.converged and err.blocks >= 16
        estimates.append(err.standard_error)
        covered += abs(np.mean(x) - mu) < 2.0 * err.standard_error
        naive = np.std(x, ddof=1) / np.sqrt(n)
        assert err.standard_error > 3.0 * naive
    assert np.median(estimates) == pytest.approx(exact, rel=0.10)
    assert 34 <= covered <= 40


def test_uncorrelated_samples_keep_the_naive_standard_error():
    rng = np.random.default_rng(2)
    x = rng.standard_normal(4096) * 2.0 + 1.0
    err = block_standard_error(x)
    # the plateau starts at once: within 10 % of sigma / sqrt(n) = 0.03125
    assert err.standard_error == pytest.approx(2.0 / 64.0, rel=0.10)


def test_a_transient_is_cut_and_the_steady_mean_is_unbiased():
    """A start 10 standard deviations away, relaxing over 300 samples, then correlated noise:
    MSER cuts where what is left of the transient biases the mean by less than the mean's
    standard error (not where it vanishes: that would throw steady data away). So: a cut
    past two relaxation times, a remaining bias (known exactly here) below one standard
    error, the truth within 3 standard errors of the steady mean - and the mean of the whole
    series (its bias height tau / n = 0.15) 5 standard errors or more away."""
    rng = np.random.default_rng(3)
    n, mu, tau, height = 20000, 0.0, 300.0, 10.0
    t = np.arange(n)
    transient = height * np.exp(-t / tau)
    x = mu + transient + ar1(n, 0.5, 1.0, 0.0, rng)
    start = steady_start(x)
    assert start is not None and 2 * tau <= start <= n // 2
    m = steady_mean(x)
    assert m.steady and m.start == start and m.samples == n - start
    assert np.mean(transient[start:]) < m.standard_error
    assert abs(m.mean - mu) < 3.0 * m.standard_error
    assert abs(np.mean(x) - mu) > 5.0 * m.standard_error      # (bias height tau / n = 0.15)


def test_a_drift_is_not_a_steady_state():
    """A series that rises steadily (a filling bed, a heating drum) has no steady part: the
    cut falls in the second half and is refused."""
    rng = np.random.default_rng(4)
    x = np.linspace(0.0, 20.0, 5000) + rng.standard_normal(5000)
    assert steady_start(x) is None
    m = steady_mean(x)
    assert not m.steady and "not steady" in str(m)


def test_short_series_are_refused_plainly():
    with pytest.raises(ValueError, match="two samples"):
        block_standard_error([1.0])
    with pytest.raises(ValueError, match="two samples"):
        steady_mean([])
    assert steady_start([1.0, 2.0, 3.0]) is None
