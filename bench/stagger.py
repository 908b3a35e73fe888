#!/usr/bin/env python3
"""The paddle stagger of the seed's original cooler chosen from evidence (issue 44 item 5).

The seed gives 24 rows of four paddles but not how each row is turned from the one before.
With four paddles a turn of 90 deg brings a row onto itself, so the staggers that matter lie
in [0, 90): 0 (every row alike: the one-row slice), 45 (two rows repeat), 30 (three), ... and
90 is 0 again. Each is mapped at the seed's operating point (60 kg/m, 5 deg; the seed's cooler 1
carried 4.6 t/h at 0.02 m/s, 64 kg/m) on the calibrated ash, and set against the seed's axial
speed:

    taichi-dem map demos/cooler_slice.toml --stagger 45 --holdup "60 kg/m" --incline 5 \\
        --time 6 --threads 1 --pictures --out OUT/stagger_45
    python bench/stagger.py --base docs/machine/seed_cooler/original \\
        --stagger 45=OUT/stagger_45 --out docs/machine/seed_cooler/stagger

``--base``: the one-row map (stagger 0) with a row at the same hold-up and incline.
"""
import argparse
import json
import math
import sys
from pathlib import Path

SEED_SPEED = 0.020          # m/s, seed 001: cooler 1 at 4.6 t/h, original paddles, 5 deg
# the seed quotes one significant figure: 0.02 m/s stands for 0.015 - 0.025
SEED_SPEED_HALF_WIDTH = 0.005
FIGURES = (("axial speed (mm/s)", "axial_speed", 1e3),
           ("axial flow (t/h)", "axial_mass_flow", 3.6),
           ("drive torque (N m per m)", "shaft/torque_per_metre", -1.0),
           ("shell torque (N m per m)", "shell/torque_per_metre", 1.0),
           ("dynamic angle (deg)", "dynamic_angle", 1.0),
           ("D_ax (m^2/s)", "axial_dispersion", 1.0),
           ("shell conductance per metre (W/(m K))", "shell/conductance_per_metre", 1.0))


def row_of(folder: Path, holdup: float, incline: float) -> dict:
    rows = json.loads((folder / "map.json").read_text())["rows"]
    for r in rows:
        if abs(r["holdup_kg_per_m"] - holdup) < 1e-6 and abs(r["incline_deg"] - incline) < 1e-6:
            return r
    raise SystemExit(f"{folder}: no row at {holdup} kg/m and {incline} deg")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--base", type=Path, required=True)
    p.add_argument("--stagger", action="append", default=[], metavar="DEG=MAP")
    p.add_argument("--holdup", type=float, default=60.0)
    p.add_argument("--incline", type=float, default=5.0)
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--design", default="original", help="the design's name in the title")
    p.add_argument("--seed-speed", type=float, default=SEED_SPEED * 1e3,
                   help="the seed's axial speed there (mm/s; default the original's 20)")
    p.add_argument("--seed-half-width", type=float, default=SEED_SPEED_HALF_WIDTH * 1e3,
                   help="half the range the seed's figure stands for (mm/s; default 5)")
    p.add_argument("--seed-where", default="cooler 1: 4.6 t/h, 64 kg/m",
                   help="where the seed gives that speed, in words")
    p.add_argument("--name", default="stagger", help="the output's stem (NAME.md, NAME.json)")
    p.add_argument("--note", action="append", default=[],
                   help="a line added under the verdict (what a map's log warned of)")
    a = p.parse_args(argv)
    maps = [(0.0, a.base)] + [(float(s.split("=")[0]), Path(s.split("=", 1)[1]))
                              for s in a.stagger]
    rows = [(deg, row_of(folder, a.holdup, a.incline)) for deg, folder in maps]
    speed, half = a.seed_speed / 1e3, a.seed_half_width / 1e3
    lines = [f"# The paddle stagger of the {a.design} cooler ({a.holdup:g} kg/m, {a.incline:g} deg, "
             "calibrated ash, 15 mm)", "",
             "Each stagger's slice holds the rows that repeat (`taichi-dem map --stagger`); "
             "steady means +- standard error.", "",
             "| figure | " + " | ".join(f"stagger {d:g} deg" for d, _ in rows) + " |",
             "|---" * (len(rows) + 1) + "|"]
    for label, key, scale in FIGURES:
        cells = []
        for _, r in rows:
            v, e = r.get(key), r.get(f"{key}_standard_error")
            if v is None:
                cells.append("n/a")
                continue
            text = f"{v * scale:.3g}" + (f" +- {abs(e * scale):.2g}" if e is not None else "")
            cells.append(text + ("" if r.get(f"{key}_steady", True) else " (not steady)"))
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    # the evidence: the seed's axial speed at its operating point
    lines += ["", f"Against the seed's {speed * 1e3:g} mm/s ({a.seed_where}, {a.incline:g} deg; "
              f"read as {1e3 * (speed - half):g} - {1e3 * (speed + half):g} mm/s):", ""]
    scores = []
    for deg, r in rows:
        v, e = r["axial_speed"], r["axial_speed_standard_error"]
        miss = max(abs(v - speed) - half, 0.0)
        z = miss / e if e > 0 else math.inf
        scores.append((z, abs(v - speed), deg))
        lines.append(f"- stagger {deg:g} deg: {v * 1e3:.3g} +- {e * 1e3:.2g} mm/s, "
                     + ("within the seed's range" if miss == 0 else
                        f"{miss * 1e3:.2g} mm/s outside it ({z:.1f} standard errors)"))
    best = min(scores)
    inside = [s for s in scores if s[0] == 0]
    if len(inside) > 1:
        verdict = (f"{len(inside)} staggers ({', '.join(f'{s[2]:g}' for s in inside)} deg) give "
                   "speeds within the seed's range: its speed does not choose between them; the "
                   f"closest to {speed * 1e3:g} mm/s is {min(inside, key=lambda s: s[1])[2]:g} deg.")
    else:
        verdict = (f"The seed's speed picks a stagger of {best[2]:g} deg"
                   + ("." if best[0] == 0 else f", the nearest to it (none lies within its range)."))
    lines += ["", verdict] + (["", *[f"- {n}" for n in a.note]] if a.note else [])
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / f"{a.name}.md").write_text("\n".join(lines) + "\n")
    (a.out / f"{a.name}.json").write_text(json.dumps({"holdup_kg_per_m": a.holdup,
                                                     "incline_deg": a.incline,
                                                     "rows": {f"{d:g}": r for d, r in rows}},
                                                    indent=1, default=float))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
