"""A packed bed of 6.4 mm steel spheres heated from one wall for an hour, against Beaulieu's
measurements (issue 32 item 2; the data and their source: tests/reference/beaulieu_heated_bed/).

The measured bed: 8849 spheres in a 0.1 x 0.105 m box about 0.2 m deep. One wall was switched
from 20 C to 53 C and held for 4000 s, and thermocouples on the centre line read the
temperature 0.040, 0.060 and 0.073 m from it. Here:

- The box is periodic across, 8 diameters each way (the thermocouples sat on the centre line,
  away from the side walls), and 0.15 m deep. The heat front moves ~3 sqrt(a t) ~ 9 cm in the
  hour, so the far, insulated end sees almost nothing.
- The spheres settle under gravity onto the heated plate (in the experiment the plate was
  pressed onto the bed). All are then set to 20 C, the plate standing at 53 C: the wall
  switched on.
- Thermal time scaling S = 1000 (exact for a bed at rest, tests/verification/test_time_scale.py)
  brings the hour into 4 s simulated.
- The temperature at a depth is the mean of the spheres whose centres lie within half a
  diameter of it, over the whole cross-section.

    .venv/bin/python tests/verification/heated_bed.py [--model schlunder] [--json out.json]
"""
from __future__ import annotations

import math
import pathlib
import time as _time

import numpy as np

import taichi_dem

DATA = pathlib.Path(__file__).resolve().parents[1] / "reference" / "beaulieu_heated_bed"
DEPTHS = (0.040, 0.060, 0.073)
T_BED, T_WALL = 293.15, 326.15
DIAMETER = 6.4e-3
STEEL = dict(density=7747.0, youngs=200e9, poisson=0.29, k=42.0, c=464.0)


def measured(depth: float, kind: str = "experiment") -> np.ndarray:
    """(n, 2): t (s), T (K) of the measurement at ``depth`` (m); kind "experiment",
    "band_upper" or "band_lower"."""
    table = np.loadtxt(DATA / f"{depth:.3f}_{kind}.csv", delimiter=",", skiprows=1)
    return np.column_stack([table[:, 0], table[:, 1] + 273.15])


def measured_at(depth: float, t: float, kind: str = "experiment", window: float = 150.0):
    """The measurement near time ``t`` (s): the mean of its points within +- window (the
    digitised thermocouple readings scatter by ~0.3 K from point to point)."""
    data = measured(depth, kind)
    near = np.abs(data[:, 0] - t) <= window
    if not np.any(near):
        return float(np.interp(t, data[:, 0], data[:, 1]))
    return float(np.mean(data[near, 1]))


def scene_text(model: str, width: float, depth: float, count: int, time_scale: float,
               friction: float = 0.5) -> str:
    s = STEEL
    r = 0.5 * DIAMETER
    return f"""
[simulation]
end_time = 100.0
gravity = [0.0, 0.0, -9.81]
precision = "f64"
seed = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [{width!r}, {width!r}, {depth + 0.1!r}]
periodic = ["x", "y"]
[materials.steel]
density = {s['density']!r}
youngs_modulus = 5e7
real_youngs_modulus = {s['youngs']!r}
poisson_ratio = {s['poisson']!r}
thermal_conductivity = {s['k']!r}
heat_capacity = {s['c']!r}
[materials.plate]
density = 2700.0
youngs_modulus = 5e7
real_youngs_modulus = 70e9
poisson_ratio = 0.33
thermal_conductivity = 250.0
heat_capacity = 900.0
[[interactions]]
pair = ["steel", "steel"]
restitution = 0.3
friction = {friction!r}
rolling_friction = 0.02
[[interactions]]
pair = ["steel", "plate"]
restitution = 0.3
friction = {friction!r}
rolling_friction = 0.02
[[walls]]
name = "heated_plate"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "plate"
temperature = {T_WALL!r}
[[particles]]
material = "steel"
radius = {r!r}
count = {count}
temperature = {T_BED!r}
region = {{ box = {{ min = [0.0, 0.0, {r!r}], max = [{width!r}, {width!r}, {depth + 0.1 - r!r}] }} }}
[thermal]
conduction = true
wall_conduction = true
gas_gap = true
gap_gas_conductivity = 0.027
gas_gap_model = "{model}"
time_scale = {time_scale!r}
[output]
interval = 0.05
"""


