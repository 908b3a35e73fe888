#!/usr/bin/env python3
"""The seed's cooler converged in sphere size (issue 44 item 3): the original design's one-row
slice (demos/cooler_slice.toml) at 20, 15 and 10 mm, each size on the ash calibrated at that
size against seed 001's eight heaps (docs/calibration/size/), mapped at 5 deg over the same
hold-ups and window as the published 15 mm map.

    python bench/size_convergence.py scenes                      # write the 10 and 20 mm slices
    taichi-dem map bench/seed_cooler/size/cooler_slice_10mm.toml --holdup "60 kg/m" "30 kg/m" \\
        "90 kg/m" --incline 5 --time 6 --threads 2 --pictures --out docs/machine/seed_cooler/size/10mm
    taichi-dem map bench/seed_cooler/size/cooler_slice_20mm.toml --holdup "30 kg/m" "60 kg/m" \\
        "90 kg/m" --incline 5 --time 6 --threads 1 --pictures --out docs/machine/seed_cooler/size/20mm
    python bench/size_convergence.py table --out docs/machine/seed_cooler/size

The 15 mm rows are the published map's (docs/machine/seed_cooler/original: the same scene, the
same hold-ups, incline and window). A size's slice is the 15 mm scene with the sphere radius, a
time step scaled with the radius (the Hertz contact time is ~ R), the calibrated contact values
of that size and its calibration record; the particle count follows from the hold-up in kg/m.

The verdict per answer and hold-up (``verdict``): the step from 15 to 10 mm against its noise
(the two standard errors combined). Within two of them the answer is converged at this
resolution and its value is the 10 mm one with an error that holds the step; beyond, it is not
converged, and the trend over 20 -> 15 -> 10 mm is given, with Aitken's extrapolation to small
spheres where the two steps have one sign and the second is at most half the first (the 20 mm
ash missed its heap by 1.9 measured sd, so that first step carries a material difference too).
A step within the noise shows convergence only where the noise is small (``RESOLVED``).
"""
import argparse
import json
import math
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASE = ROOT / "demos" / "cooler_slice.toml"
SCENES = ROOT / "bench" / "seed_cooler" / "size"
CALIBRATIONS = ROOT / "docs" / "calibration" / "size"
PUBLISHED_15 = ROOT / "docs" / "machine" / "seed_cooler" / "original"
BASE_DT = 7e-5                  # s, the 15 mm slice's step
BASE_RADIUS = 0.0075            # m
INCLINE = 5.0
SIZES_MM = (20, 15, 10)
# the answers compared: (map column, label, unit, factor to that unit): the shaft's torque is
# negative (it drives the bed), so its factor is -1
ANSWERS = (("axial_speed", "axial speed", "mm/s", 1e3),
           ("axial_mass_flow", "axial mass flow", "kg/s", 1.0),
           ("shaft/torque_per_metre", "shaft torque", "N m/m", -1.0),
           ("shell/torque_per_metre", "shell torque", "N m/m", 1.0),
           ("shell/conductance_per_metre", "shell conductance", "W/(m K)", 1.0),
           ("dynamic_angle", "dynamic angle", "deg", 1.0),
           ("axial_dispersion", "axial dispersion", "cm^2/s", 1e4))
CONVERGED_SIGMAS = 2.0
# a step within the noise shows convergence only where that noise is small: the value's error
# (the larger of its noise and the step) within 10 % of it, the resolution at which the seed's
# own figures are read (its axial speed of 20 mm/s is read from a plot as 15 - 25)
RESOLVED = 0.10


def calibrated(mm: int) -> dict:
    """The calibrated material of ``mm`` mm spheres (the 15 mm one is docs/calibration's)."""
    path = (ROOT / "docs" / "calibration" / "calibrated_material.toml" if mm == 15
            else CALIBRATIONS / f"{mm}mm" / "calibrated_material.toml")
    return tomllib.loads(path.read_text())


