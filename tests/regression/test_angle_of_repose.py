"""Regression: the fly ash of seed 001 stands at the paper's angle of repose.

Seed 001 (fly-ash paddle cooler) calibrated its virtual material - 15 mm spheres, e 0.65,
static friction 0.8 (ash-ash) and 0.9 (ash-steel), rolling friction 1.4 and 1.3 (EDEM's
coefficient; see demos/angle_of_repose.toml for that reading) - against a heap test: 38.1 deg
measured, 38.6 deg in its DEM (Table 2), the DEM's eight repeats spanning 35.0 - 43.5 deg.

This runs the bundled demo scene itself (demos/angle_of_repose.toml: 2,500 spheres poured into
a tube on a rough base, the tube lifted at 0.1 m/s, 5 s) and fits the heap's flank
(taichi_dem.app.analysis.heap_angle: the highest sphere top per one-diameter ring, a line through
the rings between 20 and 80 % of the heap's height).

MEASURED (f32): 38.8, 39.5, 37.1 deg for seeds 1, 2, 3 (mean 38.5, sd 1.2); the angle moves by
about +/- 0.5 deg over the last 0.5 s as single spheres settle. With the rolling friction read as
an angle instead (mu_r = tan 1.4 deg = 0.024), or mu_r = 0.1, the heap stands at 20.7 deg.

Tolerance: the span of the paper's own eight DEM heaps, 35.0 - 43.5 deg (their sd about 2.8
deg, more than our 1.2). A heap of free-rolling spheres (about 21 deg), a rolling-friction torque
that is not applied, or a collapsed pile fails it.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import pytest

import taichi_dem
from taichi_dem.app import analysis

pytestmark = pytest.mark.slow         # part of the default suite; -m "not slow" skips it

SCENE = Path(__file__).resolve().parent.parent.parent / "demos" / "angle_of_repose.toml"
PAPER_DEM_SPAN = (35.0, 43.5)       # seed 001, Table 2: its eight DEM heaps


def heap(seed: int) -> tuple[float, float, float]:
    """Run the demo scene with ``seed``; return (angle deg, heap height m, wall s)."""
    text = SCENE.read_text().replace("seed = 1\n", f"seed = {seed}\n", 1)
    t0 = time.perf_counter()
    with taichi_dem.Simulation.from_text(text, base_dir=str(SCENE.parent), h5="") as sim:
        sim.run()
        p = sim.particles()
    moving = ~p["fixed"]
    angle, height, _ = analysis.heap_angle({"position": p["position"][moving],
                                            "radius": p["radius"][moving]})
    return angle, height, time.perf_counter() - t0


def test_fly_ash_heap_stands_at_the_papers_angle():
    angle, height, wall = heap(1)
    print(f"\n  angle of repose {angle:.1f} deg, heap {height * 1e3:.0f} mm high ({wall:.0f} s wall); "
          f"seed 001: 38.1 measured, 38.6 DEM")
    assert PAPER_DEM_SPAN[0] <= angle <= PAPER_DEM_SPAN[1]


if __name__ == "__main__":
    # the scatter over seeds quoted in the docstring: python tests/regression/test_angle_of_repose.py 1,2,3
    import sys
    angles = []
    for seed in (int(s) for s in (sys.argv[1] if len(sys.argv) > 1 else "1,2,3").split(",")):
        angle, height, wall = heap(seed)
        angles.append(angle)
        print(f"seed {seed}: {angle:.2f} deg, height {height * 1e3:.0f} mm ({wall:.0f} s)", flush=True)
    print(f"mean {np.mean(angles):.2f} deg, sd {np.std(angles, ddof=1) if len(angles) > 1 else 0:.2f}")
