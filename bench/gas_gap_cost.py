#!/usr/bin/env python3
"""What the gas-gap laws cost per step on the drum of 2 mm glass beads (issue 32 item 3): the
wall-heat experiment's scene (tests/verification/drum_wall_heat.py: a 0.1 m slice 5 mm long,
16 low lifters, 20 % fill, 12 rpm, f64, one thread) stepped with each law in turn, rounds
alternated, medians reported in particle-steps per second and as a ratio against the former
default ("solid_resistance", lens 0.2 R).

    .venv/bin/python bench/gas_gap_cost.py --rounds 3 --steps 2000

Variants: mechanics and contact conduction only (no gas gap), the former default, and
"schlunder" at lens 0.2 and its default 0.4 (the wall law's transient ratio and the pairs'
resolved shares, from the tables, in both).
"""
import argparse
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "verification"))

VARIANTS = {
    "no gas gap": dict(model="solid_resistance", gas_gap=False),
    "solid_resistance, lens 0.2 (former default)": dict(model="solid_resistance", lens=0.2),
    "schlunder, lens 0.2": dict(model="schlunder", lens=0.2),
    "schlunder, lens 0.4 (default)": dict(model="schlunder", lens=0.4),
}


def scene(model, lens=0.2, gas_gap=True):
    from drum_wall_heat import fill_count, scene_text
    count = fill_count(0.05, 0.005, 0.2, 1e-3)
    text = scene_text(length=0.005, count=count, rpm_mech=12.0, model=model, lens=lens,
                      dt=2.5e-5, output_interval=1.0, flights=16, flight_height=1e-3)
    if not gas_gap:
        text = "\n".join(x for x in text.splitlines()
                         if not x.startswith(("gas_gap", "gap_gas")))
    return text, count


def rate(name, steps):
    import taichi_dem
    text, count = scene(**VARIANTS[name])
    with taichi_dem.Simulation.from_text(text, precision="f64", threads=1) as sim:
        sim.run(0.3)                      # settle; compile
        n = sim.particle_count
        t0 = time.perf_counter()
        sim.step(steps)
        seconds = time.perf_counter() - t0
    return n * steps / seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=2000)
    a = ap.parse_args()
    rates = {k: [] for k in VARIANTS}
    for r in range(a.rounds):
        for name in VARIANTS:
            rates[name].append(rate(name, a.steps))
            print(f"round {r + 1}: {name}: {rates[name][-1] / 1e6:.3f} M particle-steps/s",
                  flush=True)
    base = statistics.median(rates["solid_resistance, lens 0.2 (former default)"])
    print("\n| law | M particle-steps/s (median) | vs former default |\n|---|---|---|")
    for name, values in rates.items():
        m = statistics.median(values)
        print(f"| {name} | {m / 1e6:.3f} | {m / base:.2f}x |")


if __name__ == "__main__":
    main()
