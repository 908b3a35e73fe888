"""Response surfaces (weighted least squares, the model no richer than the points support) and
the optimum that meets the targets within their scatter."""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .spec import REGULARISATION, Spec, _n_coefficients


def design_matrix(x: np.ndarray, model: str) -> np.ndarray:
    """Columns of the response surface at scaled points ``x`` (n, d): 1, x_i, and for
    ``quadratic`` also x_i^2 and x_i x_j (i < j)."""
    x = np.atleast_2d(np.asarray(x, float))
    n, d = x.shape
    cols = [np.ones(n)]
    if model in ("linear", "quadratic"):
        cols += [x[:, i] for i in range(d)]
    if model == "quadratic":
        cols += [x[:, i] ** 2 for i in range(d)]
        cols += [x[:, i] * x[:, j] for i in range(d) for j in range(i + 1, d)]
    return np.column_stack(cols)


MODELS = ("constant", "linear", "quadratic")   # from the simplest: ties go to the simpler


@dataclass
class Surface:
    """A least-squares response surface in scaled parameters (each range mapped to [-1, 1]).
    ``r2``: coefficient of determination; ``residual_sd``: sqrt(SS_res / (n - p)) over the
    individual runs, in the response's unit (NaN with no residual degrees of freedom); ``n``:
    runs; ``points``: distinct points; ``loo_rmse``: the leave-one-point-out prediction error
    (weighted by each point's runs; NaN when not computed); ``pure_sd``: the run-to-run scatter
    at repeated points (NaN without repeats); ``cov``: the coefficients' covariance (None
    without residual degrees of freedom)."""
    model: str
    coef: np.ndarray
    r2: float
    residual_sd: float
    n: int
    points: int = 0
    loo_rmse: float = math.nan
    pure_sd: float = math.nan
    cov: Optional[np.ndarray] = None
    tried: dict = field(default_factory=dict)     # {model: leave-one-out rmse} of the candidates

    def __call__(self, x) -> np.ndarray:
        return design_matrix(x, self.model) @ self.coef

    def se(self, x) -> np.ndarray:
        """The standard error of the surface's value at scaled points ``x`` (the response's
        unit): sqrt(a^T cov a); NaN without a covariance."""
        a = design_matrix(x, self.model)
        if self.cov is None:
            return np.full(len(a), math.nan)
        return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", a, self.cov, a), 0.0))


def _group(x: np.ndarray, y: np.ndarray):
    """Repeated runs at one point pooled: (distinct points (m, d), mean response, runs per
    point, pure-error sum of squares, its degrees of freedom). NaN responses left out."""
    ok = np.isfinite(y)
    x, y = x[ok], y[ok]
    if len(y) == 0:
        return x, y, np.zeros(0), 0.0, 0
    keys = [tuple(np.round(r, 9)) for r in x]
    order = {}
    for k in keys:
        order.setdefault(k, len(order))
    idx = np.array([order[k] for k in keys])
    m = len(order)
    w = np.bincount(idx, minlength=m).astype(float)
    ybar = np.bincount(idx, weights=y, minlength=m) / w
    xs = np.zeros((m, x.shape[1]))
    xs[idx] = x
    ss_pure = float(np.sum((y - ybar[idx]) ** 2))
    return xs, ybar, w, ss_pure, int(len(y) - m)


def _wls(xs, ybar, w, model):
    a = design_matrix(xs, model)
    sw = np.sqrt(w)
    coef, *_ = np.linalg.lstsq(a * sw[:, None], ybar * sw, rcond=None)
    return a, coef


def loo_rmse(xs: np.ndarray, ybar: np.ndarray, w: np.ndarray, model: str) -> float:
    """Leave-one-point-out prediction error of ``model``: each distinct point (with all its
    runs) left out in turn, the weighted surface refitted on the others and its error there;
    the root of the mean squared error weighted by the points' runs. NaN when the others cannot
    determine the model (fewer points than coefficients + 1)."""
    m, d = xs.shape
    p = _n_coefficients(d, model)
    if m < p + 1:
        return math.nan
    err = np.empty(m)
    for i in range(m):          # m is a design's size (tens): a refit per point is cheap
        keep = np.arange(m) != i
        a, coef = _wls(xs[keep], ybar[keep], w[keep], model)
        if np.linalg.matrix_rank(a) < p:
            return math.nan
        err[i] = ybar[i] - float((design_matrix(xs[i:i + 1], model) @ coef)[0])
    return float(math.sqrt(np.sum(w * err ** 2) / np.sum(w)))


