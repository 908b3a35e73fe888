"""Axial dispersion and residence-time distributions (issue 44 item 6).

A slice measures how the particles spread along the axis: each particle's axial coordinate is
unwrapped across the periodic faces between samples (``AxialDisplacements``), and the variance
of the displacements grows as 2 D_ax t once the particles have sampled the bed's cross-section
(Taylor's shear dispersion: a particle near the shell and one near the surface move at
different axial speeds; over many turns each is every one of them in turn)
(``dispersion_coefficient``). A machine is then the axial dispersion model along its length,
with the hold-up h(x) of the march and D_ax(h) of the map: the tracer fraction phi of the bed
obeys

    d(h phi)/dt + d/dx (F phi - h D_ax dphi/dx) = 0,

F the feed (kg/s), closed at both ends (Danckwerts: nothing disperses back out of the inlet or
in from the outlet), and E(t) is the outlet's tracer flux after a pulse at the inlet
(``residence_time_distribution``). For a uniform bed it has the closed vessel's moments (Levenspiel,
Chemical Reaction Engineering, ch. 13): mean tau = L h / F and variance
tau^2 (2/Pe - 2/Pe^2 (1 - exp(-Pe))), Pe = u L / D_ax.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


class AxialDisplacements:
    """Each particle's axial displacement (m) since the first sample, unwrapped across a
    periodic axis of ``length`` m; the particles must keep their order (``sim.particles()``
    gives them in id order) and move less than half the period between samples."""

    def __init__(self, length: float):
        self.length = float(length)
        self._last = None
        self._total = None
        self.times: list[float] = []
        self.variances: list[float] = []     # m^2: about the mean displacement

    def add(self, time: float, axial: np.ndarray) -> None:
        """One sample: the particles' axial coordinates (m) at ``time`` (s)."""
        axial = np.asarray(axial, float)
        if self._last is None or len(axial) != len(self._last):
            self._last, self._total = axial.copy(), np.zeros_like(axial)
            self.times, self.variances = [], []
        else:
            step = axial - self._last
            step -= self.length * np.round(step / self.length)
            self._total += step
            self._last = axial.copy()
        self.times.append(float(time))
        self.variances.append(float(np.var(self._total)) if len(axial) else math.nan)


def dispersion_coefficient(times, variances, skip: float = 0.25,
                           blocks: int = 4) -> tuple[float, float]:
    """(D_ax, its standard error) in m^2/s from the variance of the axial displacements (m^2)
    against time (s): half the slope of a straight line fitted after the first ``skip`` of
    the record (the spread is not yet diffusive while the particles keep their first layers).
    The error is the scatter of the slopes of ``blocks`` consecutive parts over sqrt(blocks):
    the variances are cumulative, so the fit's own error would understate it. NaN when the
    record is too short."""
    t = np.asarray(times, float)
    v = np.asarray(variances, float)
    keep = np.isfinite(v) & (t >= t[0] + skip * (t[-1] - t[0])) if len(t) else np.array([], bool)
    t, v = t[keep], v[keep]
    if len(t) < 3 * blocks or t[-1] <= t[0]:
        return math.nan, math.nan
    slope = np.polyfit(t, v, 1)[0]
    parts = [np.polyfit(tb, vb, 1)[0] for tb, vb in
             zip(np.array_split(t, blocks), np.array_split(v, blocks))]
    return 0.5 * float(slope), 0.5 * float(np.std(parts, ddof=1) / math.sqrt(blocks))


@dataclass
class ResidenceTimes:
    """A residence-time distribution: E(t) (1/s) at ``time`` (s), its mean (s), variance
    (s^2), and the times by which 10, 50 and 90 % of a pulse has left (s)."""
    time: np.ndarray
    density: np.ndarray
    mean: float
    variance: float
    t10: float
    t50: float
    t90: float

    def quantile(self, q: float) -> float:
        """The time (s) by which the fraction ``q`` of the pulse has left."""
        cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (self.density[1:] + self.density[:-1])
                                                      * np.diff(self.time))])
        return float(np.interp(q * cumulative[-1], cumulative, self.time))


