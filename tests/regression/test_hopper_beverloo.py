"""Regression: discharge of a conical hopper against Beverloo's correlation, three orifices.

Beverloo, Leniger & van de Velde (1961), Chem. Eng. Sci. 15:260, for a circular orifice D in a
flat-bottomed bin of particles of diameter d:

    W = C rho_b sqrt(g) (D - k d)^(5/2)

with C = 0.58 and k = 1.4 in their fit; Nedderman, Tuzun, Savage & Houlsby (1982), Chem. Eng.
Sci. 37:1597 (and Nedderman 1992, Statics and Kinematics of Granular Materials, ch. 10) review
0.55 < C < 0.65 and k of about 1.5 for spheres. The hopper here is a cylindrical bin (radius
0.1 m = 20 d) on a cone of 60 deg half-angle: funnel flow with a stagnant zone over the cone, the
flat-bottomed flow Beverloo fitted. Spheres d = 10 mm (glass, E softened to 5 MPa), orifices
D/d = 5.5, 6.5 and 7.5 (the bin stays wider than 2.5 D, Nedderman's limit for wall effects;
below D/d of about 5 frictional spheres jam). 4000 spheres start on a loose lattice (settled in
0.2 s); the rate is the slope of the discharged mass (particles leaving the domain below the
orifice) over t = 0.3 - 0.8 s, while the head over the orifice stays above 6 cm; rho_b is the
solid fraction measured in the bin times the solid density.

Glass beads: friction 0.3 (particle and wall), restitution 0.5.

MEASURED (f32; `python tests/regression/test_hopper_beverloo.py 1,2,3`; W in kg/s, C per orifice
with the exponent held at 5/2 and k = 1.5, rho_b from the measured solid fraction 0.60 - 0.61):

    seed  W(5.5)  W(6.5)  W(7.5)   C(5.5) C(6.5) C(7.5)  mean C   n (k=1.5)  n (k=1.0)  n (k=2.0)
    1     0.873   1.489   2.364    0.571  0.561  0.570   0.567    2.454      2.707      2.201
    2     0.921   1.494   2.269    0.609  0.560  0.546   0.572    2.221      2.450      1.992
    3     0.883   1.459   2.323    0.582  0.547  0.557   0.562    2.382      2.627      2.135

n: mean 2.35, sd 0.12 over seeds; the rates are consistent with n = 5/2 for k of about 1.2. C:
0.546 - 0.609 per orifice (sd 0.02), mean of the three 0.562 - 0.572 (sd 0.005).

Five more realizations (2026-12-05, Taichi's IR optimisation off, ``TAICHI_DEM_OPT_LEVEL=0``:
the same arithmetic to round-off - positions agree to 3e-13 m after 1500 steps in f64 - so a
realization that differs only in round-off; the same command with seeds 1-5):

    seed  C(5.5) C(6.5) C(7.5)  mean C   n (k=1.5)
    1     0.548  0.553  0.548   0.550    2.483
    2     0.581  0.558  0.560   0.566    2.390
    3     0.565  0.577  0.550   0.564    2.433
    4     0.592  0.551  0.554   0.566    2.336
    5     0.567  0.555  0.534   0.552    2.324

Over all eight the mean C of the three orifices is 0.562 with sd 0.0075 (the three seeds above
had understated it); per orifice 0.534 - 0.609. At friction 0.5
(seed 1) the rates were 10 - 15 % lower: C = 0.52 - 0.56, n = 2.29 - Beverloo's C depends on
friction, and the published range is for real beads, whose friction is nearer 0.3.

Checks, with k = 1.5 held:
1. the exponent n of a power-law fit W ~ (D - k d)^n is 5/2 within 0.45: refitting the same rates
   with k = 1.0 or 2.0 instead of 1.5 moves n by -/+ 0.24 (k is not known better than that), and n
   scatters with sd 0.12 over seeds; 0.24 + 2 sd ~ 0.45.
2. the mean C of the three orifices lies in the published 0.55 - 0.65 widened by 2.5 sd of
   its scatter over realizations (0.019: 0.531 - 0.669; measured 0.550 - 0.572 over eight);
   each orifice's C within 0.50 - 0.70 (the range widened by 2.5 sd of the per-orifice
   scatter).
A rate that did not scale with the orifice (e.g. contacts lost at the cone, a jam) or a wrong
bulk flow (friction, gravity) fails these.
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

import pytest

import taichi_dem
from taichi_dem.app import analysis

pytestmark = pytest.mark.slow         # part of the default suite; -m "not slow" skips it

D_P = 0.010                    # m, sphere diameter
BIN_RADIUS = 0.1               # m
HALF_ANGLE = 60.0              # deg, cone half-angle from the vertical
RATIOS = (5.5, 6.5, 7.5)       # D / d
COUNT = 4000
WINDOW = (0.3, 0.8)            # s
RHO_S = 2500.0
FRICTION = 0.3
G = 9.81


def lattice_fill(radius: float, z0: float, count: int, d: float, rng, spacing=1.05) -> np.ndarray:
    """Sphere centres on a square lattice (pitch 1.05 d, jittered by 2 % of d) filling a
    vertical cylinder from z0 upwards, layer by layer: a loose start that settles in 0.2 s."""
    s = spacing * d
    n = int(radius / s) + 1
    g = np.arange(-n, n + 1) * s
    x, y = np.meshgrid(g, g)
    inside = np.hypot(x, y) <= radius - 0.55 * d
    xy = np.stack([x[inside], y[inside]], 1)
    layers = math.ceil(count / len(xy))
    pts = np.concatenate([np.column_stack([xy, np.full(len(xy), z0 + k * s)])
                          for k in range(layers)])[:count]
    return pts + rng.uniform(-0.02 * d, 0.02 * d, pts.shape)


def hopper_scene(ratio: float, seed: int, directory: Path) -> str:
    orifice = ratio * D_P
    cone = (BIN_RADIUS - orifice / 2) / math.tan(math.radians(HALF_ANGLE))
    pts = lattice_fill(BIN_RADIUS, cone + 0.5 * D_P + 0.002, COUNT, D_P, np.random.default_rng(seed))
    top = float(pts[:, 2].max()) + D_P
    fill = directory / f"hopper_fill_{seed}.csv"
    fill.write_text("x,y,z,radius\n" + "".join(
        f"{float(p[0])!r},{float(p[1])!r},{float(p[2])!r},{D_P / 2!r}\n" for p in pts))
    return f"""