def fit_surface(x: np.ndarray, y: np.ndarray, model: Optional[str] = None) -> Surface:
    """Weighted least squares of the responses ``y`` at scaled points ``x`` (n, d): repeated
    runs at a point enter as their mean weighted by their number (the same coefficients as
    every run on its own). ``model``: "constant", "linear" or "quadratic"; None: the richest
    the points allow (quadratic when the distinct points leave it residual degrees of freedom,
    else linear when they determine it, else the mean). NaN responses are left out."""
    x = np.atleast_2d(np.asarray(x, float)).reshape(len(y), -1)
    y = np.asarray(y, float)
    d = x.shape[1]
    xs, ybar, w, ss_pure, df_pure = _group(x, y)
    m, n = len(ybar), int(np.sum(w))
    if m == 0:
        return Surface("constant", np.array([math.nan]), math.nan, math.nan, 0)
    if model is None:
        if d > 0 and m > _n_coefficients(d, "quadratic"):
            model = "quadratic"
        elif d > 0 and m >= _n_coefficients(d, "linear"):
            model = "linear"
        else:
            model = "constant"
    a, coef = _wls(xs, ybar, w, model)
    p = a.shape[1]
    ss_lack = float(np.sum(w * (ybar - a @ coef) ** 2))
    ss_res = ss_lack + ss_pure                       # over the individual runs
    ymean = float(np.sum(w * ybar) / n)
    ss_tot = float(np.sum(w * (ybar - ymean) ** 2)) + ss_pure
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else math.nan
    sd = math.sqrt(ss_res / (n - p)) if n > p else math.nan
    cov = None
    if n > p and np.linalg.matrix_rank(a) == p:
        cov = sd ** 2 * np.linalg.pinv(a.T @ (a * w[:, None]))
    pure = math.sqrt(ss_pure / df_pure) if df_pure > 0 else math.nan
    return Surface(model, coef, r2, sd, n, m, loo_rmse(xs, ybar, w, model), pure, cov)


def choose_surface(x: np.ndarray, y: np.ndarray) -> Surface:
    """The surface no richer than the points support: among constant, linear and quadratic
    (each fitted by :func:`fit_surface`), the one with the smallest leave-one-point-out
    prediction error (:func:`loo_rmse`), the simpler on a tie; a model the points cannot
    cross-validate (fewer distinct points than its coefficients + 1) is not a candidate.
    With too few points for any cross-validation, the richest model they allow."""
    x = np.atleast_2d(np.asarray(x, float)).reshape(len(y), -1)
    d = x.shape[1]
    fits = {m: fit_surface(x, y, m) for m in (MODELS if d > 0 else ("constant",))}
    scored = {m: s.loo_rmse for m, s in fits.items() if math.isfinite(s.loo_rmse)}
    if not scored:
        return fit_surface(x, y)
    best = min(scored, key=lambda m: (round(scored[m], 12), MODELS.index(m)))
    out = fits[best]
    out.tried = scored
    return out


def _starts(d: int, rng_seed: int = 0) -> np.ndarray:
    if d == 0:
        return np.zeros((1, 0))
    if d <= 3:
        g = np.linspace(-1, 1, 5)
        return np.array(list(itertools.product(*([g] * d))))
    return np.random.default_rng(rng_seed).uniform(-1, 1, (60, d))


def _minimise(fun, d: int) -> tuple[np.ndarray, float]:
    from scipy.optimize import minimize
    if d == 0:
        x = np.zeros(0)
        return x, float(fun(x))
    best = (None, math.inf)
    for s in _starts(d):
        r = minimize(fun, s, method="L-BFGS-B", bounds=[(-1.0, 1.0)] * d)
        if r.fun < best[1]:
            best = (np.clip(r.x, -1, 1), float(r.fun))
    return best


def optimise(surfaces: list[Surface], targets: list[float], sds: list[float], d: int,
             prefer: Optional[np.ndarray] = None) -> tuple[np.ndarray, float]:
    """The scaled point in [-1, 1]^d minimising sum(((surface - target) / sd)^2), and that sum.
    Among points that fit equally (more parameters than tests) the one nearest ``prefer``
    (scaled) is taken: a pull of weight REGULARISATION per unit squared distance."""
    prefer = np.zeros(d) if prefer is None else np.asarray(prefer, float)

    def chi2(x):
        x = np.asarray(x, float).reshape(1, d)
        return float(sum(((s(x)[0] - t) / sd) ** 2 for s, t, sd in zip(surfaces, targets, sds)))

    x, _ = _minimise(lambda x: chi2(x) + REGULARISATION * float(np.sum((x - prefer) ** 2)), d)
    return x, chi2(x)


def reachable(surface: Surface, d: int) -> tuple[float, float]:
    """(lowest, highest) value of ``surface`` inside [-1, 1]^d."""
    lo = _minimise(lambda x: float(surface(np.reshape(x, (1, d)))[0]), d)[1]
    hi = -_minimise(lambda x: -float(surface(np.reshape(x, (1, d)))[0]), d)[1]
    return lo, hi


def scale(spec: Spec, point: dict) -> np.ndarray:
    """A design point's continuous parameters mapped to [-1, 1]."""
    return np.array([2.0 * (point[p.key] - p.low) / (p.high - p.low) - 1.0 for p in spec.parameters])


def unscale(spec: Spec, x: np.ndarray) -> dict:
    return {p.key: p.low + 0.5 * (xi + 1.0) * (p.high - p.low) for p, xi in zip(spec.parameters, x)}


# ------------------------------------------------------------------------------ running
def _stats(values) -> tuple[float, float]:
    v = np.asarray([x for x in values if np.isfinite(x)], float)
    if len(v) == 0:
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if len(v) > 1 else math.nan
