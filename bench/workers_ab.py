#!/usr/bin/env python3
"""Runs of steps on worker threads against another way of stepping, in one process,
alternating windows of ``--steps`` steps for ``--rounds`` rounds (medians of particle-steps
per second, and the median of the rounds' paired ratios): the chute at ``--size`` from
``parallel_from`` = 0. Alternating in one process is what makes a ratio trustworthy on this
noisy machine (runs minutes apart differ by 20 % and more).

``--against``:
  launches  two parallel launches per step (one simulation, the workers switched off and on;
            the modes differ by round-off, so the windows go on along nearly one trajectory)
  claims    workers that claim chunks in the pair stage too and store the partners' shares
            at the entries (tuning.WORKER_COPIES = False, as under [mobility]): a second
            simulation of the same scene, windows alternating between the two
  serial    the serial mode on one thread, runs of steps (one simulation, modes switched)
  chunks128 workers claiming 128 particles at a time in the particle stage (the chunks of
            stop 17; tuning.WORKER_CHUNKS huge): a second simulation, windows alternating
  kernel-rebuilds  the workers with the rebuild as separate parallel kernels instead of on
            the workers (Engine.rebuilds_on_workers off and on in one simulation: the lists
            are the same, so the windows go on along one trajectory); each rebuild is timed

    .venv/bin/python bench/workers_ab.py --size 32k --steps 100 --rounds 20 --against claims
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
    p.add_argument("--against", default="launches", choices=["launches", "claims", "serial", "chunks128",
                                                     "kernel-rebuilds"])
    a = p.parse_args(argv)
    import taichi as ti
    import taichi_dem as td
    from taichi_dem.setup import tuning
    scene = write_chute_scene(Path(tempfile.mkdtemp()) / a.size, **SIZES[a.size])

    def make(copies: bool, chunks=tuning.WORKER_CHUNKS):
        chunks_before = tuning.WORKER_CHUNKS
        tuning.WORKER_COPIES, tuning.WORKER_CHUNKS = copies, chunks
        try:
            sim = td.Simulation.from_toml(str(scene), precision="f32", h5="", parallel_from=0)
        finally:
            tuning.WORKER_COPIES, tuning.WORKER_CHUNKS = True, chunks_before
        sim.engine.worker_pool.stall_limit = None      # measure them, whatever the machine does
        return sim

    sim = make(True)
    e = sim.engine
    workers = e.workers
    if not workers:
        print("no worker threads on this machine (one core, or a GPU)")
        sim.close()
        return 1
    other_sim = (make(False) if a.against == "claims" else
                 make(True, chunks=10 ** 9) if a.against == "chunks128" else sim)

    def mode(name):
        """Set up ``name`` ("workers" or a.against) and return the simulation to step."""
        if name == "workers" or a.against in ("claims", "chunks128"):
            return sim if name == "workers" else other_sim
        if a.against == "launches":
            e.workers = 0
        elif a.against == "kernel-rebuilds":
            e.rebuilds_on_workers = False
        else:                                    # serial: below parallel_from
            e.parallel_from, e.serial = 10 ** 9, True
        return sim

    def back_to_workers():
        e.parallel_from, e.serial, e.workers = 0, False, workers
        e.rebuilds_on_workers = True

    # each rebuild timed, booked to the way it was done
    rebuild_times = {True: [], False: []}
    rebuild = e.broadphase.rebuild

    def timed_rebuild(n):
        t0 = time.perf_counter()
        out = rebuild(n)
        ti.sync()
        rebuild_times[e.rebuilds_on_workers].append(time.perf_counter() - t0)
        return out
    e.broadphase.rebuild = timed_rebuild

    names = ("workers", a.against)
    try:
        for name in names:                       # JIT of both
            mode(name).step(60)
            back_to_workers()
        rates = {name: [] for name in names}
        rebuild_times[True].clear()
        rebuild_times[False].clear()
        for _ in range(a.rounds):
            for name in names:
                s = mode(name)
                t0 = time.perf_counter()
                s.step(a.steps)
                ti.sync()
                rates[name].append(s.particle_count * a.steps / (time.perf_counter() - t0))
                back_to_workers()
        med = {k: statistics.median(v) for k, v in rates.items()}
        for k, v in rates.items():
            print(f"chute {a.size} ({sim.particle_count} particles), {k:8s}: median "
                  f"{med[k] / 1e6:.2f} M particle-steps/s  "
                  f"({', '.join(f'{x / 1e6:.2f}' for x in v)})")
        paired = [w / o for w, o in zip(rates["workers"], rates[a.against])]
        print(f"workers / {a.against}: median of the rounds' ratios {statistics.median(paired):.3f} "
              f"({', '.join(f'{r:.2f}' for r in paired)}); barrier waits that stalled: "
              f"{e.worker_pool.stalls} of {e.worker_pool.barriers}")
        if a.against == "kernel-rebuilds":
            for on_workers, v in rebuild_times.items():
                if v:
                    print(f"rebuilds {'on the workers' if on_workers else 'as kernels'}: {len(v)}, "
                          f"median {1e3 * statistics.median(v):.2f} ms")
    finally:
        if other_sim is not sim:
            other_sim.close()
        sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
