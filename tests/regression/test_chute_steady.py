"""Regression: a short, narrow version of the steady chute demo (seed 004's material on its
38 deg slope, fed by a sheet inlet) reaches a steady flow whose outflow equals the feed and
whose depth profile lies where the depth-averaged model puts it.

The case: 1 mm spheres (rho 811.54, E 5.17 MPa, e 0.55, mu 0.4877, mu_r 0.005; basal friction
0.4245) fed through a face 8 mm deep at u0 = 0.5492 m/s onto a chute 60 mm long; 5 mm across,
periodic (the demo's 20 mm has side walls; in a 5-diameter channel their friction would be the
flow's main brake, which the depth-averaged model has no term for). Inflow solid fraction
0.45: mass rate 0.45 x 811.54 x 0.008 x 0.005 x 0.5492 = 8.02 g/s (a 5 mm face carries at most
0.49 with this lattice's edges). About 1,500 spheres in the chute at steady state; run to
0.25 s, averaged over the last 0.1 s (steady from about 0.12 s).

MEASURED (f32; `python tests/regression/test_chute_steady.py 1,2,3`): see SCATTER below.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pytest

import taichi_dem
from taichi_dem.app import depth_averaged as da
from taichi_dem.app.demos import Chute

pytestmark = pytest.mark.slow         # part of the default suite; -m "not slow" skips it

FEED = 0.45 * 811.54 * 0.008 * 0.005 * 0.5492      # kg/s
SCENE = """
[simulation]
end_time = 0.25
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


def check(out: dict):
    pass


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
