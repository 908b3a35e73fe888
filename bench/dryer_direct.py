#!/usr/bin/env python3
"""The dryer's closures checked against a direct run: a short flighted drum
(bench/direct_check/dryer_direct.toml: the dryer slice's drum 0.72 m long, 24 mm aggregate,
8 rpm, 4.7 deg, the gas at 1 m/s against the solids, fed 13 t/h, a free discharge) run inlet to
outlet to its steady state, beside what the map of its own slice (docs/machine/dryer_slice/
map.json) gives for it two ways:

- the march of `taichi-dem machine` (app/machine.py), the cooler's, which `taichi-dem dryer`'s
  map closure (app/dryer_map.py) now uses too: the hold-up profile from the discharge back,
  with the bed's axial depth gradient pulling it along;
- a uniform hold-up: the hold-up per metre at which the slice conveys the feed, the same along
  the drum (residence H L / F, torque T(H) L) - the dryer's closure before this check.

    python bench/dryer_direct.py --out bench/results/dryer_direct            # run and compare
    python bench/dryer_direct.py --out bench/results/dryer_direct --reuse    # the table again
    python bench/dryer_direct.py --long --out bench/results/dryer_direct_long  # > 10,000 inside

``--long``: bench/direct_check/dryer_direct_long.toml, the same drum 2.8 m long fed 22 t/h,
starting from a bed of 11,000 spheres: more than 10,000 particles inside (issue 47 item 3).

The tolerances are the cooler's direct check's (15 %; BENCHMARKS.md).
"""
import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from taichi_dem.app import direct_run as dr   # noqa: E402
from taichi_dem.app import machine as mc      # noqa: E402

SCENE = ROOT / "bench" / "direct_check" / "dryer_direct.toml"
# the longer drum (--long): (scene, length m, feed t/h)
LONG = (ROOT / "bench" / "direct_check" / "dryer_direct_long.toml", 2.8, 22.0)
MAP = ROOT / "docs" / "machine" / "dryer_slice" / "map.json"
LENGTH = 0.72
FEED_T_PER_H = 13.0
INCLINE = 4.7
TOLERANCES = {"holdup": 0.15, "residence_time": 0.15, "drum/torque": 0.15}
GAS = {"gas_density": 0.46, "gas_viscosity": 3.6e-5, "gas_conductivity": 0.056,
       "gas_heat_capacity": 1150.0}


