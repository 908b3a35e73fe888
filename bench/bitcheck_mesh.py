#!/usr/bin/env python3
"""Fingerprints of two mesh scenes after a fixed run, to tell whether a change to the mesh
contacts moved any result (compare the output of two trees; issue 45 item 3's "the same
contacts result").

The drum of tests/verification/test_drum_wall_heat.py (20 % fill, 16 lifters, heat) for 0.1 s
and the seed's cooler slice at 60 kg/m (bench/slice_profile.py's scene) for 0.05 s, both f64
on one thread: the sha1 of the positions and velocities ordered by particle id.

    python bench/bitcheck_mesh.py                         # this tree
    cd OTHER_TREE && PYTHONPATH=$PWD python /path/to/bench/bitcheck_mesh.py
"""
from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import numpy as np

ROOT = Path.cwd()


def fingerprint(sim) -> str:
    """sha1 of the positions and velocities, ordered by particle id."""
    p = sim.particles()
    order = np.argsort(p["id"])
    data = (np.ascontiguousarray(p["position"][order]).tobytes()
            + np.ascontiguousarray(p["velocity"][order]).tobytes())
    return hashlib.sha1(data).hexdigest()


def main() -> int:
    sys.path[:0] = [str(ROOT / "tests" / "verification"), str(ROOT / "bench")]
    import taichi_dem
    from drum_wall_heat import GLASS_FRICTION, fill_count, scene_text
    from slice_profile import slice_text
    drum = scene_text(length=0.005, count=fill_count(0.05, 0.005, 0.2, 1e-3), rpm_mech=12.0,
                      time_scale=2.0, dt=2.5e-5, output_interval=0.025, flights=16,
                      flight_height=1e-3, model="schlunder", friction=GLASS_FRICTION)
    cooler, _ = slice_text(60.0)
    for name, text, until in (("drum", drum, 0.1), ("cooler slice", cooler, 0.05)):
        with taichi_dem.Simulation.from_text(text, precision="f64", threads=1, h5="") as sim:
            sim.run(until)
            print(f"{name}: {sim.particle_count} particles at {sim.time:.4g} s: {fingerprint(sim)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
