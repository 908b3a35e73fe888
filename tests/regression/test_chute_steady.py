"""Regression: a short, narrow version of the steady chute demo (seed 004's material on its
38 deg slope, fed by a sheet inlet) reaches a steady flow whose outflow equals the feed and
whose depth profile lies where the depth-averaged model puts it.

The case: 1 mm spheres (rho 811.54, E 5.17 MPa, e 0.55, mu 0.4877, mu_r 0.005; basal friction
0.4245) fed through a face 8 mm deep at u0 = 0.5492 m/s onto a chute 60 mm long; 5 mm across,
periodic (the demo's 20 mm has side walls; in a 5-diameter channel their friction would be the
flow's main brake, which the depth-averaged model has no term for). Inflow solid fraction
0.45: mass rate 0.45 x 811.54 x 0.008 x 0.005 x 0.5492 = 8.02 g/s (a 5 mm face carries at most
0.49 with this lattice's edges). About 1,700 spheres in the chute at steady state; run to
0.2 s, averaged over the last 0.08 s (steady from about 0.12 s).

MEASURED (f32, 2 threads; `python tests/regression/test_chute_steady.py 1,2,3`; stations at
x = 20, 40, 60 mm, 10 mm slabs, mean over t = 0.12 - 0.2 s; seed 1 was run to 0.25 s):

    seed  outflow/feed  count drift  h mm              u_mean m/s           flux/feed
    1     0.994         +0.3 %       6.43 5.59 5.25    0.632 0.730 0.811    0.991 0.995 1.004
    2     1.008         -0.2 %       6.39 5.58 5.13    0.632 0.729 0.811    1.005 1.008 0.999
    3     0.996         +0.5 %       6.44 5.59 5.24    0.631 0.730 0.805    1.005 0.999 1.004

    steady depth-averaged model from h0 = 8 mm, u0 = 0.5492 m/s (K = 1):
    delta = 23 deg: h 6.68 5.90 5.36 mm, u 0.657 0.745 0.820 m/s
    delta = 30 deg: h 7.15 6.55 6.09 mm, u 0.615 0.671 0.721 m/s
    DEM u_mean between them (0 on the 30 deg curve, 1 on the 23 deg one): 0.38 - 0.90

Checks and tolerances:
1. steady: the mass flow through x = 60 mm equals the feed within 3 % (measured 0.994 - 1.008,
   sd 0.7 %; ~1,300 spheres leave in the window) and so does the flux sum(m u)/dx at each
   station (0.991 - 1.008); the particle count drifts less than 3 % over the window (< 0.5 %);
   the inlet dropped nothing (behind schedule = 0).
2. the flow thins and accelerates down the slope (h decreasing, u_mean increasing).
3. pinned: h within 0.3 mm and u_mean within 0.02 m/s of the seed-1 - 3 means (5 sd of the
   largest scatter, 0.06 mm and 0.004 m/s; a change in friction, restitution or gravity moves
   them by more: at the inlet's speed, a basal friction of tan 30 deg instead of tan 23 deg
   changes the model's u by 0.04 - 0.1 m/s).
4. the depth-averaged velocity lies strictly between the model's delta = 30 deg and 23 deg curves
   at every station (as seed 004 finds for its free-surface velocities; the closest station is
   4 sd inside). The depth is not compared with the model: the DEM compacts from the inflow's
   0.45 to ~0.5 and is thinner than both curves (the model carries the inflow's density).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pytest

import taichi_dem
from taichi_dem.app.demos import Chute

pytestmark = pytest.mark.slow         # part of the default suite; -m "not slow" skips it

FEED = 0.45 * 811.54 * 0.008 * 0.005 * 0.5492      # kg/s
SCENE = """
[simulation]
end_time = 0.2
dt = 6.0e-6
gravity = [6.0334, 0.0, -7.7225]     # 9.80 m/s2 tilted 38 deg
precision = "f32"
seed = {seed}

[domain]
min = [-0.001, 0.0, -0.001]
max = [0.0605, 0.005, 0.03]
periodic = ["y"]

[materials.grain]
density = 811.54
youngs_modulus = 5.17e6
poisson_ratio = 0.25

