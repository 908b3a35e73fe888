#!/usr/bin/env python3
"""Each kernel's median launch time over a few hundred steps from one saved state: an A/B of
two trees on a noisy host (BENCHMARKS.md "The cooler slice against a plain bed, per stage").

Single runs on the shared 2-core host vary 2x from one minute to the next; the median of
hundreds of launches of one kernel from the same state varies a few per cent. Run the same
command in both trees (alternated) against the same ``--state`` file:

    TAICHI_DEM_WORKERS=0 python bench/kernel_medians.py --state /tmp/slice_60.h5
    TAICHI_DEM_WORKERS=0 python bench/kernel_medians.py --state /tmp/slice_60.h5 --scene demos/dryers/dryer_slice.toml --holdup 75

A missing ``--state`` is made first: the slice (the seed's cooler slice by default) filled to
``--holdup`` kg/m, run ``--settle`` s in ``--precision``, written as a checkpoint. Then the
state is restored, stepped 20 steps, and ``--steps`` steps are timed by Taichi's kernel
profiler. Prints per kernel (Taichi's offloaded tasks, the compile number dropped): launches,
minimum, 10th percentile and median in ms, the largest total first.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))


def make_state(path: str, scene: Path, holdup: float, settle: float, precision: str) -> None:
    """The slice filled to ``holdup`` kg/m, run ``settle`` s, written to ``path``."""
    import taichi_dem as td
    from taichi_dem.run import checkpoint
    from slice_profile import slice_text
    text, _ = slice_text(holdup, scene)
    with td.Simulation.from_text(text, h5="", precision=precision) as sim:
        sim.run(settle)
        checkpoint.write(path, checkpoint.capture(sim))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--state", required=True, help="checkpoint file (made when missing)")
    p.add_argument("--scene", type=Path, default=ROOT / "demos" / "cooler_slice.toml")
    p.add_argument("--holdup", type=float, default=60.0, help="kg/m, for a new state")
    p.add_argument("--settle", type=float, default=0.3, help="s, for a new state")
    p.add_argument("--precision", choices=("f32", "f64"), default="f64",
                   help="for a new state")
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--top", type=int, default=12)
    a = p.parse_args(argv)
    import taichi as ti
    orig = ti.init
    ti.init = lambda **kw: orig(**{**kw, "kernel_profiler": True})
    if not os.path.exists(a.state):
        make_state(a.state, a.scene, a.holdup, a.settle, a.precision)
    import taichi_dem as td
    from slice_profile import profiler_launches
    with td.Simulation.from_checkpoint(a.state, h5="") as sim:
        sim.step(20)
        ti.profiler.clear_kernel_profiler_info()
        sim.step(a.steps)
        launches = profiler_launches()
        print(f"{sim.particle_count} particles, {a.steps} steps from {a.state}")
    print(f"{'kernel':44s} {'launches':>8s} {'min ms':>8s} {'p10 ms':>8s} {'median ms':>9s}")
    for name in sorted(launches, key=lambda k: -sum(launches[k]))[:a.top]:
        v = sorted(launches[name])
        print(f"{name[:44]:44s} {len(v):8d} {v[0]:8.3f} {v[len(v) // 10]:8.3f} "
              f"{v[len(v) // 2]:9.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
