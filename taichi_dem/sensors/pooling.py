"""Samples whose output interval is short are pooled with the sample before them, so that no
sample's rates or counts stand for less than a full output interval.

Why: a run that stops between two regular samples (``end_time`` not a whole number of sample
steps, or dt not dividing the output interval) closes with a sample at its last instant. Its
interval may be a few steps long. A rate over a few steps is a sound estimate of the rate but a
noisy one: a mass-flow plane that nothing crossed in 1.9 ms reads 0 kg/s, one that a single
sphere crossed reads ten times the feed. A plain mean over a window counts that sample as a
full one, so one short sample moves a windowed mean by up to 1/n of itself (the hot-cooler
tutorial's outlet flow read 15.9 t/h instead of 13.2). Pooled, the short sample's value is
the one over its own interval and the interval before it: an interval at least as long as the
output interval, so every sample of a rate series carries (at least) a full interval's weight.

What is pooled is declared with each series (``Series.interval`` in sensors/series.py):
"mean" (a time mean, a rate), "total" (an amount in the interval, given for one nominal output
interval once pooled), "weighted" (a mean over what the interval saw, weighted by a sibling
series' amount). The series ``sample_interval`` (s) says what each sample covers, so that means
weighted by it are exact too. Plain Python (numpy).
"""
from __future__ import annotations

import functools
import math
from typing import Optional

import numpy as np

from .units import declaration


@functools.lru_cache(maxsize=4096)
def _kind(name: str) -> tuple[str, str]:
    d = declaration(name)
    return (d.interval, d.weight) if d is not None else ("", "")


def amounts(values: dict, interval: float) -> dict:
    """{series name: [numerator, denominator]} of every interval series in ``values`` (a
    sample's values over ``interval`` s): the value is numerator / denominator ("total" series:
    times the nominal interval). NaN values contribute nothing."""
    out = {}
    for name, v in values.items():
        kind, weight = _kind(name)
        if kind not in ("mean", "total", "weighted"):
            continue
        a = np.asarray(v, dtype=np.float64)
        if kind == "weighted":
            # the weight is the sibling's amount in the interval (a rate's: rate x interval)
            sibling = name.rsplit("/", 1)[0] + "/" + weight
            w = abs(float(values.get(sibling, 0.0)))
            if _kind(sibling)[0] == "mean":
                w *= interval
        else:
            w = interval
        if not np.all(np.isfinite(a)) or w <= 0.0:
            out[name] = [np.zeros_like(a).tolist(), 0.0]
        elif kind == "total":
            out[name] = [a.tolist(), w]
        else:
            out[name] = [(a * w).tolist(), w]
    return out


def pool(values: dict, interval: float, previous: dict, nominal: float) -> dict:
    """Replace, in ``values`` (a sample over ``interval`` s), each interval series by its value
    over this interval and the one before it (``previous``: that sample's ``amounts``); "total"
    series are given per ``nominal`` s. Returns the pooled amounts (to pool a next short sample
    with)."""
    here = amounts(values, interval)
    pooled = {}
    for name, (num, den) in here.items():
        p_num, p_den = previous.get(name, (0.0, 0.0))
        n = np.asarray(num, dtype=np.float64) + np.asarray(p_num, dtype=np.float64)
        d = den + float(p_den)
        pooled[name] = [n.tolist(), d]
        kind, _ = _kind(name)
        shape = np.shape(values[name])
        if d <= 0.0:
            value = np.full(shape, math.nan) if kind == "weighted" else np.zeros(shape)
        elif kind == "total":
            value = n / d * nominal
        else:
            value = n / d
        values[name] = float(value) if shape == () else value
    return pooled


def should_pool(interval: float, nominal: float, dt: float, previous: Optional[dict]) -> bool:
    """Whether a sample over ``interval`` s is short (more than half a step under the nominal
    output interval) and has a sample before it to pool with."""
    return previous is not None and 0.0 < interval < nominal - 0.5 * dt


def rate_of_cumulative(t: np.ndarray, cumulative: np.ndarray,
                       covered: Optional[np.ndarray] = None) -> tuple[np.ndarray, np.ndarray]:
    """(sample times s, rate per s) of a cumulative series (kg -> kg/s) over what each sample
    covers: its ``sample_interval`` when given (a pooled closing sample: its own interval and
    the one before), else the time since the previous sample. The first sample has no rate."""
    t = np.asarray(t, dtype=np.float64)
    cumulative = np.asarray(cumulative, dtype=np.float64)
    if len(t) < 2:
        return t[:0], cumulative[:0]
    if covered is None or len(covered) != len(t):
        span = np.diff(t)
        return t[1:], np.divide(np.diff(cumulative), span, out=np.zeros_like(span),
                                where=span > 0)
    start = t[1:] - np.asarray(covered, dtype=np.float64)[1:]
    begin = np.interp(start, t, cumulative)
    span = t[1:] - start
    return t[1:], np.divide(cumulative[1:] - begin, span, out=np.zeros_like(span),
                            where=span > 0)


def cumulative_of_rate(t: np.ndarray, rate: np.ndarray,
                       covered: Optional[np.ndarray] = None) -> np.ndarray:
    """The running integral of a rate series (kg/s -> kg) at each sample, exact for interval
    means: each sample adds rate x what it covers (``sample_interval``) to the integral at the
    start of what it covers (a sample time: a pooled sample starts where the one before the
    previous ended). Without ``covered``: rate x the time since the previous sample."""
    t = np.asarray(t, dtype=np.float64)
    rate = np.asarray(rate, dtype=np.float64)
    if covered is None or len(covered) != len(t):
        return np.cumsum(rate * np.diff(t, prepend=t[:1]))
    out = np.zeros_like(rate)
    for i in range(1, len(t)):      # samples, not particles: a short host loop
        start = t[i] - float(covered[i])
        out[i] = float(np.interp(start, t[:i], out[:i])) + rate[i] * float(covered[i])
    return out