def _moments(time, density) -> tuple[float, float]:
    w = np.gradient(time)
    mass = float(np.sum(density * w))
    mean = float(np.sum(time * density * w)) / mass
    return mean, float(np.sum((time - mean) ** 2 * density * w)) / mass


def residence_time_distribution(x: np.ndarray, holdup: np.ndarray, dispersion: np.ndarray,
                                feed: float, cells: int | None = None,
                                until: float = 6.0) -> ResidenceTimes:
    """E(t) of the axial dispersion model (module docstring) along a machine whose hold-up
    (kg/m) and D_ax (m^2/s) are given at the positions ``x`` (m, inlet at x[0], outlet at
    x[-1]), fed ``feed`` kg/s: a pulse at the inlet, finite volumes (central differences, the
    cells fine enough that the cell Peclet number stays below 1.5, so no numerical dispersion
    is added), implicit in time, run until ``until`` mean residence times."""
    from scipy.linalg import solve_banded
    x = np.asarray(x, float)
    length = float(x[-1] - x[0])
    h_of = lambda s: np.interp(s, x, np.asarray(holdup, float))              # noqa: E731
    d_of = lambda s: np.interp(s, x, np.asarray(dispersion, float))          # noqa: E731
    tau = float(np.trapezoid(np.asarray(holdup, float), x)) / feed
    if cells is None:
        fine = np.linspace(x[0], x[-1], 2001)
        u = feed / h_of(fine)
        dx_max = 1.5 * float(np.min(d_of(fine) / u))
        cells = int(min(max(200, math.ceil(length / dx_max)), 20000))
    dx = length / cells
    centres = x[0] + (np.arange(cells) + 0.5) * dx
    faces = x[0] + np.arange(1, cells) * dx                       # the inner faces
    h = h_of(centres)
    hd = h_of(faces) * d_of(faces) / dx                           # kg/s per unit phi jump
    # inner face k (between cells k and k+1): flux = F (phi_k + phi_k+1) / 2 - hd_k (phi_k+1 - phi_k)
    dt = tau / 4000.0
    steps = int(math.ceil(until * tau / dt))
    m = h * dx / dt
    lower = np.zeros(cells)          # coefficient of phi_{k-1} in row k
    main = m.copy()
    upper = np.zeros(cells)          # coefficient of phi_{k+1} in row k
    # face k carries out of cell k and into cell k+1
    main[:-1] += 0.5 * feed + hd
    upper[:-1] += 0.5 * feed - hd
    main[1:] += -0.5 * feed + hd
    lower[1:] += -0.5 * feed - hd
    main[-1] += feed                 # the outlet carries F phi_N away (closed: no gradient)
    banded = np.zeros((3, cells))
    banded[0, 1:] = upper[:-1]
    banded[1] = main
    banded[2, :-1] = lower[1:]
    phi = np.zeros(cells)
    phi[0] = 1.0 / (h[0] * dx)       # a unit pulse of tracer mass in the first cell
    times = np.empty(steps + 1)
    out = np.empty(steps + 1)
    times[0], out[0] = 0.0, 0.0
    for n in range(1, steps + 1):
        phi = solve_banded((1, 1), banded, m * phi)
        times[n] = n * dt
        out[n] = feed * phi[-1]
    mean, variance = _moments(times, out)
    rtd = ResidenceTimes(times, out, mean, variance, math.nan, math.nan, math.nan)
    rtd.t10, rtd.t50, rtd.t90 = (rtd.quantile(q) for q in (0.1, 0.5, 0.9))
    return rtd


def closed_vessel_variance(tau: float, peclet: float) -> float:
    """The variance (s^2) of the closed vessel's E(t): tau^2 (2/Pe - 2/Pe^2 (1 - e^-Pe))."""
    return tau * tau * (2.0 / peclet - 2.0 / peclet ** 2 * (1.0 - math.exp(-peclet)))
