#!/usr/bin/env python3
"""The cost curve (issue 14 item 1): particle-steps per second of the LAMMPS chute scene at
1k to 1M particles, taichi_dem and LAMMPS (gran/hertz/history, 1 and 2 ranks) on the same
particles in the same run, with the fixed per-step cost and the per-particle cost fitted
(time per step = a + b N) and a PNG.

    .venv/bin/python bench/cost_curve.py --sizes 1k 4k 16k 64k 256k 1M --out bench/results/cost_curve

Sizes up to 32k cut the benchmark's 32,000 particles (``max_particles``: a shorter periodic
x), larger ones tile it (``copies``); LAMMPS reads a data file written from the same particles.
At 1k the box is halved in y as well (an x cut alone would be shorter than two pair
cut-offs). Steps per run are ``--work`` particle-steps divided by N (clamped to 50..2000),
after 50 warm-up steps (JIT). ``--repeats`` rounds per size, each running every code once,
taichi_dem first in even rounds and LAMMPS first in odd ones; the table gives the ratio of
the medians and [the median of the ratios paired within a round].

The engine has two loop modes (engine/stepper.py): serial loops with several steps per launch
below ``parallel_from`` particles, parallel loops with two launches per step from it on. Up
to ``--both-modes-up-to`` particles each mode is also run forced (``serial``: parallel_from
huge; ``parallel``: parallel_from = 0), and each mode's cost is fitted on its own sizes:
time per step = a + b N, a the fixed per-step cost, b the per-particle cost.
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

SIZES = {"1k": 1000, "2k": 2000, "4k": 4000, "16k": 16000, "32k": 32000, "64k": 64000, "128k": 128000,
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
    p.add_argument("--sizes", nargs="+", default=["1k", "4k", "16k", "64k", "256k", "1M"],
                   choices=list(SIZES))
    p.add_argument("--work", type=float, default=3e7, help="particle-steps per timed run")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    p.add_argument("--no-lammps", action="store_true")
    p.add_argument("--out", type=Path, default=HERE / "results" / "cost_curve")
    p.add_argument("--both-modes-up-to", type=int, default=16000, metavar="N",
                   help="also run the forced serial and parallel modes up to N particles")
    p.add_argument("--from-json", type=Path, help="redo the fits, table and plot of a saved "
                   "cost_curve.json (no runs)")
    a = p.parse_args(argv)
    if a.from_json:
        return report(json.loads(a.from_json.read_text())["rows"], a)
    a.out.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label in a.sizes:
            size = SIZES[label]
            scene = scene_for(size, Path(tmp) / label)
            steps = int(min(max(a.work / size, 50), 2000))
            data = None if a.no_lammps else lammps_data_for(scene)
            ours, serial = [], None
            forced = {"serial": [], "parallel": []}
            lammps = {k: [] for k in ([] if a.no_lammps else a.ranks)}

            def run_ours():
                nonlocal serial
                r = run_taichi_dem(str(scene), steps, 50)
                ours.append(r["particle_steps_per_s"])
                serial = r["serial"]
                if size <= a.both_modes_up_to:
                    for mode, threshold in (("serial", 10 ** 9), ("parallel", 0)):
                        forced[mode].append(run_taichi_dem(str(scene), steps, 50, parallel_from=threshold)
                                            ["particle_steps_per_s"])

            def run_peer():
                for ranks in list(lammps):
                    try:
                        lammps[ranks].append(run_lammps(steps, ranks, data)["particle_steps_per_s"])
                    except LammpsMissing as e:
                        print(f"LAMMPS skipped: {e}")
                        a.no_lammps = True
                        lammps.clear()
                        return
            # rounds: taichi_dem first in even rounds, LAMMPS first in odd ones (this host's
            # speed drifts 10 - 40 % over minutes; runs seconds apart share their phase)
            for round_ in range(a.repeats):
                for run in ((run_ours, run_peer) if round_ % 2 == 0 else (run_peer, run_ours)):
                    run()
            row = {"size": label, "steps": steps, "taichi_dem": statistics.median(ours),
                   "taichi_dem_runs": ours, "mode": "serial" if serial else "parallel"}
            for mode, v in forced.items():
                if v:
                    row[f"taichi_dem_{mode}"] = statistics.median(v)
            for ranks, v in lammps.items():
                if len(v) == len(ours):
                    row[f"lammps_{ranks}"] = statistics.median(v)
                    row[f"lammps_{ranks}_runs"] = v
                    # the median of the ratios within a round
                    row[f"paired_{ranks}"] = statistics.median(o / l for o, l in zip(ours, v))
            row["particles"] = int(sum(1 for _ in open(scene.parent / "chute_flowing.csv")) - 1
                                   + sum(1 for _ in open(scene.parent / "chute_base.csv")) - 1)
            rows.append(row)
            print(json.dumps({k: (round(v / 1e6, 3) if isinstance(v, float) and "paired" not in k
                                  else round(v, 3) if isinstance(v, float) else v)
                              for k, v in row.items() if not k.endswith("_runs")}), flush=True)
    return report(rows, a)


def fit_mode(rows, mode, largest=None):
    """time per step = a + b N fitted on the sizes run in ``mode`` (forced, or the default
    when it ran in that mode), weighted by 1/time (least relative error, so the small sizes,
    where the fixed part shows, count as much as the large ones); None below two sizes."""
    pts = [(r["particles"], r.get(f"taichi_dem_{mode}") or
            (r["taichi_dem"] if r["mode"] == mode else None)) for r in rows]
    pts = [(k, v) for k, v in pts if v and (largest is None or k <= largest)]
    if len(pts) < 2:
        return None
    nn = np.array([k for k, _ in pts], float)
    t = nn / np.array([v for _, v in pts])
    slope, fixed = np.polyfit(nn, t, 1, w=1.0 / t)
    return {"fixed_s": float(fixed), "per_particle_s": float(slope), "sizes": [int(k) for k in nn]}


def report(rows, a):
    """The fits, the markdown table, cost_curve.json and cost_curve.png under ``a.out``."""
    a.out.mkdir(parents=True, exist_ok=True)
    n = np.array([r["particles"] for r in rows], float)
    fits = {}
    for mode in ("serial", "parallel"):
        f = fit_mode(rows, mode, 1.1 * a.both_modes_up_to if mode == "serial" else None)
        if f is not None:
            fits[mode] = f
            print(f"\ntaichi_dem {mode}: time per step = {f['fixed_s'] * 1e6:.1f} us + "
                  f"{f['per_particle_s'] * 1e9:.2f} ns x N (fixed share at 1k: "
                  f"{f['fixed_s'] / (f['fixed_s'] + f['per_particle_s'] * 1000):.0%}; fitted on "
                  f"{len(f['sizes'])} sizes)")
    first = "serial" if "serial" in fits else "parallel" if "parallel" in fits else None
    b, a0 = ((fits[first]["per_particle_s"], fits[first]["fixed_s"]) if first else (0.0, 0.0))
    ranks = [k for k in a.ranks if any(f"lammps_{k}" in r for r in rows)]
    print("| particles | steps | mode | taichi_dem M/s | serial | parallel | " + " | ".join(
        f"LAMMPS {k} rank(s) M/s | ratio of medians [paired]" for k in ranks) + " |")
    for r in rows:
        cells = [f"{r['particles']:,}", str(r["steps"]), r["mode"], f"{r['taichi_dem'] / 1e6:.2f}",
                 *(f"{r[k] / 1e6:.2f}" if k in r else "-"
                   for k in ("taichi_dem_serial", "taichi_dem_parallel"))]
        for k in ranks:
            if f"lammps_{k}" in r:
                ratio = f"{r['taichi_dem'] / r[f'lammps_{k}']:.2f}"
                if f"paired_{k}" in r:
                    ratio += f" [{r[f'paired_{k}']:.2f}]"
                cells += [f"{r[f'lammps_{k}'] / 1e6:.2f}", ratio]
        print("| " + " | ".join(cells) + " |")
    (a.out / "cost_curve.json").write_text(json.dumps({"rows": rows, "fixed_s": float(a0),
                                                       "per_particle_s": float(b), "fits": fits},
                                                      indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.plot(n, [r["taichi_dem"] / 1e6 for r in rows], "o-", label="taichi_dem (f32, 2 threads, default mode)")
    for k in ranks:
        if all(f"lammps_{k}" in r for r in rows):
            ax.plot(n, [r[f"lammps_{k}"] / 1e6 for r in rows], "s--", label=f"LAMMPS {k} rank(s)")
    for mode, style in (("serial", ":"), ("parallel", "-.")):
        if mode in fits:
            f = fits[mode]
            nn = np.array(f["sizes"], float)
            ax.plot(nn, nn / (f["fixed_s"] + f["per_particle_s"] * nn) / 1e6, style, color="grey",
                    label=f"{mode} fit: {f['fixed_s'] * 1e6:.0f} us + {f['per_particle_s'] * 1e9:.1f} ns N")
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
