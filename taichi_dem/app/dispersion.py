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
                                until: float = 6.0, inlet=None) -> ResidenceTimes:
    """E(t) of the axial dispersion model (module docstring) along a machine whose hold-up
    (kg/m) and D_ax (m^2/s) are given at the positions ``x`` (m, inlet at x[0], outlet at
    x[-1]), fed ``feed`` kg/s: a pulse at the inlet, finite volumes (central differences, the
    cells fine enough that the cell Peclet number stays below 1.5, so no numerical dispersion
    is added), implicit in time, run until ``until`` mean residence times. ``inlet``: (x0, x1)
    m, the feed falling evenly over that stretch instead of entering at x[0] (a feed box above
    the bed): the flow grows from 0 to ``feed`` across it, the pulse is spread over it, and
    the bed upstream of it only exchanges by dispersion."""
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
    if inlet is None:
        flow = np.full(cells - 1, float(feed))                  # at the inner faces
        pulse = np.zeros(cells)
        pulse[0] = 1.0
    else:
        x0, x1 = (float(v) for v in inlet)
        if not x[0] <= x0 < x1 <= x[-1]:
            raise ValueError(f"the inlet stretch ({x0:g}, {x1:g}) m must lie in the machine")
        # the fraction of the feed already in at each face, and each cell's share of it
        fed = lambda s: np.clip((s - x0) / (x1 - x0), 0.0, 1.0)   # noqa: E731
        flow = feed * fed(faces)
        pulse = np.diff(fed(np.concatenate([[x[0]], faces, [x[-1]]])))
    h = h_of(centres)
    hd = h_of(faces) * d_of(faces) / dx                           # kg/s per unit phi jump
    # inner face k (between cells k and k+1): flux = F_k (phi_k + phi_k+1) / 2 - hd_k (phi_k+1 - phi_k)
    dt = tau / 4000.0
    steps = int(math.ceil(until * tau / dt))
    m = h * dx / dt
    lower = np.zeros(cells)          # coefficient of phi_{k-1} in row k
    main = m.copy()
    upper = np.zeros(cells)          # coefficient of phi_{k+1} in row k
    # face k carries out of cell k and into cell k+1
    main[:-1] += 0.5 * flow + hd
    upper[:-1] += 0.5 * flow - hd
    main[1:] += -0.5 * flow + hd
    lower[1:] += -0.5 * flow - hd
    main[-1] += feed                 # the outlet carries F phi_N away (closed: no gradient)
    banded = np.zeros((3, cells))
    banded[0, 1:] = upper[:-1]
    banded[1] = main
    banded[2, :-1] = lower[1:]
    phi = pulse / (h * dx)           # a unit pulse of tracer mass: the first cell, or the inlet's
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


def kaplan_meier(stay, left):
    """A direct run's residence-time distribution (bench/direct_rtd.py), the survival function S(t) (the fraction still inside after t s) from each particle's
    time ``stay`` (s): its residence time where ``left``, else the time it had stayed when the
    run ended (censored). Returns (the distinct residence times, S just after each)."""
    stay, left = np.asarray(stay, float), np.asarray(left, bool)
    order = np.argsort(stay, kind="stable")
    stay, left = stay[order], left[order]
    times, index = np.unique(stay, return_index=True)
    at_risk = len(stay) - index
    events = np.add.reduceat(left.astype(float), index)
    keep = events > 0
    survival = np.cumprod(1.0 - events[keep] / at_risk[keep])
    return times[keep], survival


def rtd_figures(stay, left) -> dict:
    """Mean (s), standard deviation (s), 10/50/90 % times (s) and the fraction not seen to leave
    (the tail beyond the longest observed stay) of the Kaplan-Meier survival function."""
    t, s = kaplan_meier(stay, left)
    grid_t = np.concatenate([[0.0], t])
    grid_s = np.concatenate([[1.0], s])
    widths = np.diff(grid_t)
    mean = float(np.sum(grid_s[:-1] * widths))                   # integral of S
    second = float(np.sum(grid_s[:-1] * (grid_t[1:] ** 2 - grid_t[:-1] ** 2)))  # 2 int t S
    out = {"mean": mean, "standard_deviation": math.sqrt(max(second - mean * mean, 0.0)),
           "unseen_tail": float(grid_s[-1])}
    for q in (0.1, 0.5, 0.9):
        # the first time S falls to 1 - q; not seen when the tail left unseen is larger
        k = int(np.searchsorted(-grid_s, -(1.0 - q) - 1e-12, side="left"))
        out[f"t{int(q * 100)}"] = float(grid_t[k]) if k < len(grid_t) else math.nan
    return out


def closed_vessel_variance(tau: float, peclet: float) -> float:
    """The variance (s^2) of the closed vessel's E(t): tau^2 (2/Pe - 2/Pe^2 (1 - e^-Pe))."""
    return tau * tau * (2.0 / peclet - 2.0 / peclet ** 2 * (1.0 - math.exp(-peclet)))


def dispersion_law(machine, axial_slope: float):
    """(hold-ups kg/m, D_ax m^2/s) of a map with the axial_dispersion figure, at the design
    slope (interpolated between the mapped inclines as every figure); None without it. Below
    the lowest mapped hold-up D_ax is held at its value there (not drawn to 0: an empty
    machine has no bed to disperse, but the last metre before a free discharge has one)."""
    from .machine import _interpolate_figure
    holdups, values = _interpolate_figure(machine, "axial_dispersion", axial_slope)
    holdups, values = holdups[1:], values[1:]          # without the (0, 0) anchor
    keep = np.isfinite(values) & (values > 0.0)
    if not np.any(keep):
        return None
    return holdups[keep], values[keep]


