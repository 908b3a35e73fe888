#!/usr/bin/env python3
"""What engine/frontend.py saves: the build time of the 200-particle test scene
(tests/conftest.py SMALL_SCENE), three builds per process, with and without the savings
(TAICHI_DEM_PLAIN_TAICHI=1 switches them off), alternated over ``--rounds`` child processes.
Run it twice with the same TI_OFFLINE_CACHE_FILE_PATH for the warm figure.

    python bench/frontend_probe.py --rounds 2
"""
import argparse
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CHILD = """
import sys, time
sys.path.insert(0, TESTS)
from conftest import SMALL_SCENE
import taichi_dem as td
text = SMALL_SCENE.format(precision="f64", rolling=0.05, count=200)
for k in range(3):
    t0 = time.perf_counter()
    with td.Simulation.from_text(text, arch="cpu", precision="f64") as sim:
        t1 = time.perf_counter()
        sim.step(10)
    print(f"build {k}: {t1 - t0:.2f} s", flush=True)
""".replace("TESTS", repr(str(ROOT / "tests")))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    for r in range(args.rounds):
        for plain in ("1", "0"):
            env = {**os.environ, "TAICHI_DEM_PLAIN_TAICHI": plain}
            out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True,
                                 text=True, check=True).stdout
            times = [line.split(": ")[1] for line in out.splitlines() if line.startswith("build")]
            print(f"round {r} {'plain Taichi' if plain == '1' else 'with savings'}: "
                  f"{', '.join(times)}", flush=True)


if __name__ == "__main__":
    main()
