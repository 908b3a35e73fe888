#!/usr/bin/env python3
"""The seed's cooler (seed 001) answered at its own scale: capacity, residence, shaft torque and
outlet temperature of the 6 m machine, original and optimised, from periodic one-row slices at
the seed's 15 mm spheres (issue 31 items 3 and 8), on the calibrated ash beside the first maps'
free-rolling ash (issue 44 item 2).

    python bench/seed_cooler.py --run --out bench/results/seed_cooler     # maps, then the table
    python bench/seed_cooler.py --out docs/machine/seed_cooler            # the table from maps

With ``--run`` each design's slice (demos/cooler_slice.toml, demos/cooler_slice_optimised.toml,
now on the calibrated ash) is mapped with ``taichi-dem map`` at the hold-ups and the design's
own incline (original 5 deg, optimised 2 deg: the march at that incline needs no other), its
wall time recorded; without it the maps already in OUT/<design>/ are read. Then ``taichi-dem
machine``'s march gives the 6 m machine at its incline and the seed's feeds, and the seed's
table is printed with a column for the calibrated ash (OUT/<design>) and one for the
free-rolling ash (``--free-rolling``, default OUT/free_rolling: the maps published before the
calibration, rolling friction 0.05 in the EPSD model), and written to OUT/seed_table.md. The
modelling choices were mapped on the free-rolling ash: their tables stay with its column.
"""
import argparse
import json
import math

import numpy as np
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from taichi_dem.app import machine as mc       # noqa: E402

DESIGNS = {"original": ("cooler_slice", 5.0), "optimised": ("cooler_slice_optimised", 2.0)}
# the optimised design's inlet screw (demos/cooler_slice_screw.toml, our geometry: the seed
# gives none): its map in OUT/screw, its first SCREW_LENGTH m replacing the paddles'
SCREW = ("cooler_slice_screw", "screw")
SCREW_LENGTH = 1.0
# the original design's modelling choices (bench/modelling_choices.py --preset seed), in
# OUT/modelling_choices/<name>: each answer's change under each, beside the maps' noise
CHOICES = {"f64": "precision f64 (f32 mapped)", "20_mm_spheres": "spheres 20 mm (15 mapped)",
           "30_mm_spheres": "spheres 30 mm (15 mapped)",
           "thermal_time_scale_10": "thermal time scale 10 (1 mapped)",
           "two_rows_stagger_45": "two rows staggered 45 deg (one row mapped)"}
LENGTH = 6.0
FEEDS_T_H = (4.6, 6.5)
INLET_C, WALL_C = 450.0, 30.0


def run_maps(out: Path, holdups, seconds: float) -> dict:
    """``taichi-dem map`` for each design at its own incline (the screw at both: the optimised
    machine's inlet section); returns the wall time of each (s)."""
    walls = {}
    for design, (scene, incline) in [*DESIGNS.items(), (SCREW[1], (SCREW[0], None))]:
        inclines = [incline] if incline is not None else [5.0, 2.0]
        t0 = time.perf_counter()
        cmd = [sys.executable, "-m", "taichi_dem", "map", str(ROOT / "demos" / f"{scene}.toml"),
               "--holdup", *[f"{h} kg/m" for h in holdups], "--incline", *map(str, inclines),
               "--time", str(seconds), "--pictures", "--out", str(out / design)]
        subprocess.run(cmd, check=True)
        walls[design] = time.perf_counter() - t0
    return walls


def answers(map_dir: Path, incline: float, inlet_sections=(), machine=None,
            feeds_t_h=FEEDS_T_H) -> dict:
    """The machine's answers at the seed's feeds and its capacity (module docstring);
    ``machine``: a map to march instead of the one in ``map_dir`` (a modelling choice's)."""
    m = machine or mc.MachineMap.load(map_dir)
    feeds = [f / 3.6 for f in feeds_t_h]
    out = mc.with_errors(m, LENGTH, feeds, -math.tan(math.radians(incline)),
                         inlet_temperature=INLET_C + 273.15, draws=40,
                         inlet_sections=inlet_sections)
    return {"map": m, "out": out}


def section_speed(answer, start: float, end: float) -> float:
    """Mean axial speed (m/s) of the bed between ``start`` and ``end`` m from the inlet end:
    the section's length over its residence (its hold-up over the feed)."""
    x, h = answer.profile.x, answer.profile.holdup
    keep = (x >= start - 1e-9) & (x <= end + 1e-9)
    return (end - start) * answer.feed / float(np.trapezoid(h[keep], x[keep]))