[simulation]
end_time = {WINDOW[1]}
dt = 1e-4
gravity = [0.0, 0.0, -{G}]
precision = "f32"
seed = {seed}

[domain]
min = [-{BIN_RADIUS + 0.01}, -{BIN_RADIUS + 0.01}, -0.02]
max = [{BIN_RADIUS + 0.01}, {BIN_RADIUS + 0.01}, {top + 0.01}]

[materials.glass]
density = {RHO_S}
youngs_modulus = 5e6
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = {FRICTION}

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = {FRICTION}

[[bodies]]
name = "hopper"
material = "steel"
mesh = {{ builder = "hopper", kind = "conical", height = {cone!r}, top_radius = {BIN_RADIUS}, orifice_radius = {orifice / 2!r}, bin_height = {top - cone!r}, axis_direction = [0, 0, 1] }}

[[particles]]
material = "glass"
file = "{fill.name}"

[output]
interval = 0.02
"""


def discharge(ratio: float, seed: int, directory: Path) -> dict:
    """Run one orifice: the discharge rate (kg/s) over WINDOW and the bin's solid fraction."""
    t0 = time.perf_counter()
    orifice = ratio * D_P
    cone = (BIN_RADIUS - orifice / 2) / math.tan(math.radians(HALF_ANGLE))
    phis = []
    with taichi_dem.Simulation.from_text(hopper_scene(ratio, seed, directory),
                                         base_dir=str(directory)) as sim:
        while sim.time < WINDOW[1] - 1e-9:
            sim.step(sim.output_every * 5)
            if sim.time >= WINDOW[0] - 1e-9:
                p = sim.particles()
                z = p["position"][:, 2]
                surface = float(np.percentile(z, 98))
                phis.append(analysis.solid_fraction_in_cylinder(
                    p, BIN_RADIUS - 2 * D_P, cone + 2 * D_P, surface - 2 * D_P))
        t, out = analysis.discharged_mass(sim)
        rate = analysis.linear_rate(t, out, *WINDOW)
    return dict(ratio=ratio, rate=rate, phi=float(np.mean(phis)), wall=time.perf_counter() - t0)


