#!/usr/bin/env python3
"""The main demo's step (issue 14 item 2): where a small scene's time goes, in two phases of
demos/paddle_cooler.toml.

    .venv/bin/python bench/cooler_step.py --phase full --state /tmp/cooler45.h5
    .venv/bin/python bench/cooler_step.py --phase filling

``full``: the cooler at its hold-up (~1,170 particles, 13 t/h), from a state at t = 45 s
(written to ``--state`` by a first run of the demo scene, ~2 min, then reused); windows of
``--steps`` steps after 2,000 untimed ones. ``filling``: from t = 2 s to 8 s of a fresh run
(300 - 770 particles, 6.5 t/h), where fixed costs weigh most. Each window reports the wall
time per step, the neighbour rebuilds and the time in them (Engine.rebuild: the factories'
insertions at rebuilds included), and the factories' host time; medians over ``--repeats``
windows (``full``) or runs (``filling``, each in this process after the first's JIT).
"""
import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import taichi_dem  # noqa: E402
from taichi_dem.engine import stepper  # noqa: E402
from taichi_dem.run import checkpoint  # noqa: E402

SCENE = str(ROOT / "demos" / "paddle_cooler.toml")
rebuild_wall = [0.0]
_rebuild = stepper.Engine.rebuild


def timed_rebuild(self, n):
    t = time.perf_counter()
    try:
        return _rebuild(self, n)
    finally:
        rebuild_wall[0] += time.perf_counter() - t


stepper.Engine.rebuild = timed_rebuild


def window(sim, run):
    """Run ``run()``; (wall s, steps, rebuilds, rebuild wall s, factory wall s)."""
    s0, r0 = sim.step_count, sim.engine.broadphase.rebuilds
    w0, f0 = rebuild_wall[0], sim.factories.wall_seconds
    t = time.perf_counter()
    run()
    wall = time.perf_counter() - t
    return (wall, sim.step_count - s0, sim.engine.broadphase.rebuilds - r0,
            rebuild_wall[0] - w0, sim.factories.wall_seconds - f0)


def report(rows, particles):
    wall = statistics.median(r[0] for r in rows)
    steps = rows[0][1]
    print(f"{particles} particles at the end; medians of {len(rows)}: "
          f"{1e6 * wall / steps:.0f} us per step ({wall:.2f} s for {steps} steps), "
          f"{statistics.median(r[2] for r in rows):.0f} rebuilds "
          f"({1e3 * statistics.median(r[3] / max(r[2], 1) for r in rows):.2f} ms each, "
          f"{100 * statistics.median(r[3] / r[0] for r in rows):.0f} % of the wall), "
          f"factories {100 * statistics.median(r[4] / r[0] for r in rows):.0f} %")
    for r in rows:
        print(f"  window: {r[0]:.3f} s, {r[2]} rebuilds in {r[3]:.3f} s, factories {r[4]:.3f} s")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--phase", choices=("full", "filling"), default="full")
    ap.add_argument("--state", default="/tmp/cooler45.h5",
                    help="the state at t = 45 s (written if missing)")
    ap.add_argument("--steps", type=int, default=4000, help="steps per window (full)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--scene", default=SCENE, help="another scene file (default the demo's)")
    args = ap.parse_args(argv)
    scene = args.scene
    if args.phase == "filling":
        rows = []
        for _ in range(args.repeats):
            with taichi_dem.Simulation.from_toml(scene, h5="") as sim:
                sim.run(2.0)
                rows.append(window(sim, lambda: sim.run(8.0)))
                n = sim.particle_count
        report(rows, n)
        return
    if not os.path.exists(args.state):
        with taichi_dem.Simulation.from_toml(scene, h5="") as sim:
            t = time.perf_counter()
            sim.run(45.0)
            print(f"ran the demo scene to 45 s in {time.perf_counter() - t:.0f} s; "
                  f"state written to {args.state}", flush=True)
            checkpoint.write(args.state, checkpoint.capture(sim))
    sim = taichi_dem.Simulation.from_toml(scene, h5="")
    checkpoint.restore(sim, checkpoint.load(args.state))
    sim.step(2000)                      # JIT, first rebuilds
    rows = [window(sim, lambda: sim.step(args.steps)) for _ in range(args.repeats)]
    report(rows, sim.particle_count)
    sim.close()


if __name__ == "__main__":
    main()
