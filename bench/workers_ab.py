#!/usr/bin/env python3
"""Runs of steps on worker threads against two parallel launches per step, in one process on
one state (the same results bit for bit, so the windows alternate on one trajectory): the
chute at ``--size`` in the parallel mode, ``--rounds`` rounds of a ``--steps``-step window in
each, medians of particle-steps per second. Alternating in one process is what makes the
ratio trustworthy on this noisy machine (runs minutes apart differ by 20 % and more).

    .venv/bin/python bench/workers_ab.py --size 32k --steps 600 --rounds 5
"""
import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from chute_scene import write_chute_scene  # noqa: E402

SIZES = {"4k": dict(max_particles=4000), "8k": dict(max_particles=8000),
         "16k": dict(max_particles=16000), "32k": dict(copies=1), "128k": dict(copies=4)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", default="32k", choices=list(SIZES))
    p.add_argument("--steps", type=int, default=600)
    p.add_argument("--rounds", type=int, default=5)
    a = p.parse_args(argv)
    import taichi as ti
    import taichi_dem as td
    scene = write_chute_scene(Path(tempfile.mkdtemp()) / a.size, **SIZES[a.size])
    sim = td.Simulation.from_toml(str(scene), precision="f32", h5="", parallel_from=0)
    e = sim.engine
    workers = e.workers
    if not workers:
        print("no worker threads on this machine (one core, or a GPU)")
        return 1
    e.worker_stall_limit = None              # measure them, whatever the machine does
    try:
        for w in (workers, 0):               # JIT of both
            e.workers = w
            sim.step(60)
        rates = {"workers": [], "launches": []}
        for _ in range(a.rounds):
            for name, w in (("workers", workers), ("launches", 0)):
                e.workers = w
                t0 = time.perf_counter()
                sim.step(a.steps)
                ti.sync()
                rates[name].append(sim.particle_count * a.steps / (time.perf_counter() - t0))
        med = {k: statistics.median(v) for k, v in rates.items()}
        for k, v in rates.items():
            print(f"chute {a.size} ({sim.particle_count} particles), {k:8s}: median "
                  f"{med[k] / 1e6:.2f} M particle-steps/s  "
                  f"({', '.join(f'{x / 1e6:.2f}' for x in v)})")
        print(f"workers / launches: {med['workers'] / med['launches']:.2f}; barrier waits "
              f"that stalled: {e.worker_stalls} of {e.worker_barriers}")
    finally:
        sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
