"""When a sampled series has reached its statistical steady state, and how well its mean is
known there: the figures a periodic slice reports (axial mass flow, torque per metre, ...)
come from the steady part of a run, with a standard error, never from a guessed window.

- **Where the steady state starts** (``steady_start``): MSER-5, the marginal standard error rule
  (White 1997, Simulation 69:323; White, Cobb & Spratt 2000, WSC): the series is batched in
  means of 5 and the warm-up cut at the batch d that minimises
  MSER(d) = sum_{j>d} (y_j - mean_{j>d} y)^2 / (k - d)^2 over the k batches: the cut that
  trades the bias of a transient kept against the variance of data thrown away. The cut is
  sought in the first half of the series; a minimum at the end of that range (still falling)
  means no steady state was reached (a drift, a transient longer than half the run): None,
  not a number.
- **The standard error of its mean** (``block_standard_error``): blocking (Flyvbjerg &
  Petersen 1989, J. Chem. Phys. 91:461): the series is averaged in pairs again and again; the
  naive standard error of the block means grows while the blocks are shorter than the
  series' correlation time and levels off once they are longer. The plateau is taken at the
  first level whose estimate the next levels do not exceed by more than their own
  uncertainty, with at least ``min_blocks`` blocks left.
- ``steady_mean(values)``: both, as a ``SteadyMean``.

Pure numpy; nothing here reads a simulation.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

MSER_BATCH = 5          # MSER-5: White, Cobb & Spratt (2000)
MIN_BLOCKS = 8          # blocking stops with fewer block means than this (their spread is noise)


def steady_start(values, batch: int = MSER_BATCH) -> Optional[int]:
    """Index of the first sample of the steady part of ``values`` (1-D, equally spaced
    samples), by MSER-``batch``; None when the rule's cut falls at the end of the first half
    (MSER still falling: no steady state within the run) or there are fewer than 4 batches."""
    x = np.asarray(values, dtype=float)
    k = len(x) // batch
    if k < 4:
        return None
    # batch means of the first k * batch samples (a partial last batch is left out)
    y = x[: k * batch].reshape(k, batch).mean(axis=1)
    # MSER(d) for d = 0 .. k-2 from suffix sums: the mean and spread of y[d:]
    suffix_sum = np.cumsum(y[::-1])[::-1]
    suffix_sq = np.cumsum((y * y)[::-1])[::-1]
    remaining = np.arange(k, 0, -1, dtype=float)             # k - d
    mean = suffix_sum / remaining
    spread = np.maximum(suffix_sq - remaining * mean * mean, 0.0)
    mser = spread / remaining ** 2
    # the cut is sought in the first half only (White et al.: the statistic of a short tail
    # is noise); a minimum at the end of that range means MSER was still falling: the series
    # drifts, or its transient outlasts half the run
    half = k // 2
    d = int(np.argmin(mser[: half + 1]))
    if d >= int(0.9 * half):
        return None
    return d * batch


@dataclass(frozen=True)
class BlockError:
    """The standard error of a series' mean by blocking: ``standard_error`` (the series'
    unit), ``block_size`` (samples per block at the plateau), ``blocks`` (independent block
    means there), ``converged`` (False: no plateau before MIN_BLOCKS blocks were left; the
    largest estimate is given, an underestimate if the correlation time is longer)."""
    standard_error: float
    block_size: int
    blocks: int
    converged: bool


def block_standard_error(values, min_blocks: int = MIN_BLOCKS) -> BlockError:
    """Standard error of the mean of ``values`` (correlated samples), by blocking."""
    x = np.asarray(values, dtype=float)
    n = len(x)
    if n < 2:
        raise ValueError(f"the standard error of a mean needs two samples or more, got {n}")
    levels = []           # (estimate, its uncertainty, block size, blocks)
    size = 1
    while len(x) >= min_blocks:
        m = len(x)
        estimate = math.sqrt(float(np.var(x, ddof=1)) / m)
        # the uncertainty of a standard error from m independent values: se / sqrt(2 (m - 1))
        levels.append((estimate, estimate / math.sqrt(2.0 * (m - 1)), size, m))
        x = 0.5 * (x[: m // 2 * 2:2] + x[1: m // 2 * 2:2])
        size *= 2
    if not levels:
        m = len(x)
        return BlockError(math.sqrt(float(np.var(x, ddof=1)) / m), 1, m, False)
    for i, (estimate, _, size, blocks) in enumerate(levels):
        later = levels[i + 1:]
        if later and all(e - u <= estimate for e, u, _, _ in later):
            return BlockError(estimate, size, blocks, True)
    # no level the later ones agree with: the largest estimate, flagged
    estimate, _, size, blocks = max(levels)
    return BlockError(estimate, size, blocks, False)


@dataclass(frozen=True)
class SteadyMean:
    """A series' steady-state mean: ``mean`` and ``standard_error`` (its unit), the first
    steady sample ``start`` (index), the samples averaged ``samples``, and the blocking's
    ``block_size``, ``blocks`` and ``converged``. ``steady`` False: no steady state was
    detected, and ``mean`` is that of the second half, reported only to be looked at."""
    mean: float
    standard_error: float
    start: int
    samples: int
    block_size: int
    blocks: int
    converged: bool
    steady: bool

    def __str__(self) -> str:
        flag = "" if self.steady else " (not steady)"
        return f"{self.mean:.6g} +- {self.standard_error:.2g}{flag}"


def steady_mean(values, batch: int = MSER_BATCH, min_blocks: int = MIN_BLOCKS) -> SteadyMean:
    """The steady part of ``values`` (MSER) and its mean with a blocking standard error."""
    x = np.asarray(values, dtype=float)
    if len(x) < 2:
        raise ValueError(f"a steady mean needs two samples or more, got {len(x)}")
    start = steady_start(x, batch)
    steady = start is not None
    if start is None:
        start = len(x) // 2
    tail = x[start:]
    error = block_standard_error(tail, min_blocks)
    return SteadyMean(float(np.mean(tail)), error.standard_error, start, len(tail),
                      error.block_size, error.blocks, error.converged, steady)
