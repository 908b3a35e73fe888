#!/usr/bin/env python3
"""What ``[mobility]`` costs where nothing can freeze: the 32k chute (bench/chute.py's scene,
a flow over a frozen rough base, periodic in x and y) with and without the section, in
alternated rounds (off then on in even rounds, on then off in odd ones: this host's speed
drifts by 10 - 40 % over minutes, and a ratio of runs seconds apart is less exposed to it).

Reports particle-steps per second of each run (after ``--warmup`` steps, which include the
compilation), the share of particles mobility holds at the end (nothing should be held in a
flowing chute), and the median of the paired ratios on / off.

    python bench/mobility_cost.py --steps 1000 --rounds 5
"""
import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from chute_scene import write_chute_scene  # noqa: E402


def run(scene_text: str, base_dir: str, steps: int, warmup: int) -> dict:
    """One timed run: particle-steps per second after ``warmup`` steps, and the share held."""
    import taichi_dem as td
    sim = td.Simulation.from_text(scene_text, base_dir=base_dir, h5="")
    try:
        sim.step(warmup)
        t0 = time.perf_counter()
        sim.step(steps)
        sim.engine.flags.to_numpy()          # synchronise
        seconds = time.perf_counter() - t0
        n = sim.particle_count
        mobility = sim.engine.model.effect("mobility")
        held = mobility.statistics()["inactive_particles"] / n if mobility is not None else 0.0
        return dict(rate=n * steps / seconds, particles=n, held=held)
    finally:
        sim.close()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--warmup", type=int, default=50)
    p.add_argument("--rounds", type=int, default=5)
    a = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_chute_scene(Path(tmp) / "32k", copies=1)
        off = path.read_text()
        variants = {"off": off, "on": off + '\n[mobility]\nmode = "at_rest"\n'}
        runs = {"off": [], "on": []}
        for r in range(a.rounds):
            order = ("off", "on") if r % 2 == 0 else ("on", "off")
            for name in order:
                res = run(variants[name], str(path.parent), a.steps, a.warmup)
                runs[name].append(res)
                print(f"round {r + 1} mobility {name:>3s}: {res['rate'] / 1e6:6.2f} M "
                      f"particle-steps/s ({res['particles']} particles, {100 * res['held']:.1f} % "
                      "held)", flush=True)
    ratios = [y["rate"] / x["rate"] for x, y in zip(runs["off"], runs["on"])]
    print(f"\nmedians: off {statistics.median(x['rate'] for x in runs['off']) / 1e6:.2f}, on "
          f"{statistics.median(x['rate'] for x in runs['on']) / 1e6:.2f} M particle-steps/s; "
          f"on / off paired: median {statistics.median(ratios):.3f} "
          f"(rounds: {', '.join(f'{q:.3f}' for q in ratios)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
