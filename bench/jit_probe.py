#!/usr/bin/env python3
"""How long a new simulation takes to build (kernel compilation) and to run its first steps.

Builds the same 200-particle scene (tests/conftest.py SMALL_SCENE) three times in one process.
With a cold Taichi kernel cache every build compiles all kernels again (the cache key names
the fields' SNode ids, which differ for every simulation in a process); run it twice with the
same cache folder to see the warm figure:

    TI_OFFLINE_CACHE_FILE_PATH=/tmp/tic python bench/jit_probe.py    # cold, then warm
"""
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from conftest import SMALL_SCENE  # noqa: E402

import taichi_dem as td  # noqa: E402

text = SMALL_SCENE.format(precision="f64", rolling=0.05, count=200)
for k in range(3):
    t0 = time.perf_counter()
    with td.Simulation.from_text(text, arch="cpu", precision="f64") as sim:
        t1 = time.perf_counter()
        sim.step(10)
        t2 = time.perf_counter()
    print(f"simulation {k}: build {t1 - t0:.2f} s, first 10 steps {t2 - t1:.2f} s", flush=True)
