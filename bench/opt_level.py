#!/usr/bin/env python3
"""What Taichi's own IR optimisation (``opt_level``, $TAICHI_DEM_OPT_LEVEL) costs in compile
time and buys in step rate: each case in a fresh process with an empty kernel cache, the
levels alternated within each round.

    python bench/opt_level.py [--rounds 3] [--cases cooler pile chute slice]

cases: ``cooler`` the main demo (demos/paddle_cooler.toml) built and stepped 20 steps, cold:
the compile; ``pile`` the same for demos/pile.toml; ``chute`` the 32k chute
(bench/chute_scene.py), 300 steps timed after 50; ``slice`` the seed's cooler slice at
60 kg/m (bench/cooler_slice_step.py: settle 0.1 s, time 0.1 s). The chute and the slice run
twice on one cache and report the second run (the kernels cached: a run whose lists grow
compiles mid-run). Prints each run and the
medians; levels 0 and 1 (the default: Taichi's simplification passes before LLVM, which
optimises at -O3 either way).
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent

BUILD = r"""
import sys, time
sys.path.insert(0, {root!r})
t0 = time.perf_counter()
import taichi_dem as td
path = {path!r}
with td.Simulation.from_text(open(path).read(), base_dir={base!r}, source=path, h5="") as sim:
    t1 = time.perf_counter()
    sim.step(20)
    t2 = time.perf_counter()
print(f"RESULT build_s={{t1 - t0:.3f}} first_steps_s={{t2 - t1:.3f}}")
"""

CHUTE = r"""
import sys, tempfile
sys.path.insert(0, {here!r})
from chute_scene import write_chute_scene
from chute import run_taichi_dem
with tempfile.TemporaryDirectory() as tmp:
    path = write_chute_scene(tmp, copies=1)
    r = run_taichi_dem(str(path), 300, 50)
print("RESULT", " ".join(f"{{k}}={{v}}" for k, v in r.items() if isinstance(v, (int, float)) and not isinstance(v, bool)))
"""


def one(case: str, level: int) -> dict:
    """One run of ``case`` at ``level`` in a fresh process and an empty kernel cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, TAICHI_DEM_OPT_LEVEL=str(level), TI_OFFLINE_CACHE_FILE_PATH=cache)
        if case in ("cooler", "pile"):
            path = ROOT / "demos" / ("paddle_cooler.toml" if case == "cooler" else "pile.toml")
            cmd = [sys.executable, "-c", BUILD.format(root=str(ROOT), path=str(path),
                                                      base=str(path.parent))]
        elif case == "chute":
            cmd = [sys.executable, "-c", CHUTE.format(here=str(HERE))]
        else:
            cmd = [sys.executable, str(HERE / "cooler_slice_step.py"), "--settle", "0.1",
                   "--seconds", "0.1"]
        out = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if case in ("chute", "slice") and out.returncode == 0:
            # the step rate with the kernels cached: a run that grows its lists compiles
            # mid-run, and a cold run's rate would count those compiles
            out = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{case} at opt_level {level} failed:\n{out.stderr[-2000:]}")
    if case == "slice":
        m = re.search(r"([\d.]+) M particle-steps/s.*settle ([\d.]+) s", out.stdout)
        return {"M_particle_steps_per_s": float(m.group(1)), "build_settle_s": float(m.group(2))}
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT")][-1]
    return {k: float(v) for k, v in (kv.split("=") for kv in line.split()[1:])}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--cases", nargs="+", default=["cooler", "pile", "chute", "slice"],
                   choices=["cooler", "pile", "chute", "slice"])
    a = p.parse_args(argv)
    runs: dict = {}
    for r in range(a.rounds):
        for case in a.cases:
            for level in ((0, 1) if r % 2 == 0 else (1, 0)):
                row = one(case, level)
                runs.setdefault((case, level), []).append(row)
                print(f"round {r + 1} {case} opt_level {level}: "
                      + ", ".join(f"{k} {v:.3g}" for k, v in row.items()), flush=True)
    print("\nmedians:")
    for (case, level), rows in sorted(runs.items()):
        keys = rows[0].keys()
        print(f"  {case} opt_level {level}: " + ", ".join(
            f"{k} {statistics.median(r[k] for r in rows):.3g}" for k in keys))
    return 0


if __name__ == "__main__":
    sys.exit(main())