def slice_scene(mm: int) -> str:
    """The 15 mm slice at ``mm`` mm spheres on the ash calibrated at that size (TOML text)."""
    import tomli_w
    doc = tomllib.loads(BASE.read_text())
    cal = calibrated(mm)
    radius = mm / 2000.0
    doc["simulation"]["dt"] = float(f"{BASE_DT * radius / BASE_RADIUS:.3g}")
    doc["particles"][0]["radius"] = radius
    doc["materials"]["ash"]["calibration"] = cal["materials"]["ash"]["calibration"]
    for calibrated_pair in cal["interactions"]:
        for pair in doc["interactions"]:
            if sorted(pair["pair"]) == sorted(calibrated_pair["pair"]):
                for k in ("restitution", "friction", "rolling_friction", "model"):
                    if k in calibrated_pair:
                        pair[k] = calibrated_pair[k]
    head = (f"# The seed's original cooler slice (demos/cooler_slice.toml) with {mm} mm spheres on the\n"
            f"# ash calibrated at {mm} mm (docs/calibration/size/{mm}mm). Written by\n"
            f"# `python bench/size_convergence.py scenes`: edit that, not this.\n\n")
    return head + tomli_w.dumps(doc)


def calibration_json(mm: int) -> dict:
    """The calibrate command's calibration.json of ``mm`` mm spheres."""
    path = (ROOT / "docs" / "calibration" / "calibration.json" if mm == 15
            else CALIBRATIONS / f"{mm}mm" / "calibration.json")
    return json.loads(path.read_text())


def calibration_lines(sizes) -> list:
    """Markdown: one row per size, what its ash was calibrated to and what that cost."""
    L = ["| spheres | calibrated values | model | angle of repose, the last verification's heaps (deg) | within the "
         "measured 38.04 +- 0.81 | rounds | runs | run wall time (s) | record |",
         "|---|---|---|---|---|---|---|---|---|"]
    for mm in sorted(sizes, reverse=True):
        c = calibration_json(mm)
        cal = calibrated(mm)
        pairs = {tuple(sorted(i["pair"])): i for i in cal["interactions"]}
        aa, aw = pairs[("ash", "ash")], pairs[("ash", "steel")]
        values = (f"ash-ash: friction {aa['friction']:g}, rolling {aa['rolling_friction']:g}; "
                  f"ash-steel: friction {aw['friction']:g}, rolling {aw['rolling_friction']:g}")
        t = c["tests"][0]
        runs = c["cost"]["design"]["runs"] + c["cost"]["verification"]["runs"]
        wall = c["cost"]["design"]["wall_s"] + c["cost"]["verification"]["wall_s"]
        link = ("../../../calibration/calibration.md" if mm == 15
                else f"../../../calibration/size/{mm}mm/calibration.md")
        L.append(f"| {mm} mm | {values} | {aa.get('model', 'epsd')} | {t['achieved_mean']:.2f} +- "
                 f"{t['achieved_sd']:.2f} (SEM {t['achieved_sem']:.2f}) | "
                 f"{'yes' if t['within_scatter'] else 'NO'} | {len(c.get('rounds', []))} | {runs} | "
                 f"{wall:.0f} | [calibration.md]({link}) |")
    return L


def rows_at(path: Path) -> dict:
    """The map rows at ``INCLINE`` of the map in ``path``, by hold-up (kg/m)."""
    doc = json.loads((path / "map.json").read_text())
    return {round(r["holdup_kg_per_m"]): r for r in doc["rows"]
            if abs(r["incline_deg"] - INCLINE) < 0.01}


def maps(out: Path) -> dict:
    """{size mm: {hold-up: row}} of every size whose map exists."""
    found = {}
    for mm in SIZES_MM:
        path = PUBLISHED_15 if mm == 15 else out / f"{mm}mm"
        if (path / "map.json").is_file():
            found[mm] = rows_at(path)
    return found


def value(row: dict, key: str, scale: float) -> tuple:
    """(value, standard error) of one answer, in the table's unit."""
    v, se = row.get(key), row.get(f"{key}_standard_error")
    if v is None:
        return math.nan, math.nan
    return v * scale, abs(se * scale) if se is not None else math.nan