def beverloo_fit(runs: list[dict], k: float = analysis.BEVERLOO_K) -> dict:
    """Exponent of W against (D - k d), and C per orifice with the exponent held at 5/2."""
    x = np.array([(r["ratio"] - k) * D_P for r in runs])
    w = np.array([r["rate"] for r in runs])
    n, _ = analysis.fit_power_law(x, w)
    rho_b = np.array([r["phi"] * RHO_S for r in runs])
    c = w / (rho_b * math.sqrt(G) * x ** 2.5)
    return dict(n=n, C=c)


def test_hopper_discharge_follows_beverloo(tmp_path):
    runs = [discharge(ratio, 1, tmp_path) for ratio in RATIOS]
    fit = beverloo_fit(runs)
    for r, c in zip(runs, fit["C"]):
        w_bev = analysis.beverloo_rate(r["ratio"] * D_P, D_P, r["phi"] * RHO_S, G)
        print(f"\n  D/d = {r['ratio']}: W = {r['rate']:.4f} kg/s, solid fraction {r['phi']:.3f}, "
              f"Beverloo (C 0.58, k 1.5) {w_bev:.4f} kg/s, C = {c:.3f} ({r['wall']:.0f} s wall)", end="")
    lo, hi = beverloo_fit(runs, 1.0)["n"], beverloo_fit(runs, 2.0)["n"]
    print(f"\n  exponent of (D - 1.5 d): {fit['n']:.3f} (with k = 1.0: {lo:.3f}, k = 2.0: {hi:.3f})")
    print(f"  mean C {np.mean(fit['C']):.3f}")
    assert abs(fit["n"] - 2.5) < 0.45
    # the published range, widened by 2.5 sd (0.0075) of one realization's mean C (docstring)
    scatter = 2.5 * 0.0075
    assert (analysis.BEVERLOO_C_RANGE[0] - scatter < np.mean(fit["C"])
            < analysis.BEVERLOO_C_RANGE[1] + scatter)
    assert np.all((fit["C"] > 0.50) & (fit["C"] < 0.70))


if __name__ == "__main__":
    # the scatter over seeds quoted in the docstring: python tests/regression/test_hopper_beverloo.py 1,2,3
    import tempfile
    seeds = [int(s) for s in (sys.argv[1] if len(sys.argv) > 1 else "1,2,3").split(",")]
    ns, cs = [], []
    with tempfile.TemporaryDirectory() as d:
        for seed in seeds:
            runs = [discharge(ratio, seed, Path(d)) for ratio in RATIOS]
            fit = beverloo_fit(runs)
            ns.append(fit["n"])
            cs.append(fit["C"])
            print(f"seed {seed}: " + ", ".join(f"D/d {r['ratio']}: W {r['rate']:.4f} kg/s phi {r['phi']:.3f} "
                                                f"C {c:.3f} ({r['wall']:.0f} s)" for r, c in zip(runs, fit["C"]))
                  + f"; n = {fit['n']:.3f} (k 1.0: {beverloo_fit(runs, 1.0)['n']:.3f}, "
                    f"k 2.0: {beverloo_fit(runs, 2.0)['n']:.3f})", flush=True)
    print(f"n: mean {np.mean(ns):.3f} sd {np.std(ns, ddof=1) if len(ns) > 1 else 0:.3f}; "
          f"C: mean {np.mean(cs):.3f} range {np.min(cs):.3f} - {np.max(cs):.3f}")
