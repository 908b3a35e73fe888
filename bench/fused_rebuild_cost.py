#!/usr/bin/env python3
"""What the serial mode's one-launch rebuild (Broadphase.fused_rebuild) saves per rebuild: the
same 200-bead heap (tests/conftest.py SMALL_SCENE) stepped with it and with the separate
kernels, alternated, after 2000 settling steps (compilation outside the timed steps):

    python bench/fused_rebuild_cost.py --steps 20000 --rounds 3
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from conftest import SMALL_SCENE  # noqa: E402

import taichi_dem as td  # noqa: E402
from taichi_dem.engine import broadphase  # noqa: E402

if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--count", type=int, default=200)
    args = ap.parse_args()
    broadphase.FUSED_AFTER_QUIET_REBUILDS = 0          # fused from the first rebuild
    text = SMALL_SCENE.format(precision="f64", rolling=0.05, count=args.count).replace(
        "end_time = 0.02", "end_time = 5")
    seconds = {True: [], False: []}
    rebuilds = {}
    for _ in range(args.rounds):
        for fused in (True, False):
            with td.Simulation.from_text(text) as sim:
                sim.engine.fused_rebuilds = fused
                sim.step(2000)
                r0 = sim.engine.broadphase.rebuilds
                t0 = time.perf_counter()
                sim.step(args.steps)
                seconds[fused].append(time.perf_counter() - t0)
                rebuilds[fused] = sim.engine.broadphase.rebuilds - r0
    for fused in (True, False):
        print(f"fused={fused}: {args.steps} steps, {rebuilds[fused]} rebuilds, seconds "
              f"{', '.join(f'{t:.3f}' for t in seconds[fused])}, median "
              f"{statistics.median(seconds[fused]):.3f}")
    saved = (statistics.median(seconds[False]) - statistics.median(seconds[True])) / rebuilds[True]
    print(f"saved per rebuild (medians): {saved * 1e3:.2f} ms")
