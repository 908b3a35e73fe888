#!/usr/bin/env python3
"""The same benchmarks on two source trees, alternated round by round (this host drifts 10 -
40 % over minutes: alternating makes the drift hit both alike), with the median of each and
the median of the ratios paired within a round.

    python bench/before_after.py --before ../before-tree --rounds 3

``--before``: a checkout of the older commit (e.g. ``git worktree add --detach ../before
be8d9b8``); the current tree is "after". Both run with this interpreter; each tree is put
first on PYTHONPATH, so its taichi_dem, thermal and geometry are the ones imported. The
benchmarks: the 32k chute (bench/chute.py, no LAMMPS) and the 20k mesh drum
(bench/mesh_drum.py), one run each per round, f32, the engine's default threads.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

AFTER = Path(__file__).resolve().parents[1]
BENCHES = {
    "chute 32k": (["bench/chute.py", "--sizes", "32k", "--no-lammps", "--steps", "300",
                   "--repeats", "1"], r"taichi_dem\s+32k run 1:\s+([\d.]+)"),
    "mesh drum 20k": (["bench/mesh_drum.py", "--particles", "20000", "--steps", "300",
                       "--repeats", "1", "--settle", "0.2"], r"run 1: ([\d.]+) M particle-steps/s"),
    "mesh drum 20k x1000": (["bench/mesh_drum.py", "--particles", "20000", "--steps", "1000",
                             "--repeats", "1", "--settle", "0.2"],
                            r"run 1: ([\d.]+) M particle-steps/s"),
    "cooler slice 60 kg/m": (["bench/cooler_slice_step.py", "--holdup", "60"],
                             r"run 1: ([\d.]+) M particle-steps/s"),
}


def run(tree: Path, args, pattern) -> float:
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable] + args, cwd=tree, env=env, capture_output=True,
                         text=True, timeout=1800)
    m = re.search(pattern, out.stdout)
    if not m:
        raise RuntimeError(f"{tree}: {' '.join(args)}: no figure in\n{out.stdout[-2000:]}\n{out.stderr[-2000:]}")
    return float(m.group(1))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", required=True, type=Path)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--only", nargs="+", choices=list(BENCHES))
    a = p.parse_args(argv)
    trees = {"before": a.before.resolve(), "after": AFTER}
    results = {name: {"before": [], "after": []} for name in BENCHES}
    for r in range(a.rounds):
        order = ("before", "after") if r % 2 == 0 else ("after", "before")
        for name, (args, pattern) in BENCHES.items():
            if a.only and name not in a.only:
                continue
            for which in order:
                v = run(trees[which], args, pattern)
                results[name][which].append(v)
                print(f"round {r + 1} {name} {which}: {v:.2f} M particle-steps/s", flush=True)
    print("\n| scene | before (M particle-steps/s) | after | ratio of medians | median of paired ratios |")
    print("|---|---|---|---|---|")
    for name, res in results.items():
        if not res["before"]:
            continue
        b, f = res["before"], res["after"]
        paired = statistics.median(x / y for x, y in zip(f, b))
        print(f"| {name} | {', '.join(f'{x:.2f}' for x in b)} | {', '.join(f'{x:.2f}' for x in f)} | "
              f"{statistics.median(f) / statistics.median(b):.2f} | {paired:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