def heated_bed(model: str = "schlunder", width_diameters: float = 8.0, depth: float = 0.15,
               porosity: float = 0.42, time_scale: float = 1000.0, settle: float = 0.8,
               duration: float = 4000.0, sample: float = 100.0, threads=None) -> dict:
    """Run the experiment; returns the sampled thermal times (s), the temperature (K) at each
    of DEPTHS (one row per depth), the bed's porosity below 0.1 m, the count, the wall time."""
    width = width_diameters * DIAMETER
    volume = math.pi / 6.0 * DIAMETER ** 3
    count = int(round((1.0 - porosity) * width * width * depth / volume))
    text = scene_text(model, width, depth, count, time_scale)
    t0 = _time.perf_counter()
    kwargs = {} if threads is None else {"threads": threads}
    with taichi_dem.Simulation.from_text(text, precision="f64", **kwargs) as sim:
        sim.run(settle)
        s = sim.engine.state
        n = sim.engine.count
        temperature = s.temperature.to_numpy()
        temperature[:n] = T_BED
        s.temperature.from_numpy(temperature)
        start = sim.time
        times, rows = [0.0], [[T_BED] * len(DEPTHS)]
        z = sim.particles()["position"][:, 2]
        while sim.time < start + duration / time_scale - 1e-9:
            sim.run(sim.time + sample / time_scale)
            p = sim.particles()
            z, t = p["position"][:, 2], p["temperature"]
            times.append((sim.time - start) * time_scale)
            rows.append([float(np.mean(t[np.abs(z - h) <= 0.5 * DIAMETER])) for h in DEPTHS])
        lost = n - sim.particle_count
    # porosity of the bed's lower 0.1 m (sphere parts inside the slab)
    lo, hi = 0.02, 0.1
    solid = 0.0
    r = 0.5 * DIAMETER
    for zc in z:
        a, b = max(lo, zc - r), min(hi, zc + r)
        if b > a:
            u0, u1 = a - zc, b - zc
            solid += math.pi * (r * r * (u1 - u0) - (u1 ** 3 - u0 ** 3) / 3.0)
    return {"model": model, "times": times, "temperatures": np.array(rows).T.tolist(),
            "porosity": 1.0 - solid / (width * width * (hi - lo)), "count": count,
            "lost": int(lost), "wall_seconds": _time.perf_counter() - t0}


def comparison(result: dict, at=(1000.0, 2000.0, 3000.0, 4000.0)) -> list:
    """Rows (depth m, t s, DEM rise K, measured rise K, band low/high rises K)."""
    out = []
    times = np.asarray(result["times"])
    for k, depth in enumerate(DEPTHS):
        dem = np.asarray(result["temperatures"][k])
        for t in at:
            out.append((depth, t, float(np.interp(t, times, dem)) - T_BED,
                        measured_at(depth, min(t, 3950.0)) - T_BED,
                        measured_at(depth, min(t, 3950.0), "band_lower") - T_BED,
                        measured_at(depth, min(t, 3950.0), "band_upper") - T_BED))
    return out


def plot(results: list, path) -> None:
    """The measured curves, their bands and each result's, against time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    colours = ("#1b9e77", "#d95f02", "#7570b3")
    for k, depth in enumerate(DEPTHS):
        exp = measured(depth)
        ax.plot(exp[:, 0], exp[:, 1] - 273.15, ".", color=colours[k], ms=4,
                label=f"measured, {depth * 100:.1f} cm")
        lo, hi = measured(depth, "band_lower"), measured(depth, "band_upper")
        grid = np.linspace(0.0, 3950.0, 80)
        ax.fill_between(grid, np.interp(grid, lo[:, 0], lo[:, 1]) - 273.15,
                        np.interp(grid, hi[:, 0], hi[:, 1]) - 273.15, color=colours[k], alpha=0.12)
        for result, style in zip(results, ("-", "--", ":")):
            ax.plot(result["times"], np.asarray(result["temperatures"][k]) - 273.15, style,
                    color=colours[k], label=f"DEM {result['model']}, {depth * 100:.1f} cm")
    ax.set_xlabel("time after the wall was switched to 53 C, s")
    ax.set_ylabel("temperature, C")
    ax.set_title("6.4 mm steel spheres heated from one wall (Beaulieu)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    import argparse
    import json
    ap = argparse.ArgumentParser(description="the heated packed bed against Beaulieu's data")
    ap.add_argument("--model", action="append", default=None,
                    help="gas-gap model (repeat for several; default schlunder)")
    ap.add_argument("--json", default="")
    ap.add_argument("--plot", default="")
    a = ap.parse_args()
    results = []
    for model in a.model or ["schlunder"]:
        r = heated_bed(model)
        results.append(r)
        print(f"{model}: porosity {r['porosity']:.3f}, {r['count']} spheres, "
              f"{r['wall_seconds']:.0f} s wall")
        print("| depth | t, s | DEM rise, K | measured rise, K (band) | DEM / measured |")
        print("|---|---|---|---|---|")
        for depth, t, dem, exp, lo, hi in comparison(r):
            print(f"| {depth * 100:.1f} cm | {t:.0f} | {dem:.2f} | {exp:.2f} ({lo:.2f} - {hi:.2f}) "
                  f"| {dem / exp:.2f} |")
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(results, indent=1))
    if a.plot:
        plot(results, a.plot)
