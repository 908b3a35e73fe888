#!/usr/bin/env python3
"""What split positions cost (engine/precision.py, issue 31 item 6): the seed's cooler slice
(demos/cooler_slice.toml, 30 kg/m: 4,878 spheres of 15 mm, f32) moved 3 m along its axis - a
slice of the middle of the 6 m machine - stepped with its positions split (the default beyond
1 m) and with the split switched off (model.SPLIT_POSITIONS_BEYOND raised), alternated.

    python bench/split_positions_cost.py [--rounds 3] [--seconds 0.3]

Prints M particle-steps/s of each run and the median ratio.
"""
import argparse
import statistics
import subprocess
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHIFT = 3.0


def one(split: bool, seconds: float) -> float:
    sys.path.insert(0, str(ROOT))
    from taichi_dem.engine import model
    from taichi_dem.app.overrides import apply, to_text
    import taichi_dem as td
    if not split:
        model.SPLIT_POSITIONS_BEYOND = 1e9
    doc = tomllib.loads((ROOT / "demos" / "cooler_slice.toml").read_text())
    doc["domain"]["min"][0] += SHIFT
    doc["domain"]["max"][0] += SHIFT
    doc["particles"][0]["count"] = 4878
    region = doc["particles"][0]["region"]["cylinder"]
    region["axis_point"][0] += SHIFT
    for body in doc["bodies"]:
        # the builders place their axis from x = 0: moved with the domain (and the pivot)
        body["mesh"]["origin"] = [SHIFT, 0.0, 0.0]
        if "motion" in body:
            body["motion"]["rotate"]["axis_point"][0] += SHIFT
    text = to_text(doc)
    with td.Simulation.from_text(text, h5="") as sim:
        assert sim.engine.model.split_positions == split
        sim.run(0.2)
        n = sim.particle_count
        t0 = time.perf_counter()
        steps = int(round(seconds / sim.engine.model.dt))
        sim.run(sim.time + seconds)
        return n * steps / (time.perf_counter() - t0) / 1e6


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--seconds", type=float, default=0.3)
    p.add_argument("--one", choices=["split", "plain"])
    a = p.parse_args()
    if a.one:
        print(f"{one(a.one == 'split', a.seconds):.3f}")
        return 0
    rates = {"split": [], "plain": []}
    for r in range(a.rounds):
        for which in (("split", "plain") if r % 2 == 0 else ("plain", "split")):
            out = subprocess.run([sys.executable, __file__, "--one", which, "--seconds",
                                  str(a.seconds)], capture_output=True, text=True, check=True)
            rates[which].append(float(out.stdout.strip().splitlines()[-1]))
            print(f"round {r + 1} {which}: {rates[which][-1]:.3f} M particle-steps/s", flush=True)
    s, q = statistics.median(rates["split"]), statistics.median(rates["plain"])
    print(f"median split {s:.3f}, plain {q:.3f} M particle-steps/s: split/plain {s / q:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
