#!/usr/bin/env python3
"""The chute benchmark: taichi_dem and LAMMPS on the same particles, in the same run.

LAMMPS's chute-flow benchmark (../shared/peers/README.md, data.chute: 32,000 spheres, a frozen
rough base, gravity tilted 26 degrees, periodic in x and y) run by taichi_dem with
Hertz-Mindlin and tangential history (bench/chute_scene.py writes the scene) and by LAMMPS
gran/hertz/history on 1 and 2 ranks (bench/lammps_chute.py). Reports particle-steps per
second (atoms x steps / loop seconds; the first ``--warmup`` steps of taichi_dem, which
include JIT compilation, are not timed), medians over ``--repeats`` rounds, and the ratios:
of the medians, and the median of the ratios paired within a round (a round runs every size
and every rank count once, so that the runs of a ratio are seconds apart, not minutes).

    python bench/chute.py --steps 1000 --repeats 3                 # 32k, with LAMMPS
    python bench/chute.py --sizes 8k 32k 128k --repeats 3          # scaling
"""
import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from chute_scene import write_chute_scene  # noqa: E402
from lammps_chute import LammpsMissing, run_lammps  # noqa: E402

SIZES = {"8k": dict(max_particles=8000), "32k": dict(copies=1), "128k": dict(copies=4),
         "512k": dict(copies=16)}


def run_taichi_dem(scene_path: str, steps: int, warmup: int, threads=None, precision="f32",
                   arch: str = "cpu", parallel_from=None) -> dict:
    """One timed run of the chute scene: particle-steps per second after ``warmup`` steps.
    ``parallel_from``: the engine's loop-mode threshold (None: its default; 0: parallel
    loops at any size; a huge number: serial loops in runs of steps at any size)."""
    import taichi_dem as td
    sim = td.Simulation.from_toml(scene_path, threads=threads, precision=precision, h5="",
                                  arch=arch, parallel_from=parallel_from)
    try:
        sim.step(warmup)
        rebuilds0 = sim.engine.broadphase.rebuilds
        t0 = time.perf_counter()
        sim.step(steps)
        sim.engine.flags.to_numpy()          # synchronise
        seconds = time.perf_counter() - t0
        n = sim.particle_count
        return dict(particles=n, steps=steps, seconds=seconds, serial=sim.engine.serial,
                    particle_steps_per_s=n * steps / seconds,
                    rebuilds=sim.engine.broadphase.rebuilds - rebuilds0,
                    neighbours_per_particle=sim.engine.broadphase.entries / n)
    finally:
        sim.close()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--warmup", type=int, default=50)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--sizes", nargs="+", default=["32k"], choices=list(SIZES))
    p.add_argument("--copies", type=float, help="(taichi-dem bench) size in units of 32k")
    p.add_argument("--threads", type=int)
    p.add_argument("--precision", default="f32", choices=["f32", "f64"])
    p.add_argument("--no-lammps", action="store_true")
    p.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    p.add_argument("--json", help="write all runs here")
    p.add_argument("--arch", default="cpu", help="cpu or cuda (bench/gpu_check.sh)")
    a = p.parse_args(argv)
    if a.copies:
        a.sizes = ["32k" if a.copies == 1 else ("128k" if a.copies == 4 else "8k")]
    results = {"taichi_dem": {size: [] for size in a.sizes}, "lammps": {}}
    lammps_ranks = [] if a.no_lammps else list(a.ranks)
    # Rounds, each with every taichi_dem size and every LAMMPS rank count, taichi_dem first in
    # even rounds and LAMMPS first in odd ones: this host's speed drifts by 10 - 40 % over
    # minutes, and a ratio of two runs seconds apart (paired within a round) is less exposed
    # to it than a ratio of medians taken minutes apart.
    with tempfile.TemporaryDirectory() as tmp:
        scenes = {size: write_chute_scene(Path(tmp) / size, **SIZES[size]) for size in a.sizes}

        def taichi_round(r):
            for size in a.sizes:
                res = run_taichi_dem(str(scenes[size]), a.steps, a.warmup, a.threads,
                                     a.precision, a.arch)
                results["taichi_dem"][size].append(res)
                print(f"taichi_dem {size:>4s} run {r + 1}: {res['particle_steps_per_s'] / 1e6:6.2f} "
                      f"M particle-steps/s ({res['particles']} particles, {res['rebuilds']} "
                      f"rebuilds, {res['neighbours_per_particle']:.2f} neighbours/particle)",
                      flush=True)

        def lammps_round(r):
            for ranks in list(lammps_ranks):
                try:
                    res = run_lammps(a.steps, ranks)
                except LammpsMissing as err:
                    print(f"LAMMPS skipped: {err}")
                    lammps_ranks.clear()
                    results["lammps"].clear()
                    return
                results["lammps"].setdefault(ranks, []).append(res)
                print(f"LAMMPS {ranks} rank(s) run {r + 1}: {res['particle_steps_per_s'] / 1e6:6.2f} "
                      f"M particle-steps/s", flush=True)

        for r in range(a.repeats):
            for stage in ((taichi_round, lammps_round) if r % 2 == 0
                          else (lammps_round, taichi_round)):
                stage(r)

    def med(runs):
        return statistics.median(x["particle_steps_per_s"] for x in runs)

    def paired(runs, lruns):
        return statistics.median(x["particle_steps_per_s"] / y["particle_steps_per_s"]
                                 for x, y in zip(runs, lruns))

    print("\nmedians (million particle-steps per second), ratios of the medians and [the "
          "median of the ratios paired within a round]:")
    for size, runs in results["taichi_dem"].items():
        line = f"  taichi_dem {size:>5s} ({runs[0]['particles']} particles): {med(runs) / 1e6:6.2f}"
        for ranks, lruns in results["lammps"].items():
            line += (f"   x{med(runs) / med(lruns):.2f} [x{paired(runs, lruns):.2f}] of LAMMPS "
                     f"{ranks} rank(s)")
        if size != "32k" and results["lammps"]:
            # (LAMMPS runs data.chute, 32k, here: bench/cost_curve.py runs it at each size)
            line += "   (LAMMPS's figures at 32k)"
        print(line)
    for ranks, lruns in results["lammps"].items():
        print(f"  LAMMPS gran/hertz/history {ranks} rank(s), 32000 particles: {med(lruns) / 1e6:6.2f}")
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
