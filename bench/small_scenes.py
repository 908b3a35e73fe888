#!/usr/bin/env python3
"""Small scenes and the engine's loop modes (issue 14 item 2): the stepping time of a scene run
to ``--until`` in each mode, medians of ``--repeats`` runs, each in a fresh process (the
Taichi runtime takes its thread count once per process).

    .venv/bin/python bench/small_scenes.py demos/dryer_drum.toml --until 2 --repeats 3
    .venv/bin/python bench/small_scenes.py demos/paddle_cooler.toml --until 8

Modes (engine/stepper.py): ``runs`` - the default below 5,000 particles: every loop on one
thread, several whole steps per launch (Engine.run_steps); ``parallel`` - parallel_from = 0:
two parallel launches per step on every thread; ``serial-steps`` - one thread, one step per
launch (the serial loops without the runs), to show what each part gives. Stepping time is the
simulation's own wall time in ``step`` (JIT included: the first steps compile the kernels),
and set-up is excluded; ``--warm`` first runs a short stretch (not timed) so that the figures
exclude the JIT.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import json, sys, time
sys.path.insert(0, {root!r})
import taichi_dem as td
import taichi_dem.engine.stepper as stepper
mode, scene, until, warm = {mode!r}, {scene!r}, {until!r}, {warm!r}
kw = dict(h5="")
if mode == "parallel":
    kw["parallel_from"] = 0
if mode == "serial-steps":
    kw["threads"] = 1
sim = td.Simulation.from_toml(scene, **kw)
if mode == "serial-steps":
    sim.engine.runs = False
if warm:
    sim.run(until=warm)
w0, s0 = sim.wall_seconds, sim.step_count
particle_steps = 0
t_end = until
while sim.time < t_end - 0.5 * sim.dt:
    k = min(200, int(round((t_end - sim.time) / sim.dt)))
    sim.step(k)
    particle_steps += k * sim.particle_count
wall = sim.wall_seconds - w0
print(json.dumps(dict(mode=mode, wall=wall, steps=sim.step_count - s0,
                      particle_steps=particle_steps, particles=sim.particle_count,
                      serial=sim.engine.serial)))
sim.close()
"""


def run(mode: str, scene: str, until: float, warm: float) -> dict:
    code = CHILD.format(root=str(ROOT), mode=mode, scene=scene, until=until, warm=warm)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    if r.returncode != 0:
        raise SystemExit(r.stderr[-3000:])
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene")
    p.add_argument("--until", type=float, required=True, help="simulated time to run to, s")
    p.add_argument("--warm", type=float, default=0.0, help="untimed stretch first, s")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--modes", nargs="+", default=["runs", "parallel"],
                   choices=["runs", "parallel", "serial-steps"])
    a = p.parse_args(argv)
    rows = {m: [] for m in a.modes}
    for _ in range(a.repeats):             # interleaved: the machine's noise hits every mode
        for m in a.modes:
            rows[m].append(run(m, a.scene, a.until, a.warm))
    print(f"{a.scene}, t = {a.warm:g} .. {a.until:g} s, medians of {a.repeats}:")
    print("| mode | stepping wall s | us per step | M particle-steps/s | particles at the end |")
    print("|---|---|---|---|---|")
    for m, runs in rows.items():
        wall = statistics.median(r["wall"] for r in runs)
        steps = runs[0]["steps"]
        rate = statistics.median(r["particle_steps"] / r["wall"] for r in runs)
        print(f"| {m} | {wall:.2f} | {wall / steps * 1e6:.0f} | {rate / 1e6:.3f} | "
              f"{runs[0]['particles']:,} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
