#!/usr/bin/env python3
"""Step rate of the seed's cooler slice (demos/cooler_slice.toml: one paddle row, periodic,
15 mm spheres, f32) at a hold-up: settle ``--settle`` s, then time ``--seconds`` s.

    python bench/cooler_slice_step.py [--holdup 60 [90 ...]] [--settle 0.2] [--seconds 0.3]
                                      [--arch cuda] [--scene demos/cooler_slice.toml]
                                      [--precision f64]

Prints ``run K: X M particle-steps/s`` per hold-up (bench/before_after.py reads it).
"""
import argparse
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--holdup", type=float, nargs="+", default=[60.0], help="kg/m")
    p.add_argument("--arch", default="cpu")
    p.add_argument("--scene", type=Path, default=ROOT / "demos" / "cooler_slice.toml")
    p.add_argument("--settle", type=float, default=0.2)
    p.add_argument("--seconds", type=float, default=0.3)
    p.add_argument("--precision", choices=["f32", "f64"], default=None,
                   help="default: the scene's (f32)")
    a = p.parse_args()
    import taichi_dem as td
    from taichi_dem.app import slice_map as sm
    from taichi_dem.app.overrides import apply, to_text
    from taichi_dem.scene.loader import parse_scene
    path = a.scene
    base = path.read_text()
    scene = parse_scene(base, source=str(path))
    for k, holdup in enumerate(a.holdup, 1):
        count, _, _ = sm.holdup_count(scene, sm.slice_geometry(scene), ("kg/m", holdup))
        text = to_text(apply(tomllib.loads(base), {"particles.0.count": count}, str(path)))
        t0 = time.perf_counter()
        with td.Simulation.from_text(text, h5="", arch=a.arch, precision=a.precision) as sim:
            sim.run(a.settle)
            start = time.perf_counter() - t0
            t0 = time.perf_counter()
            steps = int(round(a.seconds / sim.engine.model.dt))
            sim.run(sim.time + a.seconds)
            rate = sim.particle_count * steps / (time.perf_counter() - t0) / 1e6
        print(f"run {k}: {rate:.3f} M particle-steps/s ({count} particles, {holdup:g} kg/m, "
              f"{a.arch}, {a.precision or 'scene precision'}; build, compile and settle {start:.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