def verdict(by_size: dict) -> dict:
    """The size verdict of one answer at one hold-up from {mm: (value, se)}: the step 15 -> 10
    mm in standard errors; ``status``: "converged" (within ``CONVERGED_SIGMAS`` of them, and the
    value's error within ``RESOLVED`` of it), "within the noise" (within them, but the noise too
    large to show convergence) or "not converged"; the value where the step is within the noise
    (the 10 mm one, its error the larger of its noise and the step) and the trend (the change
    per step, 20 -> 15 -> 10)."""
    out = {"sizes": {mm: list(v) for mm, v in by_size.items()}}
    if 15 in by_size and 10 in by_size:
        (a15, s15), (a10, s10) = by_size[15], by_size[10]
        step, noise = a10 - a15, math.hypot(s15, s10)
        out["step_15_10"] = step
        out["step_15_10_relative"] = step / a15 if a15 else math.nan
        out["step_sigmas"] = abs(step) / noise if noise > 0 else math.inf
        within = out["step_sigmas"] <= CONVERGED_SIGMAS
        error = max(s10, abs(step))
        resolved = abs(a10) > 0 and error <= RESOLVED * abs(a10)
        out["status"] = ("not converged" if not within else
                         "converged" if resolved else "within the noise")
        out["converged"] = out["status"] == "converged"
        if within:
            out["value"], out["error"] = a10, error
    if 20 in by_size and 15 in by_size:
        out["step_20_15"] = by_size[15][0] - by_size[20][0]
        out["step_20_15_relative"] = out["step_20_15"] / by_size[20][0] if by_size[20][0] else math.nan
    if "step_15_10" in out and "step_20_15" in out and out["status"] == "not converged":
        # Aitken's extrapolation over equal steps in size: successive changes shrinking by
        # r = step(15->10) / step(20->15), the rest sums to step * r / (1 - r). Only for
        # changes of one sign that at least halve (0 < r <= 0.5: the rest no larger than the
        # last step; slower series extrapolate noise); the correction itself is its error
        r = out["step_15_10"] / out["step_20_15"] if out["step_20_15"] else math.nan
        if 0.0 < r <= 0.5:
            rest = out["step_15_10"] * r / (1.0 - r)
            out["extrapolated"], out["extrapolated_error"] = by_size[10][0] + rest, abs(rest)
    return out


def _fmt(v: float, se: float) -> str:
    if not math.isfinite(v):
        return "-"
    digits = 3 if abs(v) < 10 else (1 if abs(v) < 1000 else 0)
    return f"{v:.{digits}f} +- {se:.{digits}f}" if math.isfinite(se) else f"{v:.{digits}f}"


