#!/usr/bin/env python3
"""What each modelling choice costs a slice's map (issue 31 item 5): the map of a slice with one
scene key changed (`taichi-dem map --set`) beside the scene's own map, each figure's difference
against the two standard errors combined, so that a bias is told from noise (|z| > 2: a bias
the runs resolve; below: within the noise of runs this long), and the wall time of each map.

    python bench/modelling_choices.py --out bench/results/modelling_choices
    python bench/modelling_choices.py --out bench/results/modelling_choices --reuse   # table

Default slice: bench/direct_check/cooler_slice.toml (20 mm spheres in a 0.3 m cooler with a
25 mm paddle clearance), hold-ups 6 and 9 kg/m at 5 deg, 15 s each. Choices: f64; spheres of
16 and 24 mm (24 mm just passes the clearance); the thermal time scale 10.

``--preset seed``: the seed's one-row slice (demos/cooler_slice.toml: 15 mm spheres, 20 mm
paddle clearance) at its mapped hold-ups 30, 60 and 90 kg/m at 5 deg, 6 s each, the reference
being the rows at 5 deg of the design's published map (docs/machine/seed_cooler/original, the
same command and length) rather than a new run. Choices: f64; spheres of 20 mm (as wide as the
clearance) and 30 mm (wider: the seed's question of what the clearance allows); the thermal
time scale 10; two paddle rows staggered 45 degrees (bench/seed_cooler/cooler_slice_two_rows.toml)
against the one-row slice's stagger 0.

    python bench/modelling_choices.py --preset seed --out docs/machine/seed_cooler/modelling_choices

``--preset seed_optimised``: the optimised design's slice at 2 deg (its incline) against its
published map, with 20 mm spheres, f64, and two rows staggered 45 degrees:

    python bench/modelling_choices.py --preset seed_optimised --out docs/machine/seed_cooler/modelling_choices_optimised

f32 against f64 over a longer window at the operating hold-up (20 s at 60 kg/m, 5 deg):

    taichi-dem map demos/cooler_slice.toml --holdup 60 --incline 5 --time 20 \
        --set simulation.precision=f32 --out docs/machine/seed_cooler/modelling_choices/long_f32
    (the same with f64 into long_f64)
    python bench/modelling_choices.py --compare docs/machine/seed_cooler/modelling_choices/long_f32 \
        docs/machine/seed_cooler/modelling_choices/long_f64 --out docs/machine/seed_cooler/modelling_choices/precision_long.md

The presets' slices now hold the calibrated ash (issue 44); the choices published so far
were mapped on the free-rolling ash (rolling friction 0.05, EPSD) against its own maps, and
lie with them in docs/machine/seed_cooler/free_rolling/ (modelling_choices*/). A run now maps
the choices on the calibrated ash against docs/machine/seed_cooler/original and optimised.
"""
import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "bench" / "direct_check" / "cooler_slice.toml"
CHOICES = {"reference": [],
           "f64": ["simulation.precision=f64"],
           "16 mm spheres": ["particles.0.radius=0.008"],
           "24 mm spheres": ["particles.0.radius=0.012"],
           "thermal time scale 10": ["thermal.time_scale=10"]}
SEED_SCENE = ROOT / "demos" / "cooler_slice.toml"
SEED_REFERENCE = ROOT / "docs" / "machine" / "seed_cooler" / "original"
SEED_CHOICES = {"reference": [],
                "20 mm spheres": ["particles.0.radius=0.01"],
                "30 mm spheres": ["particles.0.radius=0.015"],
                "thermal time scale 10": ["thermal.time_scale=10"],
                "f64": ["simulation.precision=f64"],
                # another scene, not a key: two rows staggered 45 degrees (the one-row slice
                # has stagger 0; the seed gives none, our full machine staggers 45)
                "two rows stagger 45": {"scene": ROOT / "bench" / "seed_cooler" /
                                        "cooler_slice_two_rows.toml"}}
SEED_OPTIMISED_SCENE = ROOT / "demos" / "cooler_slice_optimised.toml"
SEED_OPTIMISED_REFERENCE = ROOT / "docs" / "machine" / "seed_cooler" / "optimised"
SEED_OPTIMISED_CHOICES = {"reference": [],
                          "20 mm spheres": ["particles.0.radius=0.01"],
                          "f64": ["simulation.precision=f64"],
                          "two rows stagger 45": {"scene": ROOT / "bench" / "seed_cooler" /
                                                  "cooler_slice_optimised_two_rows.toml"}}
FIGURES = ("axial_mass_flow", "shaft/torque_per_metre", "shell/torque_per_metre",
           "shell/conductance_per_metre", "dynamic_angle")


def folder(out: Path, name: str) -> Path:
    return out / name.replace(" ", "_")