def machine_rtd(machine, answer, axial_slope: float,
                inlet_temperature: float | None = None, inlet=None) -> dict | None:
    """The residence-time distribution of a marched machine (``answer``: app/machine.py's, its
    hold-up profile) with the map's D_ax: E(t), its mean, variance and 10/50/90 % times; with
    ``inlet_temperature`` (K) and an outlet temperature from the march, the distribution of
    the outlet temperatures: a parcel that stays t cools as the bed does over the fraction
    t / tau of the machine's NTU (T = T_wall + (T_in - T_wall) exp(-NTU t / tau)), so the
    mixed outlet (the E-weighted mean) is warmer than the plug's. None without D_ax.
    ``inlet``: (x0, x1) m where the feed falls (residence_time_distribution)."""
    law = dispersion_law(machine, axial_slope)
    if law is None:
        return None
    prof = answer.profile
    d = np.interp(prof.holdup, *law)
    rtd = residence_time_distribution(prof.x, prof.holdup, d, answer.feed, inlet=inlet)
    out = {"rtd": rtd, "dispersion": d}
    walls = list(machine.wall_temperatures.values())
    if inlet_temperature is not None and answer.outlet_temperature is not None and walls:
        mixed, quantiles = outlet_temperatures(rtd, answer.residence_time, inlet_temperature,
                                               walls[0], answer.outlet_temperature)
        out["outlet_temperature_mixed"] = mixed
        out["outlet_temperature_quantiles"] = quantiles
    return out


def outlet_temperatures(rtd: ResidenceTimes, tau: float, inlet: float, wall: float,
                        plug_outlet: float) -> tuple[float, dict]:
    """(the mixed outlet temperature, {0.1, 0.5, 0.9: the parcels' temperature quantiles}), K,
    of parcels leaving by ``rtd``: a parcel that stays t cools over the fraction t / ``tau``
    (s) of the machine's NTU, ln((T_in - T_wall) / (T_plug - T_wall)), ``plug_outlet`` being
    the march's outlet at the mean residence."""
    ntu = math.log((inlet - wall) / (plug_outlet - wall))
    temps = wall + (inlet - wall) * np.exp(-ntu * rtd.time / tau)
    weights = rtd.density * np.gradient(rtd.time)
    weights = weights / weights.sum()
    order = np.argsort(temps)
    cumulative = np.cumsum(weights[order])
    quantiles = {q: float(np.interp(q, cumulative, temps[order])) for q in (0.1, 0.5, 0.9)}
    return float(np.sum(weights * temps)), quantiles


def rtd_report(machine, out: dict, axial_slope: float, inlet_temperature=None,
               plot=None, inlet=None) -> tuple[str, list]:
    """A Markdown table of each feed's RTD (and outlet temperatures) for ``taichi-dem machine``
    and the JSON rows; ``plot``: a path for E(t) of every feed; ``inlet``: (x0, x1) m where the
    feed falls, as the march was given it (machine_rtd). ("", []) without D_ax."""
    rows, lines = [], []
    curves = []
    for ans in out["feeds"]:
        got = machine_rtd(machine, ans, axial_slope, inlet_temperature, inlet=inlet)
        if got is None:
            return "", []
        r = got["rtd"]
        row = {"feed_kg_per_s": ans.feed, "mean_s": r.mean, "variance_s2": r.variance,
               "t10_s": r.t10, "t50_s": r.t50, "t90_s": r.t90,
               "axial_dispersion_m2_per_s": [float(got["dispersion"].min()),
                                             float(got["dispersion"].max())]}
        cell_t = ""
        if "outlet_temperature_mixed" in got:
            qs = got["outlet_temperature_quantiles"]
            row["outlet_temperature_mixed_K"] = got["outlet_temperature_mixed"]
            row["outlet_temperature_K_quantiles"] = {str(k): v for k, v in qs.items()}
            cell_t = (f" | {got['outlet_temperature_mixed'] - 273.15:.4g} | "
                      f"{qs[0.1] - 273.15:.4g} / {qs[0.5] - 273.15:.4g} / {qs[0.9] - 273.15:.4g}")
        rows.append(row)
        curves.append((ans.feed, r))
        lines.append(f"| {ans.feed * 3.6:.4g} | {r.mean:.4g} | {math.sqrt(r.variance):.3g} | "
                     f"{r.t10:.4g} / {r.t50:.4g} / {r.t90:.4g} | "
                     f"{got['dispersion'].min():.2g} - {got['dispersion'].max():.2g}{cell_t} |")
    temp_head = (" | mixed outlet (C) | outlet 10/50/90 % (C)" if "outlet_temperature_mixed_K"
                 in rows[0] else "")
    head = ["## Residence-time distributions (axial dispersion model, D_ax from the map)", "",
            "(the maps' noise in D_ax is not carried into these figures)", "",
            "| feed (t/h) | mean (s) | standard deviation (s) | 10 / 50 / 90 % out by (s) | "
            f"D_ax along the machine (m^2/s){temp_head} |",
            "|---" * (5 + (2 if temp_head else 0)) + "|"]
    if plot is not None:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4))
        for feed, r in curves:
            ax.plot(r.time, r.density, label=f"{feed * 3.6:.3g} t/h")
        ax.set_xlabel("residence time (s)")
        ax.set_ylabel("E(t) (1/s)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(plot, dpi=100)
        plt.close(fig)
    return "\n".join(head + lines), rows
