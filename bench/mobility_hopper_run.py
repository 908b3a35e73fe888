#!/usr/bin/env python3
"""``[mobility]`` over a whole hopper run as a user would run it: seed 000's slot hopper filled
and left to settle for ``--settle`` s (0.45 s: the bed comes to rest only just before the slot
opens), then the slot opened and the bed discharged for ``--discharge`` s, each phase with
mobility on or off (the discharge starts from that variant's own bed). Wall time of the whole
run (both phases' stepping, compiling excluded by a first step), the discharge mass flow of
each, and the ratio off / on; variants alternated round by round (this host drifts).

    python bench/mobility_hopper_run.py --rounds 2
    python bench/mobility_hopper_run.py --rounds 4 --seeds 4    # four beds
"""
import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from taichi_dem.app import slot_hopper as sh
from taichi_dem.run.simulation import Simulation


def whole_run(folder: Path, mobility: bool, settle: float, discharge: float,
              seed: int = 1) -> dict:
    """Fill and settle (the fill placed with ``seed``), then discharge; wall seconds of each
    phase's stepping."""
    text = sh.scene_text(phase="fill", mobility=mobility, end_time=settle, seed=seed)
    with Simulation.from_text(text, base_dir=str(folder)) as sim:
        sim.step(1)
        t0 = time.perf_counter()
        sim.run()
        fill = time.perf_counter() - t0
        bed = folder / f"bed_{'on' if mobility else 'off'}.csv"
        sh.write_bed(sim, bed)
    rate, wall, _, _ = sh.discharge(bed, mobility=mobility, end_time=discharge)
    return dict(fill=fill, discharge=wall, total=fill + wall, rate=rate)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--settle", type=float, default=0.45)
    p.add_argument("--discharge", type=float, default=0.7)
    p.add_argument("--seeds", type=int, default=1,
                   help="round r fills its bed with seed 1 + r mod SEEDS: with more than one, "
                        "the discharge on / off is seen over several beds, not one pair")
    a = p.parse_args(argv)
    runs = {False: [], True: []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.rounds):
            for mobility in ((False, True) if r % 2 == 0 else (True, False)):
                res = whole_run(Path(tmp), mobility, a.settle, a.discharge,
                                seed=1 + r % a.seeds)
                runs[mobility].append(res)
                print(f"round {r + 1} mobility {'on ' if mobility else 'off'}: fill and settle "
                      f"{res['fill']:.1f} s, discharge {res['discharge']:.1f} s, whole run "
                      f"{res['total']:.1f} s; discharge {1e3 * res['rate']:.2f} g/s", flush=True)
    ratios = [x["total"] / y["total"] for x, y in zip(runs[False], runs[True])]
    discharge = [y["rate"] / x["rate"] for x, y in zip(runs[False], runs[True])]
    print(f"\nwhole run off / on, paired: median {statistics.median(ratios):.2f} (rounds "
          f"{', '.join(f'{q:.2f}' for q in ratios)}); discharge on / off "
          f"{statistics.median(discharge):.4f} (rounds "
          f"{', '.join(f'{q:.4f}' for q in discharge)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
