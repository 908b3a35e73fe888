"""What thermal time scaling costs in accuracy on the paddle cooler (issue 10 item 3).

    .venv/bin/python bench/cooler_time_scale.py --until 12 --scales 1 4 16

Runs demos/paddle_cooler.toml (f32, seed 1) to ``--until`` s at each ``[thermal] time_scale``
S and prints, over the last third of the run: the ash's outlet temperature drop below the feed
(K), that drop over S (what one unit of thermal time does: constant if scaling were exact), the
shell's heat flow (W), its wall-to-bed coefficient (W/(m^2 K)), the energy balance and the wall
time. Heat flows are physical (W), so at steady state the shell's heat flow should be the
same at every S while the bed's temperature is near the feed's; the drop per unit S falls as
the bed cools (less driving difference) and as the shell sees each particle S times longer in
thermal time (a longer contact, a lower coefficient: the penetration effect scaling leaves out).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

import taichi_dem as td
from taichi_dem.app.summaries import process_summary

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "demos" / "paddle_cooler.toml"


def run(scale: float, until: float) -> dict:
    text = SCENE.read_text()
    if scale != 1.0:
        text = text.replace("gas_gap = true\n", f"gas_gap = true\ntime_scale = {scale!r}\n")
    t0 = time.perf_counter()
    with td.Simulation.from_text(text, base_dir=str(SCENE.parent), h5="") as sim:
        sim.run(until)
        wall = time.perf_counter() - t0
        out = process_summary(sim, window=1 / 3)
        s = sim.series
        tail = s["time"] >= until * 2 / 3
        q = float(np.mean(np.asarray(s["bodies/shell/heat_flow"])[tail]))
        h = float(np.nanmean(np.asarray(s["bodies/shell/heat_transfer_coefficient"])[tail]))
    feed = 723.15
    drop = feed - out.get("discharge/temperature", float("nan"))
    return {"scale": scale, "drop": drop, "drop_per_scale": drop / scale, "shell_heat_flow": q,
            "coefficient": h, "balance": out.get("energy_balance_error", float("nan")),
            "wall": wall}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--until", type=float, default=12.0)
    p.add_argument("--scales", type=float, nargs="+", default=[1.0, 4.0, 16.0])
    a = p.parse_args(argv)
    rows = [run(s, a.until) for s in a.scales]
    print("| time_scale | outlet drop K | drop / S | shell heat flow W | h W/(m^2 K) | "
          "energy balance | wall s |\n|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scale']:g} | {r['drop']:.3f} | {r['drop_per_scale']:.4f} | "
              f"{r['shell_heat_flow']:.4g} | {r['coefficient']:.4g} | {r['balance']:.2%} | "
              f"{r['wall']:.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