def compare(first: Path, second: Path) -> str:
    """Markdown: two maps of the same slice (f32 and f64 over a long window), row by row, each
    figure's difference with z (the difference over the two standard errors combined)."""
    a = json.loads((first / "map.json").read_text())
    b = json.loads((second / "map.json").read_text())
    lines = [f"{first.name} against {second.name} ({a['scene']}): each figure's value in both, "
             "the difference (second - first) in % of the first, and z (|z| > 2: a bias these "
             "runs resolve; below it, the bias is under about two standard errors)", "",
             "| hold-up (kg/m) | incline (deg) | figure | " + first.name + " | " + second.name
             + " | difference | z |", "|---|---|---|---|---|---|---|"]
    for ra in a["rows"]:
        rb = next((r for r in b["rows"] if abs(r["holdup_kg_per_m"] - ra["holdup_kg_per_m"]) < 1e-6
                   and abs(r["incline_deg"] - ra["incline_deg"]) < 1e-6), None)
        if rb is None:
            continue
        for fig in FIGURES + ("axial_speed", "shell/heat_transfer_coefficient"):
            va, ea = ra.get(fig, math.nan), ra.get(fig + "_standard_error", math.nan)
            vb, eb = rb.get(fig, math.nan), rb.get(fig + "_standard_error", math.nan)
            e = math.hypot(ea, eb)
            lines.append(f"| {ra['holdup_kg_per_m']:.3g} | {ra['incline_deg']:.3g} | {fig} | "
                         f"{va:.4g} +- {ea:.2g} | {vb:.4g} +- {eb:.2g} | "
                         f"{100 * (vb - va) / abs(va):+.1f} % | {(vb - va) / e:+.1f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "modelling_choices")
    p.add_argument("--preset", choices=["direct_check", "seed", "seed_optimised"],
                   default="direct_check",
                   help="which slice and choices (module docstring)")
    p.add_argument("--scene", type=Path, default=None)
    p.add_argument("--holdups", nargs="+", default=None)
    p.add_argument("--incline", default=None, help="deg (default 5; seed_optimised 2)")
    p.add_argument("--time", type=float, default=None)
    p.add_argument("--reference", type=Path, default=None,
                   help="a map folder whose rows at --incline are the reference (not re-run)")
    p.add_argument("--only", nargs="+", default=None, help="choices to run (default all)")
    p.add_argument("--reuse", action="store_true", help="keep maps already in OUT")
    p.add_argument("--compare", nargs=2, type=Path, metavar=("FIRST", "SECOND"), default=None,
                   help="only compare two maps already written (e.g. f32 and f64 over a long "
                        "window) and write OUT (a .md file)")
    a = p.parse_args(argv)
    if a.compare:
        text = compare(*a.compare)
        print(text)
        a.out.write_text(text + "\n")
        return 0
    seed = a.preset in ("seed", "seed_optimised")
    optimised = a.preset == "seed_optimised"
    choices = (SEED_OPTIMISED_CHOICES if optimised else SEED_CHOICES) if seed else CHOICES
    a.scene = a.scene or ((SEED_OPTIMISED_SCENE if optimised else SEED_SCENE) if seed else SCENE)
    a.holdups = a.holdups or (["30", "60", "90"] if seed else ["6", "9"])
    a.time = a.time or (6.0 if seed else 15.0)
    a.incline = a.incline or ("2" if optimised else "5")
    if a.reference is None and seed:
        a.reference = SEED_OPTIMISED_REFERENCE if optimised else SEED_REFERENCE
    walls_file = a.out / "walls.json"
    walls = json.loads(walls_file.read_text()) if walls_file.exists() else {}
    for name, sets in choices.items():
        if name == "reference" and a.reference is not None:
            continue
        if a.only and name not in a.only and name != "reference":
            continue
        out = folder(a.out, name)
        if a.reuse and (out / "map.json").exists():
            continue
        scene = a.scene
        if isinstance(sets, dict):          # a choice that is another scene
            scene, sets = sets["scene"], sets.get("sets", [])
        cmd = [sys.executable, "-m", "taichi_dem", "map", str(scene), "--holdup", *a.holdups,
               "--incline", a.incline, "--time", str(a.time), "--out", str(out)]
        for s in sets:
            cmd += ["--set", s]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True)
        walls[name] = time.perf_counter() - t0
        a.out.mkdir(parents=True, exist_ok=True)
        walls_file.write_text(json.dumps(walls, indent=1))
    maps = {}
    for name in choices:
        f = folder(a.out, name) / "map.json"
        if name == "reference" and a.reference is not None:
            f = a.reference / "map.json"
        if f.exists():
            rows = json.loads(f.read_text())["rows"]
            maps[name] = [r for r in rows if abs(r["incline_deg"] - float(a.incline)) < 1e-6]
    ref = maps["reference"]
    lines = [f"Slice {a.scene.name}, {a.time:g} s per hold-up at {a.incline} deg; each figure: "
             "the choice's value, its difference from the reference in %, and z = difference / "
             "combined standard error (|z| > 2: a bias these runs resolve).", "",
             "| choice | hold-up (kg/m) | " + " | ".join(FIGURES) + " | map wall (min) |",
             "|---|---|" + "---|" * len(FIGURES) + "---|"]
    for name, rows in maps.items():
        for k, row in enumerate(rows):
            cells = []
            for fig in FIGURES:
                v, e = row.get(fig, math.nan), row.get(fig + "_standard_error", math.nan)
                if name == "reference":
                    cells.append(f"{v:.4g} +- {e:.2g}")
                    continue
                match = [x for x in ref if abs(x["holdup_kg_per_m"] - row["holdup_kg_per_m"])
                         < 1e-6 * max(1.0, row["holdup_kg_per_m"])]
                rr = match[0] if match else {}
                r, re_ = rr.get(fig, math.nan), rr.get(fig + "_standard_error", math.nan)
                diff = v - r
                z = diff / math.hypot(e, re_) if math.hypot(e, re_) > 0 else math.nan
                pct = 100.0 * diff / abs(r) if r else math.nan
                cells.append(f"{v:.4g} ({pct:+.0f} %, z {z:+.1f})")
            wall = walls.get(name)
            lines.append(f"| {name} | {row['holdup_kg_per_m']:.3g} | " + " | ".join(cells)
                         + f" | {wall / 60:.1f} |" if wall and k == 0 else
                         f"| {name} | {row['holdup_kg_per_m']:.3g} | " + " | ".join(cells) + " | |")
    text = "\n".join(lines)
    print(text)
    (a.out / "choices.md").write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
