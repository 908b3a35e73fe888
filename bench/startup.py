#!/usr/bin/env python3
"""Where the start-up of a run goes (issue 45 item 1): the main demo's first 0.05 s, warm and
cold, broken into imports, ti.init, the scene and its meshes (load, validate, place the fill),
building the simulation's fields and kernels' Python side, the kernels' first calls (Taichi's
front end turning each into IR, then compiling it or reading it from the cache), the first
neighbour list, and the steps.

    python bench/startup.py [SCENE] [--until 0.05] [--rounds 3]

Each round runs in a fresh process. Round 1 uses an empty kernel cache (cold); the others
reuse it (warm). Prints one table row per round and the medians of the warm rounds.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PHASES = ("imports", "ti_init", "scene", "build", "first_list", "steps", "total",
          "kernel_front_end", "kernel_compile_or_load")


def _one(scene: str, until: float) -> dict:
    t_start = time.perf_counter()
    sys.path.insert(0, str(ROOT))
    import taichi_dem as td                      # noqa: F401
    from taichi_dem.engine import backend
    from taichi_dem.engine.stepper import Engine
    from taichi_dem.run.simulation import Simulation
    from taichi_dem.scene.loader import load_scene
    from taichi.lang import kernel_impl
    out = {"imports": time.perf_counter() - t_start}
    # the kernels' first calls: front end + compile or cache load, wherever they happen
    first_calls = [0.0]
    materialize = kernel_impl.Kernel.materialize

    def timed(self, key=None, args=None, arg_features=None):
        t = time.perf_counter()
        try:
            return materialize(self, key, args, arg_features)
        finally:
            first_calls[0] += time.perf_counter() - t
    kernel_impl.Kernel.materialize = timed
    # ... and their first launch: compiling the IR (LLVM) or reading it from the cache
    launch = kernel_impl.Kernel.launch_kernel
    launched: set = set()
    first_launches = [0.0]

    def timed_launch(self, t_kernel, *args):
        if id(t_kernel) in launched:
            return launch(self, t_kernel, *args)
        launched.add(id(t_kernel))
        t = time.perf_counter()
        try:
            return launch(self, t_kernel, *args)
        finally:
            first_launches[0] += time.perf_counter() - t
    kernel_impl.Kernel.launch_kernel = timed_launch
    acquire = backend.acquire
    init = [0.0]

    def timed_acquire(*a, **k):
        t = time.perf_counter()
        try:
            return acquire(*a, **k)
        finally:
            init[0] += time.perf_counter() - t
    backend.acquire = timed_acquire
    start = Engine.start
    first_list = [0.0]

    def timed_start(self, n):
        t = time.perf_counter()
        try:
            return start(self, n)
        finally:
            first_list[0] += time.perf_counter() - t
    Engine.start = timed_start
    t = time.perf_counter()
    scene = load_scene(scene)
    out["scene"] = time.perf_counter() - t
    t = time.perf_counter()
    sim = Simulation(scene, h5="")
    built = time.perf_counter() - t
    t = time.perf_counter()
    sim.run(until)
    out["steps"] = time.perf_counter() - t
    sim.close()
    out["ti_init"] = init[0]
    out["first_list"] = first_list[0]
    out["kernel_front_end"] = first_calls[0]
    out["kernel_compile_or_load"] = first_launches[0]
    # placing the fill happens inside the build: what the build took besides ti.init and the
    # first list (its kernels' first calls are in the kernel_* columns as well)
    out["build"] = built - init[0] - first_list[0]
    out["total"] = time.perf_counter() - t_start
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default=str(ROOT / "demos" / "paddle_cooler.toml"))
    p.add_argument("--until", type=float, default=0.05)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.one:
        print(json.dumps(_one(a.scene, a.until)))
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, TI_OFFLINE_CACHE_FILE_PATH=cache)
        for k in range(a.rounds + 1):
            r = subprocess.run([sys.executable, __file__, a.scene, "--until", str(a.until),
                                "--one"], env=env, capture_output=True, text=True, check=True)
            rows.append(json.loads(r.stdout.strip().splitlines()[-1]))
    print("| round | " + " | ".join(PHASES) + " |")
    print("|---" * (len(PHASES) + 1) + "|")
    for k, r in enumerate(rows):
        print(f"| {'cold' if k == 0 else f'warm {k}'} | "
              + " | ".join(f"{r[n]:.2f}" for n in PHASES) + " |")
    warm = rows[1:]
    print("| warm median | " + " | ".join(f"{statistics.median(r[n] for r in warm):.2f}"
                                         for n in PHASES) + " |")
    print("(s; the kernel_* columns overlap build, first_list and steps: they are where in "
          "them the kernels were first called: Taichi's Python front end making each kernel's "
          "IR, and its first launch, which compiles the IR or reads it from the cache)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
