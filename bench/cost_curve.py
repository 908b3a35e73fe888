#!/usr/bin/env python3
"""The cost curve (issue 14 item 1): particle-steps per second of the LAMMPS chute scene at
1k to 1M particles, taichi_dem and LAMMPS (gran/hertz/history, 1 and 2 ranks) on the same
particles in the same run, with the fixed per-step cost and the per-particle cost fitted
(time per step = a + b N) and a PNG.

    .venv/bin/python bench/cost_curve.py --sizes 1k 4k 16k 64k 256k 1M --out bench/results/cost_curve

Sizes up to 32k cut the benchmark's 32,000 particles (``max_particles``: a shorter periodic
x), larger ones tile it (``copies``); LAMMPS reads a data file written from the same particles.
The smallest is 2k: the bed is 40 particles deep, and 1k would need a periodic length below
two pair cut-offs (the engine refuses it); a 1k scene of this flow needs a shallower bed. Steps per run are
``--work`` particle-steps divided by N (clamped to 50..2000), after 50 warm-up steps (JIT).
"""
import argparse
import json
import statistics
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from chute import run_taichi_dem  # noqa: E402
from chute_scene import write_chute_scene  # noqa: E402
from lammps_chute import LammpsMissing, run_lammps  # noqa: E402

SIZES = {"2k": 2000, "4k": 4000, "16k": 16000, "32k": 32000, "64k": 64000, "128k": 128000,
         "256k": 256000, "1M": 1024000}


def scene_for(size: int, out: Path) -> Path:
    if size <= 32000:
        return write_chute_scene(out, max_particles=size if size < 32000 else None)
    return write_chute_scene(out, copies=size // 32000)


def lammps_data_for(scene: Path) -> Path:
    """A LAMMPS atom_style sphere data file with the scene's particles (flowing: type 1 with
    their velocities; base: type 2 at rest)."""
    doc = tomllib.loads(scene.read_text())
    lo, hi = doc["domain"]["min"], doc["domain"]["max"]
    density = doc["materials"]["grain"]["density"]
    flow = np.loadtxt(scene.parent / "chute_flowing.csv", delimiter=",", skiprows=1, ndmin=2)
    base = np.loadtxt(scene.parent / "chute_base.csv", delimiter=",", skiprows=1, ndmin=2)
    n = len(flow) + len(base)
    lines = ["LAMMPS data file (taichi_dem bench/cost_curve.py)", "", f"{n} atoms", "",
             "2 atom types", "", f"{lo[0]:.9g} {hi[0]:.9g} xlo xhi", f"{lo[1]:.9g} {hi[1]:.9g} ylo yhi",
             f"{lo[2]:.9g} {hi[2]:.9g} zlo zhi", "", "Atoms", ""]
    k = 1
    for rows, kind in ((flow, 1), (base, 2)):
        for r in rows:
            lines.append(f"{k} {kind} {2 * r[3]:.9g} {density:.9g} {r[0]:.9g} {r[1]:.9g} {r[2]:.9g}")
            k += 1
    lines += ["", "Velocities", ""]
    k = 1
    for r in flow:
        lines.append(f"{k} " + " ".join(f"{float(c):.9g}" for c in r[4:10]))
        k += 1
    for _ in base:
        lines.append(f"{k} 0 0 0 0 0 0")
        k += 1
    path = scene.parent / "data.chute"
    path.write_text("\n".join(lines) + "\n")
    return path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", nargs="+", default=["2k", "4k", "16k", "64k", "256k", "1M"],
                   choices=list(SIZES))
    p.add_argument("--work", type=float, default=3e7, help="particle-steps per timed run")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    p.add_argument("--no-lammps", action="store_true")
    p.add_argument("--out", type=Path, default=HERE / "results" / "cost_curve")
    a = p.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label in a.sizes:
            size = SIZES[label]
            scene = scene_for(size, Path(tmp) / label)
            steps = int(min(max(a.work / size, 50), 2000))
            ours = [run_taichi_dem(str(scene), steps, 50)["particle_steps_per_s"]
                    for _ in range(a.repeats)]
            row = {"size": label, "steps": steps, "taichi_dem": statistics.median(ours),
                   "taichi_dem_runs": ours}
            if not a.no_lammps:
                data = lammps_data_for(scene)
                for ranks in a.ranks:
                    try:
                        runs = [run_lammps(steps, ranks, data)["particle_steps_per_s"]
                                for _ in range(a.repeats)]
                    except LammpsMissing as e:
                        print(f"LAMMPS skipped: {e}")
                        a.no_lammps = True
                        break
                    row[f"lammps_{ranks}"] = statistics.median(runs)
            row["particles"] = int(sum(1 for _ in open(scene.parent / "chute_flowing.csv")) - 1
                                   + sum(1 for _ in open(scene.parent / "chute_base.csv")) - 1)
            rows.append(row)
            print(json.dumps({k: (round(v / 1e6, 3) if isinstance(v, float) else v)
                              for k, v in row.items() if k != "taichi_dem_runs"}), flush=True)
    n = np.array([r["particles"] for r in rows], float)
    # time per step = a + b N, fitted to taichi_dem's medians
    t_step = n / np.array([r["taichi_dem"] for r in rows])
    b, a0 = np.polyfit(n, t_step, 1) if len(n) > 1 else (t_step[0] / n[0], 0.0)
    print(f"\ntaichi_dem: time per step = {a0 * 1e6:.1f} us + {b * 1e9:.2f} ns x N "
          f"(fixed share at 1k: {a0 / (a0 + b * 1000):.0%}, at 2k: {a0 / (a0 + b * 2000):.0%})")
    print("| particles | steps | taichi_dem M/s | " + " | ".join(
        f"LAMMPS {k} rank(s) M/s | ratio" for k in a.ranks if not a.no_lammps) + " |")
    for r in rows:
        cells = [f"{r['particles']:,}", str(r["steps"]), f"{r['taichi_dem'] / 1e6:.2f}"]
        for k in a.ranks:
            if f"lammps_{k}" in r:
                cells += [f"{r[f'lammps_{k}'] / 1e6:.2f}", f"{r['taichi_dem'] / r[f'lammps_{k}']:.2f}"]
        print("| " + " | ".join(cells) + " |")
    (a.out / "cost_curve.json").write_text(json.dumps({"rows": rows, "fixed_s": a0,
                                                       "per_particle_s": b}, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.plot(n, [r["taichi_dem"] / 1e6 for r in rows], "o-", label="taichi_dem (f32, 2 threads)")
    for k in a.ranks:
        if all(f"lammps_{k}" in r for r in rows):
            ax.plot(n, [r[f"lammps_{k}"] / 1e6 for r in rows], "s--", label=f"LAMMPS {k} rank(s)")
    ax.plot(n, n / (a0 + b * n) / 1e6, ":", color="grey", label=f"fit: {a0 * 1e6:.0f} us + {b * 1e9:.1f} ns N")
    ax.set_xscale("log")
    ax.set_xlabel("particles")
    ax.set_ylabel("million particle-steps per second")
    ax.set_title("Chute benchmark: cost against size (same machine, same run)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out / "cost_curve.png", dpi=110)
    print(f"plot: {a.out / 'cost_curve.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
