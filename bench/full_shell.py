#!/usr/bin/env python3
"""The seed's original cooler up to a full shell (issue 44 item 4): the drive torque, the axial
flow and the power of its one-row slice (calibrated ash, 15 mm, 5 deg) against the hold-up,
from 30 kg/m to what the shell holds, and where the torque reaches the seed's 6 kN m and
1 kN m.

    taichi-dem map demos/cooler_slice.toml --holdup "150 kg/m" "270 kg/m" --incline 5 \\
        --time 6 --threads 1 --pictures --out OUT/full_a
    taichi-dem map demos/cooler_slice.toml --holdup "210 kg/m" --incline 5 --time 6 \\
        --threads 1 --pictures --out OUT/full_b
    python bench/full_shell.py --maps docs/machine/seed_cooler/original OUT/full_a OUT/full_b \\
        --out docs/machine/seed_cooler/full_shell

A cooler fed beyond its capacity fills along its length until the bed stands at the same
hold-up from end to end (the seed's coolers "at their maximum transport capacity" after 330 s
of overloading): the machine's drive torque is then the slice's torque per metre times its
6 m, and its flow the slice's axial flow. The seed's 6 kN m (original) and 1 kN m (optimised)
are torques of such "fully loaded" coolers; the hold-up where 6 m of our slice reach them says
whether they are those of an overfilled cooler.
"""
import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

LENGTH = 6.0
SEED_TORQUES = {"original": 6000.0, "optimised": 1000.0}      # N m, "fully loaded"
INCLINE = 5.0
OPTIMISED_INCLINE = 2.0


def rows_at(maps, incline: float = INCLINE) -> tuple[list, dict]:
    """The rows of every map at ``incline``, by hold-up (a later map's row replaces an
    earlier one's), and the first map's machine block."""
    rows, machine = {}, None
    for folder in maps:
        doc = json.loads((Path(folder) / "map.json").read_text())
        machine = machine or doc["machine"]
        for r in doc["rows"]:
            if abs(r["incline_deg"] - incline) < 1e-6:
                rows[round(r["holdup_kg_per_m"], 6)] = r
    return [rows[k] for k in sorted(rows)], machine


