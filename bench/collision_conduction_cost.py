#!/usr/bin/env python3
"""What Sun & Chen's collision conduction costs per step (issue 32): the small drum demo
(demos/small_drum.toml: 400 softened glass beads of 8 mm, 4 flights, 20 rpm, f32) with
[thermal] conduction between particles and to the shell (held at 350 K), stepped with
``contact_conduction_model`` "steady" (the default) and "collision" (pairs and the shell) in
alternated rounds, one thread; medians of the seconds per step.

    TI_OFFLINE_CACHE_FILE_PATH=/tmp/ticache_collision .venv/bin/python bench/collision_conduction_cost.py
"""
import argparse
import pathlib
import statistics
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]


def scene(model):
    text = (ROOT / "demos" / "small_drum.toml").read_text()
    text = text.replace("youngs_modulus = 5.0e7\n", "youngs_modulus = 5.0e7\nreal_youngs_modulus = "
                        "6.3e10\nthermal_conductivity = 1.0\nheat_capacity = 840.0\n")
    text = text.replace("youngs_modulus = 2.0e11\n", "youngs_modulus = 2.0e11\n"
                        "thermal_conductivity = 45.0\nheat_capacity = 460.0\n")
    text = text.replace("count = 400\n", "count = 400\ntemperature = 300.0\n")
    # the shell held at 350 K: wall conduction, and with "collision" the wall variant too
    text = text.replace('name = "drum"\nmaterial = "steel"\n',
                        'name = "drum"\nmaterial = "steel"\ntemperature = 350.0\n')
    text += (f'\n[thermal]\nconduction = true\nwall_conduction = true\n'
             f'contact_conduction_model = "{model}"\n')
    return text


def seconds_per_step(model, steps):
    import taichi_dem
    with taichi_dem.Simulation.from_text(scene(model), threads=1) as sim:
        sim.run(0.3)                      # fill falls and the drum turns; compile
        t0 = time.perf_counter()
        sim.step(steps)
        return (time.perf_counter() - t0) / steps


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=2000)
    a = ap.parse_args()
    times = {"steady": [], "collision": []}
    for _ in range(a.rounds):
        for model in times:
            times[model].append(seconds_per_step(model, a.steps))
    base = statistics.median(times["steady"])
    for model, values in times.items():
        median = statistics.median(values)
        print(f"{model:10s} {median * 1e6:8.1f} us/step ({median / base:.3f}x)  "
              f"rounds: {', '.join(f'{v * 1e6:.1f}' for v in values)}")


if __name__ == "__main__":
    main()