class Uniform:
    """A uniform hold-up H where the slice carries the feed, in the shape compare() reads
    (machine.MachineAnswer's)."""

    def __init__(self, holdup: float, feed: float, torque_per_metre: float):
        self.holdup = holdup * LENGTH
        self.residence_time = holdup * LENGTH / feed
        self.torques = {"drum": torque_per_metre * LENGTH}
        self.outlet_temperature = None
        self.profile = None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "dryer_direct")
    p.add_argument("--time", type=float, default=90.0, help="simulated s of the direct run")
    p.add_argument("--reuse", action="store_true", help="reuse the direct run in OUT")
    p.add_argument("--map", type=Path, default=MAP, help="the slices' map (default: the "
                   "published one, docs/machine/dryer_slice/map.json)")
    p.add_argument("--feed-over", type=float, nargs=2, metavar=("X0", "X1"), default=None,
                   help="march with the feed entering evenly between X0 and X1 m from the "
                   "inlet end (the factory's box: 0.03 0.25) instead of at the inlet end")
    p.add_argument("--long", action="store_true", help="the 2.8 m drum fed 22 t/h with more "
                   "than 10,000 particles inside (dryer_direct_long.toml)")
    a = p.parse_args(argv)
    global SCENE, LENGTH, FEED_T_PER_H
    if a.long:
        SCENE, LENGTH, FEED_T_PER_H = LONG
    a.out.mkdir(parents=True, exist_ok=True)
    run_file = a.out / "direct.npz"
    wall = None
    if not (a.reuse and run_file.exists()):
        t0 = time.perf_counter()
        obs, residence, _ = dr.run_direct(SCENE.read_text(), base_dir=str(SCENE.parent),
                                          source=str(SCENE), seconds=a.time, length=LENGTH,
                                          bins=14 if a.long else 6, outlet="discharge", residence_sensor="residence")
        wall = time.perf_counter() - t0
        dr.save_record(obs, residence, run_file)
    obs, residence = dr.load_record(run_file)
    direct = dr.reduce_direct(obs, residence)
    # The particles' own residence times are those of the particles that left in the steady
    # window; a particle leaving at time t was fed after 0, so it stayed less than t. Where
    # the window opens before the feed has run for about two residence times (the long drum
    # starts from a poured bed, whose spheres carry no time), the long stays are cut off and
    # the mean is low: Little's law (hold-up over discharge rate, both over the steady window)
    # is then the residence time compared.
    own_times = direct.residence_time
    censored = direct.steady_from < 2.0 * direct.little_residence_time.value
    if censored:
        direct.residence_time = direct.little_residence_time
    feed = direct.discharge_rate.value
    from taichi_dem.app.dryer_map import closures
    c = closures(a.map, {"diameter": 1.0, "length": LENGTH, "incline": math.radians(INCLINE),
                       "rpm": 8.0, "feed": feed, "gas_flow": 0.46 * math.pi / 4, **GAS},
                 "bench/dryer_direct.py")
    doc_rows = json.loads((a.map / "map.json" if a.map.is_dir() else a.map).read_text())["rows"]
    torque = float(np.interp(c["map_uniform_holdup"], [r["holdup_kg_per_m"] for r in doc_rows],
                             [r["drum/torque_per_metre"] for r in doc_rows]))
    uniform = Uniform(c["map_uniform_holdup"], feed, torque)
    errors = {"holdup": c["residence_uncertainty"] * uniform.holdup,
              "residence_time": c["residence_uncertainty"] * uniform.residence_time,
              "drum/torque": math.nan}
    rows_uniform = dr.compare(direct, uniform, errors, TOLERANCES)
    m = mc.MachineMap.load(a.map)
    out = mc.with_errors(m, LENGTH, [feed], -math.tan(math.radians(INCLINE)), draws=40,
                         feed_over=a.feed_over)
    ans, err = out["feeds"][0], out["errors"][0]
    rows_machine = dr.compare(direct, ans, err, TOLERANCES)
    rms, worst = dr.profile_difference(direct, ans)
    lines = [f"direct run: {LENGTH:g} m, {obs.time[-1]:.3g} s, steady from "
             f"{direct.steady_from:.1f} s ({'steady' if direct.steady else 'NOT steady'}), "
             f"discharge {direct.discharge_rate.value * 3.6:.3f} +- "
             f"{direct.discharge_rate.error * 3.6:.2g} t/h (fed {FEED_T_PER_H:g} t/h), "
             f"{direct.particles_out} particles out in the steady part; Little's law residence "
             f"{direct.little_residence_time.value:.3g} +- {direct.little_residence_time.error:.2g} s"
             + (f"; the particles' own times ({own_times.value:.3g} s) are cut off by the "
                f"run's start (steady from {direct.steady_from:.1f} s, under two residence "
                f"times): Little's law is compared" if censored else ""),
             "", "The march of `taichi-dem machine` and of `taichi-dem dryer`'s map closure (the "
             "hold-up profile from the discharge back"
             + (f"; the feed entering over {a.feed_over[0]:g} - {a.feed_over[1]:g} m"
                if a.feed_over else "") + "):", "", dr.table(rows_machine), "",
             f"`taichi-dem dryer`'s residence, hold-up and torque from its closure: "
             f"{c['residence_time']:.4g} s, {c['map_holdup'] * LENGTH:.4g} kg, "
             f"{c['drive_torque']:.4g} N m", "",
             "A uniform hold-up where the slice alone carries the feed "
             f"({c['map_uniform_holdup']:.4g} kg/m, the dryer's closure before):", "",
             dr.table(rows_uniform), "",
             f"hold-up profile, march minus direct: RMS {rms:.3g} kg/m, largest {worst:.3g} "
             f"kg/m (mean {direct.holdup.value / LENGTH:.3g} kg/m)", "",
             "| x (m) | direct (kg/m) | march (kg/m) | uniform (kg/m) |", "|---|---|---|---|"]
    marched = np.interp(direct.x, ans.profile.x, ans.profile.holdup)
    for x, h, e, mh in zip(direct.x, direct.holdup_profile, direct.holdup_profile_error, marched):
        lines.append(f"| {x:.3f} | {h:.3g} +- {e:.2g} | {mh:.3g} | {c['map_uniform_holdup']:.3g} |")
    if wall is not None:
        lines += ["", f"wall time of the direct run: {wall / 60:.1f} min"]
    text = "\n".join(lines)
    print(text)
    tag = "" if a.map == MAP else "_" + (a.map.parent.name if a.map.name == "map.json"
                                         else a.map.stem)
    if a.feed_over:
        tag += "_feed_over"
    (a.out / f"comparison{tag}.md").write_text(text + "\n")
    (a.out / f"comparison{tag}.json").write_text(json.dumps({
        name: [{"name": r.name, "direct": [r.direct.value, r.direct.error],
                "march": [r.march.value, r.march.error], "ratio": r.ratio,
                "tolerance": r.tolerance, "within": bool(r.within)} for r in rows]
        for name, rows in (("uniform", rows_uniform), ("march", rows_machine))}, indent=1,
        default=float))
    return 0 if all(r.within for r in rows_machine) else 1


if __name__ == "__main__":
    sys.exit(main())