def crossing(x, y, level: float):
    """The first x where the piecewise-linear y(x) reaches ``level`` (None if it does not)."""
    for i in range(len(x) - 1):
        a, b = y[i] - level, y[i + 1] - level
        if a == 0:
            return x[i]
        if a * b < 0:
            return x[i] + (x[i + 1] - x[i]) * a / (a - b)
    return None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--maps", nargs="+", required=True, help="map folders (their 5 deg rows)")
    p.add_argument("--optimised", nargs="*", default=[],
                   help="the optimised design's map folders (their 2 deg rows): where the "
                        "seed's 1 kN m falls on its own curve")
    p.add_argument("--out", type=Path, required=True)
    a = p.parse_args(argv)
    rows, machine = rows_at(a.maps)
    h = np.array([r["holdup_kg_per_m"] for r in rows])
    fill = np.array([r["fill_fraction"] for r in rows])
    drive = np.array([-r["shaft/torque_per_metre"] for r in rows]) * LENGTH
    drive_e = np.array([r["shaft/torque_per_metre_standard_error"] for r in rows]) * LENGTH
    shell = np.array([r["shell/torque_per_metre"] for r in rows]) * LENGTH
    power = np.array([r["shaft/power_per_metre"] for r in rows]) * LENGTH
    flow = np.array([r["axial_mass_flow"] for r in rows]) * 3.6
    flow_e = np.array([r["axial_mass_flow_standard_error"] for r in rows]) * 3.6
    steady = [r.get("shaft/torque_per_metre_steady", True) and r.get("axial_mass_flow_steady", True)
              for r in rows]
    full = h[-1] / fill[-1]           # kg/m at fill 1
    lines = [f"# The original cooler up to a full shell (calibrated ash, 15 mm, {INCLINE:g} deg)",
             "", f"One-row slice maps at {INCLINE:g} deg ({', '.join(map(str, a.maps))}); the "
             f"machine's figures are the slice's per metre times {LENGTH:g} m, the bed level "
             f"from end to end (an overfilled cooler). A full shell holds {full:.0f} kg/m at "
             "the maps' bulk solid fraction.", "",
             "| hold-up (kg/m) | fill | drive torque, 6 m (N m) | shell torque, 6 m (N m) | "
             "shaft power, 6 m (W) | axial flow (t/h) | steady |",
             "|---|---|---|---|---|---|---|"]
    for i in range(len(rows)):
        lines.append(f"| {h[i]:.0f} | {fill[i]:.2f} | {drive[i]:.0f} +- {drive_e[i]:.0f} | "
                     f"{shell[i]:.0f} | {power[i]:.0f} | {flow[i]:.2f} +- {flow_e[i]:.2f} | "
                     f"{'yes' if steady[i] else 'no'} |")
    lines.append("")
    curves = {"original": (h, drive, fill, INCLINE)}
    if a.optimised:
        o_rows, _ = rows_at(a.optimised, OPTIMISED_INCLINE)
        curves["optimised"] = (np.array([r["holdup_kg_per_m"] for r in o_rows]),
                               np.array([-r["shaft/torque_per_metre"] for r in o_rows]) * LENGTH,
                               np.array([r["fill_fraction"] for r in o_rows]), OPTIMISED_INCLINE)
    for name, torque in SEED_TORQUES.items():
        if name not in curves:
            continue
        ch, cd, cf, incline = curves[name]
        at = crossing(ch, cd, torque)
        what = f"The seed's {torque / 1e3:g} kN m ({name} design, fully loaded; our {name} slice at {incline:g} deg)"
        if at is None:
            lines.append(f"- {what}: not reached up to {ch[-1]:.0f} kg/m "
                         f"({100 * cf[-1]:.0f} % full): {cd[-1]:.0f} N m there."
                         if torque > cd.max() else
                         f"- {what}: below our lightest hold-up ({cd[0]:.0f} N m at {ch[0]:.0f} kg/m).")
        else:
            k = int(np.searchsorted(ch, at))
            lines.append(f"- {what}: reached at {at:.0f} kg/m ({100 * at / full:.0f} % full), "
                         f"between the slices at {ch[k - 1]:.0f} and {ch[k]:.0f} kg/m.")
    (a.out).mkdir(parents=True, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    axes[0].errorbar(h, drive / 1e3, yerr=drive_e / 1e3, fmt="o-",
                     label=f"original, {INCLINE:g} deg: drive torque, 6 m")
    if "optimised" in curves:
        ch, cd, _, incline = curves["optimised"]
        axes[0].plot(ch, cd / 1e3, "s-", label=f"optimised, {incline:g} deg")
    for name, torque in SEED_TORQUES.items():
        axes[0].axhline(torque / 1e3, ls="--", color="0.5")
        axes[0].text(h[0], torque / 1e3, f" seed, {name}, fully loaded", va="bottom", fontsize=8)
    axes[0].set_xlabel("hold-up (kg/m)")
    axes[0].set_ylabel("torque (kN m)")
    axes[0].legend()
    axes[1].errorbar(h, flow, yerr=flow_e, fmt="o-")
    axes[1].set_xlabel("hold-up (kg/m)")
    axes[1].set_ylabel("axial flow (t/h)")
    fig.suptitle(f"original cooler, calibrated ash, {INCLINE:g} deg: one-row slice x {LENGTH:g} m")
    fig.tight_layout()
    fig.savefig(a.out / "full_shell.png", dpi=110)
    lines += ["", "![torque and flow against hold-up](full_shell.png)"]
    # the beds at the end of their runs (map --pictures), those inside OUT linked
    for folder in a.maps:
        for png in sorted(Path(folder).glob("bed_*.png")):
            try:
                rel = png.resolve().relative_to(a.out.resolve())
            except ValueError:
                continue
            lines += ["", f"![the bed: {png.stem}]({rel.as_posix()})"]
    text = "\n".join(lines) + "\n"
    (a.out / "full_shell.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
