#!/usr/bin/env python3
"""Cost of checkpoints, of the last-good-state snapshot and of the divergence check, on the
meshes benchmark's drum (bench/mesh_drum.py: flights and a paddle shaft).

    python bench/checkpoint_cost.py --particles 20000 --steps 2000 --samples 10 --repeats 3

After settling, the same simulation runs ``--steps`` steps with ``--samples`` output samples
in three modes, interleaved, ``--repeats`` times each (after one uncounted round that
compiles): "off" (no snapshot, no checkpoint),
"snapshot" (the state copied to host memory at every sample, the default) and "checkpoint"
(a checkpoint file written at every sample, the worst case of checkpoint_interval). Prints the
median wall time of each mode and the medians of the time spent inside the capture, the write
and the divergence check, per sample and as a fraction of the run.
"""
import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from mesh_drum import scene_text  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--particles", type=int, default=20000)
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--samples", type=int, default=10)
    p.add_argument("--settle", type=float, default=0.3, help="simulated seconds before timing")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--precision", default="f32")
    a = p.parse_args(argv)
    import taichi_dem as td

    sim = td.Simulation.from_text(scene_text(a.particles, a.precision), h5="")
    ck = sim.checkpointer
    ck.path = os.path.join(tempfile.mkdtemp(), "drum.checkpoint.h5")
    print(f"{sim.particle_count} particles, dt = {sim.dt:.3g} s; settling {a.settle} s", flush=True)
    sim.run(a.settle)
    sim.output_every = max(a.steps // a.samples, 1)
    results = {m: {"wall": [], "capture": [], "write": [], "check": []}
               for m in ("off", "snapshot", "checkpoint")}
    for r in range(a.repeats + 1):         # round 0 warms up (compiles), not counted
        for mode, res in results.items():
            ck.keep_last_good = mode == "snapshot"
            ck.interval = sim.output_every * sim.dt if mode == "checkpoint" else None
            ck._schedule(sim)
            s0, w0, c0 = ck.snapshot_seconds, ck.write_seconds, sim.divergence.seconds
            # align to a sample so every mode gets the same number of samples
            sim.step(sim.output_every - sim.step_count % sim.output_every)
            t0 = time.perf_counter()
            sim.step(a.steps)
            sim.engine.flags.to_numpy()
            if r == 0:
                continue
            res["wall"].append(time.perf_counter() - t0)
            res["capture"].append(ck.snapshot_seconds - s0)
            res["write"].append(ck.write_seconds - w0)
            res["check"].append(sim.divergence.seconds - c0)
        if r == 0:
            continue
        print(f"repeat {r}: " + ", ".join(f"{m} {res['wall'][-1]:.2f} s" for m, res in results.items()),
              flush=True)
    size = os.path.getsize(ck.path) / 2 ** 20
    n = a.steps // sim.output_every
    print(f"{a.steps} steps, {n} samples (one per {sim.output_every} steps = "
          f"{sim.output_every * sim.dt:.3g} s simulated); checkpoint file {size:.1f} MiB")
    base = statistics.median(results["off"]["wall"])
    for mode, res in results.items():
        wall = statistics.median(res["wall"])
        parts = {k: statistics.median(res[k]) for k in ("capture", "write", "check")}
        print(f"{mode:10s}: wall {wall:.2f} s ({wall / base - 1:+.1%} vs off); per sample: capture "
              f"{parts['capture'] / n * 1e3:.1f} ms, write {parts['write'] / n * 1e3:.1f} ms, "
              f"divergence check {parts['check'] / n * 1e3:.2f} ms; together "
              f"{sum(parts.values()) / wall:.2%} of the run")
    sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