[materials.base]
density = 7800.0
youngs_modulus = 5.17e6
poisson_ratio = 0.25

[[interactions]]
pair = ["grain", "grain"]
restitution = 0.55
friction = 0.4877
rolling_friction = 0.005

[[interactions]]
pair = ["grain", "base"]
restitution = 0.55
friction = 0.4245
rolling_friction = 0.005

[[walls]]
name = "base"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "base"

[[walls]]
name = "gate"
plane = {{ point = [0, 0, 0], normal = [1, 0, 0] }}
material = "base"

[[factories]]
name = "inlet"
pattern = "sheet"
material = "grain"
radius = 0.0005
face = {{ point = [0.0, 0.0, 0.0], width = [0.0, 0.005, 0.0], depth = [0.0, 0.0, 0.008] }}
velocity = [0.5492, 0.0, 0.0]
mass_rate = {feed!r}
jitter = 0.03

[[sensors]]
kind = "mass_flow"
name = "outflow"
plane = {{ point = [0.06, 0, 0], normal = [1, 0, 0] }}

[output]
interval = 0.01
"""


class ShortChute(Chute):
    STATIONS = (0.02, 0.04, 0.06)
    START = 0.1
    WINDOW = 0.08


def run_case(seed: int, tmp: Path) -> dict:
    path = tmp / f"short_chute_{seed}.toml"
    path.write_text(SCENE.format(seed=seed, feed=FEED))
    sim = taichi_dem.Simulation.from_toml(str(path), arch="cpu")
    demo = ShortChute()
    demo.attach(sim)
    t0 = time.perf_counter()
    sim.run()
    out = demo.summary(sim)
    out["wall"] = time.perf_counter() - t0
    sim.close()
    return out


def test_short_chute_steady(tmp_path):
    out = run_case(1, tmp_path)
    check(out)


PINNED_H = np.array([6.42, 5.59, 5.21]) * 1e-3     # m, seeds 1 - 3
PINNED_U = np.array([0.632, 0.730, 0.809])          # m/s


def check(out: dict):
    assert abs(out["outflow"] / out["feed"] - 1.0) < 0.03, out
    assert np.all(np.abs(out["flux"] / out["feed"] - 1.0) < 0.03), out["flux"]
    assert abs(out["count_drift"]) < 0.03 and out["behind"] == 0.0
    # the feed is the scheduled rate: nothing dropped, and half a layer (28 spheres, 12 ug) at
    # each end of the window's 0.64 g is 1.9 %
    assert out["feed"] == pytest.approx(FEED, rel=0.025)
    assert np.all(np.diff(out["h"]) < 0) and np.all(np.diff(out["u_mean"]) > 0)
    assert np.all(np.abs(out["h"] - PINNED_H) < 0.3e-3), out["h"]
    assert np.all(np.abs(out["u_mean"] - PINNED_U) < 0.02), out["u_mean"]
    pos = out["position"]["u_mean"]
    assert np.all((pos > 0.0) & (pos < 1.0)), pos
    # (the model itself: at the inlet its two curves start from the same state)
    m23, m30 = out["models"][23.0], out["models"][30.0]
    assert np.all(m23["u"] > m30["u"]) and np.all(m23["h"] < m30["h"])
    assert np.allclose(m23["h"] * m23["u"], 0.008 * 0.5492)


if __name__ == "__main__":
    import tempfile
    seeds = [int(s) for s in (sys.argv[1] if len(sys.argv) > 1 else "1").split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        for s in seeds:
            o = run_case(s, Path(tmp))
            print(f"seed {s}: wall {o['wall']:.1f} s, outflow/feed {o['outflow'] / o['feed']:.4f}, "
                  f"count {o['count']:.0f} drift {o['count_drift']:+.3f}; h mm "
                  f"{np.round(o['h'] * 1e3, 2)}, u {np.round(o['u_mean'], 3)}, u_surf "
                  f"{np.round(o['u_surface'], 3)}, flux/feed {np.round(o['flux'] / o['feed'], 3)}, "
                  f"phi {np.round(o['phi'], 3)}; position u {np.round(o['position']['u_mean'], 2)} "
                  f"h {np.round(o['position']['h'], 2)}")
