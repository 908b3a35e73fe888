#!/usr/bin/env python3
"""The march checked against a direct run (issue 31 item 4): a short whole paddle cooler
(bench/direct_check/cooler_direct.toml: 6 rows, 0.48 m, 20 mm spheres, 30 rpm, 5 deg, fed
0.45 t/h at 450 C, a free discharge) run inlet to outlet to its steady state, and the same
cooler assembled by `taichi-dem machine`'s march from the map of its own slice
(bench/direct_check/cooler_slice.toml, one row periodic); hold-up, its profile, residence
time, shaft torque and the cooling set side by side (taichi_dem/app/direct_run.py).

    python bench/direct_check.py --out bench/results/direct_check              # all
    python bench/direct_check.py --out bench/results/direct_check --reuse      # the table again

The map runs with `taichi-dem map` (hold-ups 3-15 kg/m at 5 and 2 deg, --map-time s each);
the direct run with the Python API, observed every output interval (0.2 s). Wall times are
recorded (map, direct run). --rows/--time make a shorter machine and run.
"""
import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from taichi_dem.app import direct_run as dr   # noqa: E402
from taichi_dem.app import machine as mc      # noqa: E402

HERE = ROOT / "bench" / "direct_check"
INCLINE = 5.0
ROW = 0.08
INLET_K = 450.0 + 273.15
# the tolerances (fractions) and why: BENCHMARKS.md "Stop 25", "The march against a direct run"
TOLERANCES = {"holdup": 0.15, "residence_time": 0.15, "shaft/torque": 0.15,
              "outlet_temperature_drop": 0.15}


def run(rows: int, seconds: float):
    """The direct cooler cut to ``rows`` rows, run ``seconds`` s: (observer, residence, wall)."""
    path = HERE / "cooler_direct.toml"
    text = dr.shorter_machine(path.read_text(), rows, ROW, seconds, str(path))
    return dr.run_direct(text, base_dir=str(HERE), source=str(path), seconds=seconds,
                         length=rows * ROW, bins=2 * rows, outlet="discharge",
                         residence_sensor="residence")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "direct_check")
    p.add_argument("--rows", type=int, default=6)
    p.add_argument("--time", type=float, default=60.0, help="simulated s of the direct run")
    p.add_argument("--map-time", type=float, default=8.0)
    p.add_argument("--holdups", type=float, nargs="+", default=[3, 6, 9, 12, 15])
    p.add_argument("--reuse", action="store_true", help="reuse the map and direct run in OUT")
    a = p.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    walls = {}
    map_dir = a.out / "map"
    if not (a.reuse and (map_dir / "map.json").exists()):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "taichi_dem", "map", str(HERE / "cooler_slice.toml"),
                        "--holdup", *map(str, a.holdups), "--incline", "5", "2",
                        "--time", str(a.map_time), "--out", str(map_dir)], check=True)
        walls["map"] = time.perf_counter() - t0
    run_file = a.out / f"direct_{a.rows}rows.npz"
    if not (a.reuse and run_file.exists()):
        obs, residence, walls["direct"] = run(a.rows, a.time)
        dr.save_record(obs, residence, run_file)
    obs, residence = dr.load_record(run_file)
    direct = dr.reduce_direct(obs, residence)
    m = mc.MachineMap.load(map_dir)
    feed = direct.discharge_rate.value
    slope = -math.tan(math.radians(INCLINE))
    out = mc.with_errors(m, a.rows * ROW, [feed], slope, inlet_temperature=INLET_K, draws=40)
    ans, err = out["feeds"][0], out["errors"][0]
    rows = dr.compare(direct, ans, err, TOLERANCES, inlet_temperature=INLET_K)
    rms, worst = dr.profile_difference(direct, ans)
    lines = [f"direct run: {a.rows} rows ({a.rows * ROW:g} m), {obs.time[-1]:.3g} s, steady from "
             f"{direct.steady_from:.1f} s ({'steady' if direct.steady else 'NOT steady'}), "
             f"discharge {direct.discharge_rate.value * 3.6:.3f} +- "
             f"{direct.discharge_rate.error * 3.6:.2g} t/h (fed 0.45 t/h), "
             f"{direct.particles_out} particles out in the steady part; Little's law residence "
             f"{direct.little_residence_time.value:.3g} +- {direct.little_residence_time.error:.2g} s",
             "", dr.table(rows), "",
             f"hold-up profile, march minus direct: RMS {rms:.3g} kg/m, largest {worst:.3g} "
             f"kg/m (mean {direct.holdup.value / (a.rows * ROW):.3g} kg/m)", "",
             "| x (m) | direct (kg/m) | march (kg/m) |", "|---|---|---|"]
    marched = np.interp(direct.x, ans.profile.x, ans.profile.holdup)
    for x, h, e, mh in zip(direct.x, direct.holdup_profile, direct.holdup_profile_error, marched):
        lines.append(f"| {x:.3f} | {h:.3g} +- {e:.2g} | {mh:.3g} |")
    if walls:
        lines += ["", "wall times: " + ", ".join(f"{k} {v / 60:.1f} min" for k, v in walls.items())]
    text = "\n".join(lines)
    print(text)
    (a.out / f"comparison_{a.rows}rows.md").write_text(text + "\n")
    (a.out / f"comparison_{a.rows}rows.json").write_text(json.dumps({
        "rows": [{"name": r.name, "direct": [r.direct.value, r.direct.error],
                  "march": [r.march.value, r.march.error], "ratio": r.ratio,
                  "tolerance": r.tolerance, "within": bool(r.within)} for r in rows],
        "profile_rms": rms, "profile_max": worst, "walls": walls}, indent=1, default=float))
    return 0 if all(r.within for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
