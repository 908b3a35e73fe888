"""What the coarse-grained wall law gives and costs on the paddle cooler (issue 10 item 6).

    .venv/bin/python bench/cooler_coarse_grained.py --until 12 \
        --variants none 100 30 300 100:0.35 100:0.5

Runs demos/paddle_cooler.toml (f32, seed 1) to ``--until`` s for each variant: ``none`` = the
ash as 30 mm spheres (spot + gas-gap laws to the shell, the demo before the law), ``D`` = the
ash standing for D um particles (bed porosity 0.4), ``D:P`` = bed porosity P. Prints over the
last third of the run: the shell's heat flow (W), its wall-to-bed coefficient (W/(m^2 K)), the
outlet's temperature drop below the feed (K), the seed's 6 m cooler estimated from it
(analysis.longer_cooler_outlet at the run's feed rate), the energy balance and the wall time
(stepping only; the whole run on one machine, nothing else running).
"""
import argparse
import re
import time
from pathlib import Path

import numpy as np

import taichi_dem as td
from taichi_dem.app import analysis

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "demos" / "paddle_cooler.toml"
LAW = re.compile(r'coarse_grained = \{ represented_diameter = "100 um", bed_porosity = 0.4 \}\n')


def scene_text(variant: str) -> str:
    text = SCENE.read_text()
    assert LAW.search(text), "the demo's coarse_grained line changed: update this script"
    if variant == "none":
        return LAW.sub("", text)
    diameter, _, porosity = variant.partition(":")
    return LAW.sub(f'coarse_grained = {{ represented_diameter = "{diameter} um", '
                   f'bed_porosity = {porosity or "0.4"} }}\n', text)


def run(variant: str, until: float) -> dict:
    text = scene_text(variant)
    t0 = time.perf_counter()
    with td.Simulation.from_text(text, base_dir=str(SCENE.parent), h5="") as sim:
        sim.run(until)
        wall = time.perf_counter() - t0
        s = sim.series
        late = s["time"] >= until * 2 / 3
        shell = next(b for b in sim.scene.bodies if b.name == "shell")
        feed = sim.scene.factories[0]
        q = np.asarray(s["bodies/shell/heat_flow"], float)[late]
        est = analysis.longer_cooler_outlet(
            q, float(np.ptp(np.asarray(shell.vertices, float)[:, 0])),
            np.asarray(s["particles/mean_temperature"], float)[late], shell.temperature,
            feed.temperature, feed.mass_rate.at(sim.time),
            sim.scene.materials[feed.material].heat_capacity, 6.0)
        outlet = np.asarray(s["outlets/discharge/mean_temperature"], float)[late]
        loss = float(s["thermal/particle_heat_loss"][-1])
        into = float(s["thermal/wall_heat"][-1])
        return {"variant": variant, "shell_heat_flow": float(np.mean(q)),
                "htc": float(np.nanmean(np.asarray(s["bodies/shell/heat_transfer_coefficient"])[late])),
                "outlet_drop": feed.temperature - float(np.nanmean(outlet)),
                "full_outlet_c": est["outlet_temperature"] - 273.15,
                "full_outlet_error": est["outlet_temperature_error"],
                "balance": abs(loss - into) / max(abs(into), 1e-30), "wall": wall}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--until", type=float, default=12.0)
    ap.add_argument("--variants", nargs="+", default=["none", "100", "30", "300"])
    a = ap.parse_args()
    print("| variant | shell W | h W/(m^2 K) | outlet drop K | 6 m cooler outlet C | balance | wall s |")
    print("|---|---|---|---|---|---|---|")
    for v in a.variants:
        r = run(v, a.until)
        print(f"| {v} | {r['shell_heat_flow']:.4g} | {r['htc']:.3g} | {r['outlet_drop']:.2f} | "
              f"{r['full_outlet_c']:.1f} +- {r['full_outlet_error']:.1f} | {r['balance']:.1e} | "
              f"{r['wall']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
