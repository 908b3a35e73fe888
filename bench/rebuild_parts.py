#!/usr/bin/env python3
"""What a neighbour rebuild of the chute costs, part by part, on the workers' machine
(issue 14): after ``--warmup`` steps (the particles in cell order, so that each repeated
rebuild does the same work),

1. each of the parallel kernels of the rebuild at the particle count and at n = 0 (its loops
   dispatched to Taichi's thread pool with nothing to do: what the dispatches alone cost);
2. each stage's body per particle in one serial loop (what a core spends on it);
3. the whole rebuild as separate kernels and on the workers (Broadphase.rebuild_on_workers).

Medians of ``--repeats`` synchronised launches each.

    .venv/bin/python bench/rebuild_parts.py --size 32k --threads 2
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

SIZES = {"8k": dict(max_particles=8000), "32k": dict(copies=1), "128k": dict(copies=4)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", default="32k", choices=list(SIZES))
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--warmup", type=int, default=100)
    p.add_argument("--repeats", type=int, default=30)
    a = p.parse_args(argv)
    import taichi as ti
    import taichi_dem as td
    scene = write_chute_scene(Path(tempfile.mkdtemp()) / a.size, **SIZES[a.size])
    sim = td.Simulation.from_toml(str(scene), threads=a.threads, precision="f32", h5="")
    e = sim.engine
    bp = e.broadphase
    try:
        sim.step(a.warmup)
        n = e.count

        def median_ms(f, *args):
            v = []
            for _ in range(a.repeats):
                ti.sync()
                t0 = time.perf_counter()
                f(*args)
                ti.sync()
                v.append(time.perf_counter() - t0)
            return 1e3 * statistics.median(v)

        print(f"chute {a.size}: {n} particles, grid {bp.grid.dims} ({bp.grid.n_cells} cells), "
              f"{a.threads} thread(s), workers {e.workers}")
        f = bp.row_funcs

        cells = bp.grid.n_cells

        def serial_loop(body, over_cells=False):
            @ti.kernel
            def k(n: ti.i32):
                ti.loop_config(serialize=True)
                for i in range(cells if ti.static(over_cells) else n):
                    body(i)
            return k

        @ti.func
        def save(i):
            f["save_row"](i)
            f["save_pair_row"](i)

        @ti.func
        def search(i):
            f["search_row"](i)

        @ti.kernel
        def sort(n: ti.i32):
            ti.loop_config(serialize=True)
            for c in range(cells):
                f["clear_cell"](c)
            ti.loop_config(serialize=True)
            for i in range(n):
                f["bin_particle"](i)
            f["put_in_cell_order"](n)

        @ti.kernel
        def place(n: ti.i32):
            # (the cells' fill counters back to zero first: a cheap loop)
            ti.loop_config(serialize=True)
            for c in range(cells):
                bp.cell_fill[c] = 0
            f["put_in_cell_order"](n)

        @ti.kernel
        def start_rows(n: ti.i32):
            f["start_rows"](n)
        # (each repeatable: the sort whole, or its serial part with its counters reset)
        serial = [("save_row + save_pair_row", serial_loop(save)),
                  ("sort: clear, bin, place", sort),
                  ("  of which place (serial)", place),
                  ("search_row", serial_loop(search)),
                  ("start_rows (serial scan)", start_rows),
                  ("compact_row", serial_loop(f["compact_row"])),
                  ("link_row", serial_loop(f["link_row"]))]
        # (1) the kernels, at n and at 0 (last; a rebuild then restores the state)
        print("the parallel kernels (ms): at n, at n = 0 (the dispatches alone)")
        kernels = ("_save_rows", "_save_pairs", "_sort_by_cell", "_permute", "_find_candidates",
                   "_compact", "_link_and_carry")
        at_n, at_0 = {}, {}
        for k in kernels:
            # (after a rebuild the particles are in cell order: the sort's order is the
            # identity, and a repeated permute moves nothing while doing all its work)
            bp.rebuild(n)
            bp._sort_by_cell(n)
            at_n[k] = median_ms(getattr(bp, k), n)
        for k in kernels:
            at_0[k] = median_ms(getattr(bp, k), 0)
        bp.rebuild(n)
        for k in kernels:
            print(f"  {k.strip('_'):18s} {at_n[k]:7.3f} {at_0[k]:7.3f}")
        print(f"  {'sum':18s} {sum(at_n.values()):7.3f} {sum(at_0.values()):7.3f}")
        # (2) each body in one serial loop
        print("each stage's body, one serial loop (ms)")
        total = 0.0
        for name, k in serial:
            t = median_ms(k, n)
            total += 0.0 if name.startswith(" ") else t
            print(f"  {name:28s} {t:7.3f}")
        print(f"  {'sum (without the moves of permute)':28s} {total:7.3f}")
        bp.rebuild(n)
        # (3) the whole rebuild both ways
        whole = {}
        for on_workers in (False, True, False, True):
            e.rebuilds_on_workers = on_workers
            whole.setdefault(on_workers, []).append(median_ms(bp.rebuild, n))
        e.rebuilds_on_workers = True
        print(f"whole rebuild (ms): separate kernels {statistics.median(whole[False]):.3f}, "
              f"on the workers {statistics.median(whole[True]):.3f}"
              + ("" if e.workers else " (no workers: the same path)"))
    finally:
        sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
