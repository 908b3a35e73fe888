#!/usr/bin/env python3
"""Periodic drum slice: what taking the particle image nearest the whole triangle costs.

A rotating drum slice, periodic along its axis, whose shell triangles span the whole slice
(the case tests/stability/test_periodic_slices.py checks). Reports particle-steps per second
of the stepping (compilation and settling excluded), median of ``--repeats`` timed windows.
Run it against another checkout in the same session to compare (``--code DIR`` puts DIR first
on sys.path, e.g. a git worktree of an older commit):

    python bench/periodic_slice.py --particles 4000 --steps 400 --repeats 5
    python bench/periodic_slice.py --particles 4000 --steps 400 --repeats 5 --code /tmp/old
"""
import argparse
import statistics
import sys
import time


def scene_text(particles: int, radius: float, slice_length: float, drum_radius: float) -> str:
    """The drum slice scene (glass beads, steel shell with four flights, 20 rpm)."""
    return f"""
[simulation]
end_time = 100.0
gravity = [0.0, 0.0, -9.81]
precision = "f32"
seed = 1
[domain]
min = [0.0, {-drum_radius - 0.005}, {-drum_radius - 0.005}]
max = [{slice_length}, {drum_radius + 0.005}, {drum_radius + 0.005}]
periodic = ["x"]
[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5
[[bodies]]
name = "shell"
material = "steel"
mesh = {{ builder = "drum", radius = {drum_radius}, length = {slice_length}, end_walls = false, flights = 4, flight_height = {0.2 * drum_radius} }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "20 rpm" }} }}
[[particles]]
material = "glass"
radius = {radius}
count = {particles}
region = {{ cylinder = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], length = {slice_length}, radius = {0.75 * drum_radius} }} }}
[output]
interval = 0.05
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, default=4000)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--settle", type=float, default=0.1, help="simulated seconds before timing")
    ap.add_argument("--code", default=None, help="checkout to import taichi_dem from")
    args = ap.parse_args(argv)
    if args.code:
        sys.path.insert(0, args.code)
    import taichi_dem as td

    radius = 0.002
    # a slice 10 diameters long; the drum sized so the particles fill ~35 % of it
    slice_length = 20 * radius
    solid = args.particles * 4.0 / 3.0 * 3.14159 * radius ** 3 / 0.6
    drum_radius = (solid / (0.35 * 3.14159 * slice_length)) ** 0.5
    text = scene_text(args.particles, radius, slice_length, drum_radius)
    with td.Simulation.from_text(text, arch="cpu", precision="f32") as sim:
        sim.step(max(1, int(args.settle / sim.dt)))
        rates = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            sim.step(args.steps)
            wall = time.perf_counter() - t0
            rates.append(sim.particle_count * args.steps / wall)
        print(f"periodic drum slice: {sim.particle_count} particles, dt {sim.dt:.3g} s, "
              f"median {statistics.median(rates) / 1e6:.3f} M particle-steps/s "
              f"(runs: {', '.join(f'{r / 1e6:.3f}' for r in rates)}) code={args.code or 'this'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
