#!/usr/bin/env python3
"""Where the chute's step goes in the parallel mode: each launch of the pair kernel, of the
gather and of the neighbour rebuild timed on its own (synchronised before and after), after
``--warmup`` untimed steps, with their distribution (median, min, p90) per step.

    .venv/bin/python bench/chute_kernels.py --size 32k --threads 2
    .venv/bin/python bench/chute_kernels.py --size 32k --threads 1   # the same kernels, one thread

``--rebuild-parts``: each kernel of the rebuild timed instead of the whole; ``--fused-rebuild``:
the serial mode's one-launch rebuild (on one thread) instead of the parallel kernels.

``--serial``: the serial mode's kernels instead (one thread, the partners' shares added
directly, the one-launch rebuild), one launch per stage rather than its runs of steps: what a
core costs per stage without the mirror pass.

The worker threads (Engine.workers) are switched off: their runs of steps are one launch.
``--threads 1`` runs the parallel kernels (not the serial mode's runs of steps) on a one-thread
Taichi pool, so that the two runs compare the same code: their ratio is what the second thread
gives each kernel. Particle-steps per second here include the synchronisations (a few per cent
below bench/chute.py's figure).
"""
import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from chute_scene import write_chute_scene  # noqa: E402

SIZES = {"8k": dict(max_particles=8000), "16k": dict(max_particles=16000),
         "32k": dict(copies=1), "128k": dict(copies=4)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", default="32k", choices=list(SIZES))
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--steps", type=int, default=400)
    p.add_argument("--warmup", type=int, default=60)
    p.add_argument("--rebuild-parts", action="store_true")
    p.add_argument("--fused-rebuild", action="store_true")
    p.add_argument("--serial", action="store_true")
    a = p.parse_args(argv)
    import taichi as ti
    import taichi_dem as td
    scene = write_chute_scene(Path(tempfile.mkdtemp()) / a.size, **SIZES[a.size])
    sim = td.Simulation.from_toml(str(scene), threads=a.threads, precision="f32", h5="",
                                  parallel_from=10 ** 9 if a.serial else None)
    e = sim.engine
    e.workers = 0                  # (one launch per stage: the kernels timed one by one)
    if a.serial:
        e.runs = False             # (the serial kernels launched per step, not in runs)
    elif a.threads == 1:
        # one thread would choose the serial mode: keep the parallel kernels instead
        e.threads = 2
        e.choose_loop_mode(e.count)
    times: dict[str, list] = {}

    def timed(name, f):
        def run(*args):
            ti.sync()
            t0 = time.perf_counter()
            out = f(*args)
            ti.sync()
            times.setdefault(name, []).append(time.perf_counter() - t0)
            return out
        return run

    try:
        sim.step(a.warmup)
        # the step's kernels of each holding variant (Engine.select_step hands one of them to
        # the step after every rebuild: wrapping only the current ones was undone there)
        for variant in e._variants.values():
            if "pairs" in variant:
                pair, gather, *rest = variant["pairs"]
                variant["pairs"] = (timed("pair", pair), timed("gather", gather), *rest)
        e.select_step()
        bp = e.broadphase
        if a.fused_rebuild:
            parallel_rebuild = bp.rebuild

            def fused(n):
                # the broadphase takes its one-launch path in the serial mode
                e.serial = True
                try:
                    return parallel_rebuild(n)
                finally:
                    e.serial = False
            bp.rebuild = fused
        if a.rebuild_parts:
            for k in ("_save_rows", "_save_pairs", "_sort_by_cell", "_permute",
                      "_find_candidates", "_compact", "_link_and_carry"):
                setattr(bp, k, timed(k.strip("_"), getattr(bp, k)))
        else:
            bp.rebuild = timed("fused rebuild" if a.fused_rebuild else "rebuild", bp.rebuild)
        t0 = time.perf_counter()
        sim.step(a.steps)
        ti.sync()
        wall = time.perf_counter() - t0
        n = sim.particle_count
        kind = "serial kernels" if a.serial else "parallel kernels"
        print(f"chute {a.size} ({n} particles), {a.threads} thread(s), {kind}: "
              f"{n * a.steps / wall / 1e6:.2f} M particle-steps/s, {1e3 * wall / a.steps:.3f} ms "
              f"per step")
        for name, v in times.items():
            v = 1e3 * np.array(v)
            print(f"  {name:15s} {len(v):4d} launches: median {np.median(v):.3f} ms, min "
                  f"{v.min():.3f}, p90 {np.percentile(v, 90):.3f}, mean {v.mean():.3f}; "
                  f"{v.sum() / a.steps:.3f} ms per step")
    finally:
        sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