def table(out: Path) -> dict:
    """Write size_convergence.md and .json in ``out`` from the maps found; return the json."""
    found = maps(out)
    holdups = sorted(set.intersection(*(set(r) for r in found.values()))) if found else []
    result = {"incline_deg": INCLINE, "sizes_mm": sorted(found), "holdups_kg_per_m": holdups,
              "answers": {}}
    L = ["# The seed's original cooler against the sphere size", "",
         "The one-row slice of the original design at 5 deg, 6 s per point, each size on the ash "
         "calibrated at that size against the rotary-cooler paper's eight heaps (below). Steady means +- "
         "standard error. "
         f"Converged: the step from 15 to 10 mm within {CONVERGED_SIGMAS:g} standard errors "
         "(both maps' combined), and the value (the 10 mm one, its error the larger of its "
         f"noise and that step) known within {RESOLVED:.0%}. Within the noise: the step within "
         f"{CONVERGED_SIGMAS:g} standard errors, but the noise too large to show convergence at "
         f"{RESOLVED:.0%}. Not converged: where the steps 20 -> 15 and 15 -> 10 mm have one "
         "sign and the second is at most half the first, Aitken's extrapolation to small spheres (the 10 mm value plus the "
         "rest of a geometric series of steps), its correction as its error; the 20 mm ash "
         "missed its heap by 1.9 measured sd, so that step holds a material difference too. "
         "Made by `python bench/size_convergence.py table`.", ""]
    def heading(mm: int) -> str:
        return f"{mm} mm" + ("" if calibration_json(mm)["within_scatter"] else " (not calibrated)")
    L += ["| answer | hold-up (kg/m) | " + " | ".join(heading(mm) for mm in sorted(found, reverse=True))
          + " | 20 -> 15 mm | 15 -> 10 mm (standard errors) | verdict |",
          "|---|---|" + "---|" * len(found) + "---|---|---|"]
    for key, label, unit, scale in ANSWERS:
        result["answers"][key] = {}
        for h in holdups:
            by_size = {mm: value(found[mm][h], key, scale) for mm in found}
            v = verdict(by_size)
            result["answers"][key][str(h)] = v
            cells = [_fmt(*by_size[mm]) + ("" if found[mm][h].get(f"{key}_steady", True) else "*")
                     for mm in sorted(found, reverse=True)]
            s2015 = (f"{100 * v['step_20_15_relative']:+.0f} %" if "step_20_15_relative" in v else "-")
            s1510 = (f"{100 * v['step_15_10_relative']:+.0f} % ({v['step_sigmas']:.1f})"
                     if "step_sigmas" in v else "-")
            conv = (f"{v['status']}: {_fmt(v['value'], v['error'])}" if "value" in v
                    else v.get("status", "-"))
            if "extrapolated" in v:
                conv += f"; extrapolated {_fmt(v['extrapolated'], v['extrapolated_error'])}"
            L.append(f"| {label} ({unit}) | {h} | " + " | ".join(cells) + f" | {s2015} | {s1510} | {conv} |")
    L += ["", "`*`: not steady within the window (MSER-5 finds no steady start in its first half: "
          "the series still drifts), as the maps mark it; its mean is that of the second half.", ""]
    if 10 in found and 15 in found:
        L += ["## Verdicts", ""]
        for key, label, unit, scale in ANSWERS:
            vs = result["answers"][key]
            parts = []
            for status in ("converged", "within the noise", "not converged"):
                at = [(h, v) for h, v in vs.items() if v["status"] == status]
                if at:
                    parts.append(f"{status} at " + ", ".join(
                        f"{h} kg/m ({100 * v['step_15_10_relative']:+.0f} %, "
                        f"{v['step_sigmas']:.1f} standard errors"
                        + (f", the value +- {100 * v['error'] / abs(v['value']):.0f} %"
                           if "value" in v and v["value"] else "")
                        + (f"; 20 -> 15 mm {100 * v['step_20_15_relative']:+.0f} %"
                           if status == "not converged" and "step_20_15_relative" in v else "")
                        + ")" for h, v in at))
            L.append(f"- **{label}**: " + "; ".join(parts) + ".")
        L.append("")
    L += ["## The ash at each size", "",
          "Each size calibrated by `taichi-dem calibrate` against the same heaps "
          "(demos/calibration/fly_ash_seed001*.toml); run wall time: the runs' own, two at once "
          "on this machine's two cores.", ""] + calibration_lines(found)
    L += ["", "Particles per slice: " + "; ".join(
        f"{mm} mm: " + ", ".join(f"{found[mm][h]['particles']:,} at {h} kg/m" for h in holdups)
        for mm in sorted(found, reverse=True)) + "."]
    out.mkdir(parents=True, exist_ok=True)
    (out / "size_convergence.md").write_text("\n".join(L) + "\n")
    (out / "size_convergence.json").write_text(json.dumps(result, indent=1) + "\n")
    return result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=["scenes", "table"])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "machine" / "seed_cooler" / "size")
    a = ap.parse_args(argv)
    if a.what == "scenes":
        SCENES.mkdir(parents=True, exist_ok=True)
        for mm in SIZES_MM:
            if mm != 15 and (CALIBRATIONS / f"{mm}mm" / "calibrated_material.toml").is_file():
                path = SCENES / f"cooler_slice_{mm}mm.toml"
                path.write_text(slice_scene(mm))
                print(f"wrote {path.relative_to(ROOT)}")
        return 0
    result = table(a.out)
    print(f"wrote {a.out / 'size_convergence.md'} (sizes {result['sizes_mm']} mm, hold-ups "
          f"{result['holdups_kg_per_m']} kg/m)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
