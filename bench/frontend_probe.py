#!/usr/bin/env python3
"""What engine/frontend.py saves: bench/jit_probe.py (three builds of the 200-particle test
scene in one process) run in child processes with and without the savings
(TAICHI_DEM_PLAIN_TAICHI=1 switches them off), the two alternated over ``--rounds``. Run it
twice with the same TI_OFFLINE_CACHE_FILE_PATH for the warm figure.

    python bench/frontend_probe.py --rounds 2
"""
import argparse
import os
import subprocess
import sys
from pathlib import Path

PROBE = Path(__file__).resolve().parent / "jit_probe.py"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    for r in range(args.rounds):
        for plain in ("1", "0"):
            env = {**os.environ, "TAICHI_DEM_PLAIN_TAICHI": plain}
            out = subprocess.run([sys.executable, str(PROBE)], env=env, capture_output=True,
                                 text=True, check=True).stdout
            builds = [line.split("build ")[1].split(",")[0] for line in out.splitlines()
                      if line.startswith("simulation")]
            print(f"round {r} {'plain Taichi' if plain == '1' else 'with savings'}: "
                  f"builds {', '.join(builds)}", flush=True)


if __name__ == "__main__":
    main()
