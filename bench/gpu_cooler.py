#!/usr/bin/env python3
"""The seed's 6 m cooler stepped whole on a GPU (issue 45 item 5): the original design's 24
paddle rows (0.866 m shell, 15 mm calibrated ash, 10 rpm, 5 deg) as one periodic machine at a
uniform hold-up, a few seconds; particle-steps per second, and the shaft torque per metre and
the axial flow beside the map's at that hold-up (docs/machine/seed_cooler/original and the
full-shell points, one row periodic).

    python bench/gpu_cooler.py --arch cuda --rows 24 --holdup 150 --time 5     # 585,000 spheres
    python bench/gpu_cooler.py --rows 2 --holdup 30 --time 0.3                  # a CPU check

The machine is demos/cooler_slice.toml with ``rows`` rows (0.25 m each) in its periodic
domain. The rate is over the steps after the first output sample (the compile and the
first neighbour list left out). The torque and flow are the steady means of the run's
second half (app/steady_state.py), to be read as a check of the long machine against its
one-row slice only when --time reaches the map's settling (6 s); tests/unit/test_gpu_cooler.py
runs it small on the CPU.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SLICE = ROOT / "demos" / "cooler_slice.toml"
MAPS = [ROOT / "docs" / "machine" / "seed_cooler" / "original",
        ROOT / "docs" / "machine" / "seed_cooler" / "full_shell" / "map_200",
        ROOT / "docs" / "machine" / "seed_cooler" / "full_shell" / "map_270"]
ROW = 0.25
INCLINE = 5.0


def machine_text(rows: int) -> str:
    """demos/cooler_slice.toml with ``rows`` paddle rows in a periodic domain rows x 0.25 m."""
    from taichi_dem.app.overrides import overridden_text
    length = rows * ROW
    text = SLICE.read_text()
    doc = tomllib.loads(text)
    return overridden_text(text, {
        "domain.max": [length] + doc["domain"]["max"][1:],
        "bodies.0.mesh.length": length, "bodies.1.mesh.length": length,
        "bodies.1.mesh.rows": rows,
        "particles.0.region.cylinder.length": length}, str(SLICE))


def mapped(holdup: float) -> dict:
    """The one-row map's shaft torque per metre (N m/m) and axial flow (kg/s), with their
    standard errors, interpolated linearly in the hold-up at 5 deg (nan beyond the map)."""
    rows = []
    for folder in MAPS:
        path = folder / "map.json"
        if path.exists():
            rows += [r for r in json.loads(path.read_text())["rows"]
                     if abs(r["incline_deg"] - INCLINE) < 1e-6]
    rows.sort(key=lambda r: r["holdup_kg_per_m"])
    h = np.array([r["holdup_kg_per_m"] for r in rows])
    out = {}
    for name in ("shaft/torque_per_metre", "axial_mass_flow"):
        v = np.array([r[name] for r in rows])
        e = np.array([r[name + "_standard_error"] for r in rows])
        inside = len(h) and h[0] <= holdup <= h[-1]
        out[name] = (float(np.interp(holdup, h, v)) if inside else math.nan,
                     float(np.interp(holdup, h, e)) if inside else math.nan)
    return out


def run(rows: int, holdup: float, seconds: float, arch: str = "cpu") -> dict:
    """Step the machine (module docstring); its rate and figures with the map's."""
    from taichi_dem.app.slice_map import (SliceObserver, holdup_count, inclined_gravity,
                                          slice_geometry)
    from taichi_dem.app.steady_state import steady_mean
    from taichi_dem.app.overrides import overridden_text
    from taichi_dem.run.simulation import Simulation
    from taichi_dem.scene.loader import parse_scene
    text = machine_text(rows)
    scene = parse_scene(text, source=str(SLICE), base_dir=str(SLICE.parent))
    geometry = slice_geometry(scene)
    count, kg_per_m, _ = holdup_count(scene, geometry, ("kg/m", holdup))
    text = overridden_text(text, {
        "particles.0.count": count,
        "simulation.gravity": inclined_gravity(scene.simulation.gravity, geometry, INCLINE)},
        str(SLICE))
    walls: list[tuple[float, int]] = []
    t0 = time.perf_counter()
    with Simulation.from_text(text, base_dir=str(SLICE.parent), source=str(SLICE), arch=arch,
                              h5="") as sim:
        built = time.perf_counter() - t0
        observer = SliceObserver(sim, geometry)
        sim.add_observer(observer, now=False)
        sim.add_observer(lambda s, v: walls.append((time.perf_counter(), s.step_count)),
                         now=False)
        started = (time.perf_counter(), sim.step_count)
        sim.run(seconds)
        particles = sim.engine.count
    if len(walls) < 2:          # a run of one sample: from the start (compile included)
        walls.insert(0, started)
    (w0, s0), (w1, s1) = walls[0], walls[-1]
    rate = particles * (s1 - s0) / (w1 - w0) if w1 > w0 else math.nan
    half = len(observer.series["time"]) // 2
    figures = {}
    for name in ("shaft/torque_per_metre", "axial_mass_flow"):
        values = np.asarray(observer.series.get(name, [math.nan]), float)[half:]
        values = values[np.isfinite(values)]
        figures[name] = steady_mean(values) if len(values) >= 2 else None
    return {"rows": rows, "length_m": rows * ROW, "holdup_kg_per_m": kg_per_m,
            "particles": int(particles), "arch": arch, "simulated_s": seconds,
            "build_s": built, "particle_steps_per_s": rate,
            "figures": {k: (None if v is None else [v.mean, v.standard_error, bool(v.steady),
                                                    int(v.samples)])
                        for k, v in figures.items()},
            "window_s": [float(observer.series["time"][half]), float(observer.series["time"][-1])]
            if len(observer.series["time"]) > half else None,
            "map": mapped(kg_per_m)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--arch", default="cpu")
    p.add_argument("--rows", type=int, default=24)
    p.add_argument("--holdup", type=float, default=150.0, help="kg/m")
    p.add_argument("--time", type=float, default=5.0, help="simulated s")
    p.add_argument("--json", type=Path, default=None)
    a = p.parse_args(argv)
    r = run(a.rows, a.holdup, a.time, a.arch)
    print(f"{r['rows']} rows ({r['length_m']:g} m) at {r['holdup_kg_per_m']:g} kg/m: "
          f"{r['particles']:,} spheres on {r['arch']}, {r['simulated_s']:g} s simulated, "
          f"built in {r['build_s']:.1f} s; {r['particle_steps_per_s'] / 1e6:.3g} M "
          "particle-steps/s")
    for name, fig in r["figures"].items():
        ref, err = r["map"][name]
        got = ("n/a (too few samples)" if fig is None else
               f"{fig[0]:.4g} +- {fig[1]:.2g} over {r['window_s'][0]:.3g}-{r['window_s'][1]:.3g} s "
               f"({fig[3]} samples{'' if fig[2] else ', NOT steady: a transient, not a check'})")
        print(f"  {name}: this run {got}; the one-row map {ref:.4g} +- {err:.2g}")
    if a.json:
        a.json.write_text(json.dumps(r, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