CHOICE_FOLDERS = {"original": "modelling_choices", "optimised": "modelling_choices_optimised"}


def choices_table(out: Path, base: dict, design: str = "original") -> str:
    """Each answer of ``design`` at 6.5 t/h with its error from noise, and what each modelling
    choice mapped in OUT/<CHOICE_FOLDERS[design]> moves it by (z: over the noise)."""
    folder = out / CHOICE_FOLDERS[design]
    found = {k: v for k, v in CHOICES.items() if (folder / k / "map.json").exists()}
    if not found:
        return ""
    incline = DESIGNS[design][1]
    diffs = {}
    for key, label in found.items():
        choice = mc.MachineMap.load(folder / key)
        # both marches from the hold-ups the choice mapped (the design's map may have more)
        theirs = {round(r.holdup, 6) for r in choice.rows}
        m = base["map"]
        common = mc.MachineMap([r for r in m.rows if round(r.holdup, 6) in theirs], m.section,
                               m.angular_speeds, m.particle_diameter, m.heat_capacity,
                               m.wall_temperatures, m.bodies)
        reference = answers(None, incline, machine=common)["out"]
        other = mc.substituted(common, choice, source=str(folder / key))
        diffs[label] = mc.choice_differences(reference, answers(None, incline, machine=other)["out"])
    k = FEEDS_T_H.index(6.5)
    a, e = base["out"]["feeds"][k], base["out"]["errors"][k]
    names = [("capacity (t/h)", base["out"]["capacity"] * 3.6, base["out"]["capacity_error"] * 3.6,
              lambda d: d["capacity"], 3.6, True),
             ("mean residence (s)", a.residence_time, e.get("residence_time"),
              lambda d: d["feeds"][k]["residence_time"], 1.0, True),
             ("shaft drive torque (N m)", -a.torques["shaft"], e.get("shaft/torque"),
              lambda d: d["feeds"][k]["shaft/torque"], -1.0, True),
             ("outlet temperature (C)", a.outlet_temperature - 273.15, e.get("outlet_temperature"),
              lambda d: d["feeds"][k]["outlet_temperature"], 1.0, False)]
    title = ("Original paddles, 5 deg" if design == "original" else
             "Optimised paddles (45 deg), 2 deg, no inlet screw")
    preset = "seed" if design == "original" else "seed_optimised"
    lines = [f"{title}, at 6.5 t/h: each answer with its error from the maps' noise "
             "(one standard deviation over the re-marches) and the change each modelling choice "
             f"makes (the choice's map at {incline:g} deg, `bench/modelling_choices.py --preset "
             f"{preset}`; z = "
             "the change over the two noises combined: |z| < 2 is a change these maps do not "
             "resolve, so the choice's error is below about 2 noise)", "",
             "| answer | value | noise | " + " | ".join(diffs) + " |",
             "|---|---|---|" + "---|" * len(diffs)]
    for name, value, noise, pick, scale, pct in names:
        cells = []
        for d in diffs.values():
            c = pick(d)
            if c is None:
                cells.append("n/a")
            elif pct:
                # (the drive torque is minus the particles' torque: its change and z flip)
                cells.append(f"{c['change'] * scale:+.3g} ({100 * c['relative']:+.0f} %, "
                             f"z {math.copysign(1.0, scale) * c['z']:+.1f})")
            else:
                cells.append(f"{c['change'] * scale:+.3g} K (z {c['z']:+.1f})")
        lines.append(f"| {name} | {value:.4g} | {noise:.2g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def fmt(value, error, scale=1.0, digits=3):
    if value is None or not math.isfinite(value):
        return "n/a"
    e = error if error is not None and math.isfinite(error) else math.nan
    return f"{value * scale:.{digits}g} +- {e * scale:.2g}"


def cap_text(out: dict) -> str:
    return fmt(out["capacity"], out["capacity_error"], 3.6) + " t/h"


def _rows(results: dict) -> list:
    """(quantity, the seed's value, ours) for each answer of ``results``."""
    rows = []
    for design, seed in (("original", {
            "capacity": "about 6 t/h; 4.6 t/h already at its limit",
            "speed": "0.02 m/s, 300 s over 6 m (at 6.5 t/h fed to the pair; 4.6 t/h in cooler 1)",
            "torque": "6 kN m (fully loaded)",
            "holdup": "64-90 kg/m (4.6-6.5 t/h at 0.02 m/s)"}),
            ("optimised", {"capacity": "6.5 t/h each, not overloaded",
                           "speed": "36-39 mm/s at the paddles, ~150 s",
                           "torque": "1 kN m (fully loaded)"})):
        if design not in results:
            continue
        r = results[design]
        out = r["out"]
        r_map = r["map"]
        cap = fmt(out["capacity"], out["capacity_error"], 3.6) + " t/h"
        by_feed = {round(a.feed * 3.6, 2): (a, e) for a, e in zip(out["feeds"], out["errors"])}
        a, e = by_feed[6.5]
        speed = (f"{LENGTH / a.residence_time * 1e3:.3g} mm/s, "
                 f"{fmt(a.residence_time, e.get('residence_time'))} s at 6.5 t/h"
                 + (" (overflows: beyond capacity)" if a.overflows else ""))
        # the drive torque: minus the particles' torque on the shaft
        shaft = fmt(-a.torques.get("shaft", math.nan), e.get("shaft/torque")) + " N m"
        temp = fmt(None if a.outlet_temperature is None else a.outlet_temperature - 273.15,
                   e.get("outlet_temperature"))
        label = "original paddles, 5 deg" if design == "original" else \
            "optimised paddles (45 deg), 2 deg; no inlet screw"
        hold = (f"{fmt(a.holdup / LENGTH, e.get('holdup', math.nan) / LENGTH)} kg/m mean, "
                f"{a.inlet_holdup:.3g} kg/m at the inlet end")
        rows += [(f"{label}: capacity (inlet end at {max(r.holdup for r in r_map.rows):.3g} kg/m)",
                  seed["capacity"], cap),
                 (f"{label}: axial speed / residence", seed["speed"], speed),
                 (f"{label}: hold-up at 6.5 t/h", seed.get("holdup", ""), hold),
                 (f"{label}: shaft drive torque at 6.5 t/h", seed["torque"], shaft),
                 (f"{label}: outlet temperature at 6.5 t/h (C, fed at 450 C)",
                  "(not simulated)", temp)]
        from taichi_dem.app.dispersion import machine_rtd
        got = machine_rtd(r_map, a, -math.tan(math.radians(DESIGNS[design][1])),
                          INLET_C + 273.15)
        if got is not None:         # the map measured D_ax: the residence-time distribution
            d = got["rtd"]
            text = (f"10 / 50 / 90 % out by {d.t10:.3g} / {d.t50:.3g} / {d.t90:.3g} s "
                    f"(sd {math.sqrt(d.variance):.3g} s; D_ax {got['dispersion'].min():.2g} - "
                    f"{got['dispersion'].max():.2g} m^2/s; its error not carried into these)")
            if "outlet_temperature_quantiles" in got:
                q = got["outlet_temperature_quantiles"]
                text += (f"; outlet mixed {got['outlet_temperature_mixed'] - 273.15:.4g} C, "
                         f"10 / 50 / 90 % {q[0.1] - 273.15:.4g} / {q[0.5] - 273.15:.4g} / "
                         f"{q[0.9] - 273.15:.4g} C")
            rows.append((f"{label}: residence-time distribution at 6.5 t/h (axial dispersion "
                         "model)", "(only the mean)", text))
        a46, e46 = by_feed[4.6]
        rows.append((f"{label}: at 4.6 t/h: residence (s), shaft drive torque (N m)", "",
                     f"{fmt(a46.residence_time, e46.get('residence_time'))}; "
                     f"{fmt(-a46.torques.get('shaft', math.nan), e46.get('shaft/torque'))}"))
    if "optimised_with_screw" in results:
        r = results["optimised_with_screw"]
        out = r["out"]
        label = f"optimised paddles, 2 deg, with {SCREW_LENGTH:g} m of inlet screw (our geometry)"
        by_feed = {round(a.feed * 3.6, 2): (a, e) for a, e in zip(out["feeds"], out["errors"])}
        seed = {6.5: "60 / 36 mm/s, about 150 s", 13.0: "45 / 39 mm/s, about 150 s"}
        for feed in (6.5, 13.0):
            a, e = by_feed[feed]
            speeds = (f"{section_speed(a, 0.0, SCREW_LENGTH) * 1e3:.3g} / "
                      f"{section_speed(a, SCREW_LENGTH, LENGTH) * 1e3:.3g} mm/s, "
                      f"{fmt(a.residence_time, e.get('residence_time'))} s"
                      + (" (overflows: beyond capacity)" if a.overflows else ""))
            rows.append((f"{label}: at {feed:g} t/h, axial speed along screw / paddles, "
                         "residence", seed[feed], speeds))
        a, e = by_feed[6.5]
        drive = -(a.torques.get("shaft", 0.0) + a.torques.get("screw", 0.0))
        drive_e = math.hypot(e.get("shaft/torque", 0.0), e.get("screw/torque", 0.0))
        rows += [(f"{label}: capacity", "", cap_text(out)),
                 (f"{label}: inlet-end hold-up at 6.5 t/h", "no accumulation under the inlet",
                  f"{a.inlet_holdup:.3g} kg/m"),
                 (f"{label}: shaft drive torque at 6.5 t/h (paddles + screw)", "",
                  fmt(drive, drive_e) + " N m"),
                 (f"{label}: outlet temperature at 6.5 t/h (C)", "(not simulated)",
                  fmt(a.outlet_temperature - 273.15, e.get("outlet_temperature")))]
    return rows


def size_paragraph(out: Path, holdup: int = 60) -> str:
    """The size study's verdict at ``holdup`` kg/m (bench/size_convergence.py, OUT/size): how
    each slice answer behind the table moves from 15 to 10 mm, each size calibrated at its
    size. Empty when the study has not been made."""
    path = out / "size" / "size_convergence.json"
    if not path.is_file():
        return ""
    doc = json.loads(path.read_text())
    if 10 not in doc["sizes_mm"] or str(holdup) not in next(iter(doc["answers"].values())):
        return ""
    parts = []
    labels = {"axial_speed": "axial speed", "shaft/torque_per_metre": "shaft torque",
              "shell/conductance_per_metre": "shell conductance", "axial_dispersion": "D_ax"}
    for key, label in labels.items():
        v = doc["answers"][key][str(holdup)]
        parts.append(f"{label} {100 * v['step_15_10_relative']:+.0f} % ({v['step_sigmas']:.1f} "
                     f"standard errors: {v['status']})")
    return (f"Sphere size (the original design's slice at {holdup} kg/m, 5 deg, each size on the "
            f"ash calibrated at its size; size/size_convergence.md): from 15 to 10 mm, "
            + "; ".join(parts) + ". The machine's residence scales with 1 / axial speed, its "
            "torque with the shaft torque and its cooling with the shell conductance.")


def table(columns: list, walls: dict | None) -> str:
    """The seed's table with a column of ours for each (title, results) of ``columns``: the
    calibrated ash's, then the free-rolling ash's (issue 44)."""
    header = ["quantity", "the paper (EDEM, 15 mm spheres)"] + [c for c, _ in columns]
    by_column = [{q: (s, o) for q, s, o in _rows(r)} for _, r in columns]
    order = []
    for rows in by_column:
        order += [q for q in rows if q not in order]
    lines = ["| " + " | ".join(header) + " |", "|---" * len(header) + "|"]
    for q in order:
        seed = next((rows[q][0] for rows in by_column if q in rows and rows[q][0]), "")
        cells = [rows[q][1] if q in rows else "" for rows in by_column]
        lines.append("| " + " | ".join([q, seed] + cells) + " |")
    if walls:
        lines += ["", "map wall times on this machine: " + ", ".join(
            f"{d} {w / 60:.1f} min" for d, w in walls.items())]
    lines += ["", "Errors: one standard deviation from the maps' noise (re-marches). "
              "Calibrated ash: the paper's fly ash fitted by `taichi-dem calibrate` to its eight "
              "heaps (Table 2, 38.0 +- 0.8 deg; constant torque, rolling friction 1.38 ash-ash "
              "and 1.5 ash-steel, docs/calibration/). Free-rolling ash: the first maps' rolling "
              "friction 0.05 (EPSD), whose heap stands at ~20 deg. What the precision, the "
              "particle size, the thermal time scale and the one-row slice's stagger of 0 "
              "(against two rows staggered 45 deg) moved the free-rolling answers by is in the "
              "tables below."]
    return "\n".join(lines)


SLICE_FIGURES = (("axial speed (mm/s)", "axial_speed", 1e3),
                 ("shaft torque (N m per m)", "shaft/torque_per_metre", -1.0),
                 ("shell torque (N m per m)", "shell/torque_per_metre", 1.0),
                 ("dynamic angle (deg)", "dynamic_angle", 1.0),
                 ("bed solid fraction", "bed_solid_fraction", 1.0),
                 ("shell conductance per metre (W/(m K))", "shell/conductance_per_metre", 1.0))


def slice_comparison(out: Path, free: Path, holdup: float = 60.0) -> str:
    """Each design's slice at ``holdup`` kg/m and its incline, calibrated against
    free-rolling ash: the figures the issue set side by side (no march: the maps' rows)."""
    lines = []
    for design, (_, incline) in DESIGNS.items():
        pair = []
        for folder in (out / design, free / design):
            try:
                rows = json.loads((folder / "map.json").read_text())["rows"]
            except OSError:
                break
            row = [r for r in rows if abs(r["holdup_kg_per_m"] - holdup) < 1e-6
                   and abs(r["incline_deg"] - incline) < 1e-6]
            if not row:
                break
            pair.append(row[0])
        if len(pair) != 2:
            continue
        if not lines:
            lines = [f"The slices themselves at {holdup:g} kg/m and each design's incline "
                     "(the maps' rows, steady means +- standard error; shaft torque as the "
                     "drive's, positive):", "",
                     "| design | figure | calibrated ash | free-rolling ash | change |",
                     "|---|---|---|---|---|"]
        for label, key, scale in SLICE_FIGURES:
            cells = []
            for r in pair:
                v, e = r.get(key), r.get(f"{key}_standard_error")
                if v is None:
                    cells.append("n/a")
                    continue
                text = f"{v * scale:.3g}" + (f" +- {abs(e * scale):.2g}" if e is not None else "")
                if r.get(f"{key}_steady") is False:
                    text += " (not steady)"
                cells.append(text)
            a, b = pair[0].get(key), pair[1].get(key)
            change = f"{100 * (a / b - 1):+.0f} %" if a is not None and b else ""
            lines.append(f"| {design}, {incline:g} deg | {label} | {cells[0]} | {cells[1]} | "
                         f"{change} |")
    return "\n".join(lines)


def design_results(out: Path) -> dict:
    """The marched answers of each design whose map is in ``out`` (and the optimised design
    with the inlet screw's map, when there is one)."""
    results = {}
    for design, (_, incline) in DESIGNS.items():
        folder = out / design
        if (folder / "map.json").exists():
            results[design] = answers(folder, incline)
        else:
            print(f"no map for {design} in {folder}", file=sys.stderr)
    if "optimised" in results and (out / SCREW[1] / "map.json").exists():
        screw = mc.MachineMap.load(out / SCREW[1])
        results["optimised_with_screw"] = answers(out / "optimised", DESIGNS["optimised"][1],
                                                  [(screw, SCREW_LENGTH)], feeds_t_h=(6.5, 13.0))
    return results


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--run", action="store_true", help="run the maps first")
    p.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "seed_cooler")
    p.add_argument("--free-rolling", type=Path, default=None,
                   help="the maps on the free-rolling ash (default OUT/free_rolling): their "
                        "column beside the calibrated ash's, and the modelling choices")
    p.add_argument("--holdups", type=float, nargs="+", default=[30, 60, 90, 120])
    p.add_argument("--time", type=float, default=10.0, help="simulated s per slice")
    a = p.parse_args(argv)
    walls = run_maps(a.out, a.holdups, a.time) if a.run else None
    free = a.free_rolling or a.out / "free_rolling"
    columns = [("taichi_dem, calibrated ash (slices at 15 mm, march)", design_results(a.out))]
    free_results = design_results(free) if (free / "original" / "map.json").exists() else {}
    if free_results:
        columns.append(("taichi_dem, free-rolling ash (rolling friction 0.05)", free_results))
    text = table(columns, walls)
    compared = slice_comparison(a.out, free)
    if compared:
        text += "\n\n" + compared
    sized = size_paragraph(a.out)
    if sized:
        text += "\n\n" + sized
    for design in CHOICE_FOLDERS:
        if design in free_results:
            extra = choices_table(free, free_results[design], design)
            if extra:
                text += "\n\n" + extra.replace(", at 6.5 t/h:", ", free-rolling ash, at 6.5 t/h:", 1)
    print(text)
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / "seed_table.md").write_text(text + "\n")
    if walls:
        (a.out / "wall_times.json").write_text(json.dumps(walls))
    return 0


if __name__ == "__main__":
    sys.exit(main())
