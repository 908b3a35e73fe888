#!/usr/bin/env python3
"""The neighbour search's two stencils on one chute, in one process: 9 runs of three cells
along z (the default where z is not periodic) against the 27 cells one by one (the path of a
periodic z), two simulations of the same scene stepped in alternating 100-step windows. Each
``find_candidates`` launch is timed (synchronised); the step rates are compared window by
window. The two list the same candidates in the same order, so the states stay equal bit
for bit (printed).

    .venv/bin/python bench/search_ab.py 32k 20      # size, windows per simulation
"""
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
import numpy as np

from chute_scene import write_chute_scene  # noqa: E402

SIZES = {"8k": dict(max_particles=8000), "32k": dict(copies=1), "128k": dict(copies=4)}


def main(argv) -> int:
    import taichi as ti
    import taichi_dem as td
    size, windows = argv[0], int(argv[1])
    scene = write_chute_scene(Path(tempfile.mkdtemp()) / size, **SIZES[size])
    sims, times, rates = {}, {}, {}
    for name in ("runs", "cells"):
        sim = td.Simulation.from_toml(str(scene), precision="f32", h5="")
        sim.engine.worker_pool.stall_limit = None      # keep the workers, whatever the host does
        bp = sim.engine.broadphase
        if name == "cells":
            # the 27-cell stencil, as compiled for a periodic z (the chute's z faces are far
            # from every particle, so the wrap adds no candidate: checked by the bitwise test)
            periodic = sim.engine.model.grid.periodic
            sim.engine.model.grid.periodic = (periodic[0], periodic[1], 1)
            bp._compile_search(bp.scratch_width)
            bp._compact = bp._make_compact(sim.engine.pairs)     # reads the new scratch
            sim.engine.model.grid.periodic = periodic
        search = bp._find_candidates

        def timed(*args, search=search, name=name):
            ti.sync()
            t0 = time.perf_counter()
            out = search(*args)
            ti.sync()
            times.setdefault(name, []).append(time.perf_counter() - t0)
            return out
        bp._find_candidates = timed
        sim.step(60)                     # JIT
        sims[name] = sim
    times.clear()
    for w in range(windows):
        order = list(sims.items()) if w % 2 == 0 else list(reversed(sims.items()))
        for name, sim in order:
            t0 = time.perf_counter()
            sim.step(100)
            ti.sync()
            rates.setdefault(name, []).append(sim.particle_count * 100 / (time.perf_counter() - t0))
    a, b = (sims[k].engine.state for k in ("runs", "cells"))
    print("states equal bit for bit:",
          np.array_equal(a.position.to_numpy(), b.position.to_numpy())
          and np.array_equal(a.velocity.to_numpy(), b.velocity.to_numpy()))
    for name in sims:
        print(f"{size} {name}: find_candidates median {1e3 * statistics.median(times[name]):.2f} ms "
              f"({len(times[name])} launches), steps median {statistics.median(rates[name]) / 1e6:.2f} M/s")
    print("runs / cells, median of the windows' ratios:",
          round(statistics.median(x / y for x, y in zip(rates["runs"], rates["cells"])), 3))
    for sim in sims.values():
        sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
