#!/usr/bin/env python3
"""What the Verlet skin gives on the chute, to taichi_dem and to LAMMPS alike: the 32k chute
(bench/chute.py's scene and LAMMPS input) at several skins, in rounds - each round runs every
skin once in taichi_dem and in LAMMPS on ``--ranks``, taichi_dem first in even rounds - with
the rebuilds each code did. A larger skin means fewer rebuilds and longer neighbour lists; the
physics is the same (a pair within reach is listed whatever the skin), so the skin is a speed
knob of both codes. The benchmark's skin is 0.1 (bench/chute.py).

    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 .venv/bin/python \\
        bench/chute_skin.py --skins 0.05 0.1 0.2 0.3 --rounds 3 --ranks 2
"""
import argparse
import statistics
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from chute import run_taichi_dem  # noqa: E402
from chute_scene import write_chute_scene  # noqa: E402
from lammps_chute import LammpsMissing, run_lammps  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--skins", type=float, nargs="+", default=[0.05, 0.1, 0.2, 0.3])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--warmup", type=int, default=50)
    p.add_argument("--ranks", type=int, nargs="+", default=[2])
    a = p.parse_args(argv)
    ours = {s: [] for s in a.skins}
    theirs = {(s, r): [] for s in a.skins for r in a.ranks}
    lammps = True
    with tempfile.TemporaryDirectory() as tmp:
        scenes = {s: write_chute_scene(Path(tmp) / f"skin{s}", skin=s) for s in a.skins}

        def taichi_round(k):
            for s in a.skins:
                res = run_taichi_dem(str(scenes[s]), a.steps, a.warmup)
                ours[s].append(res)
                print(f"round {k + 1} skin {s:g}: taichi_dem {res['particle_steps_per_s'] / 1e6:6.2f} "
                      f"M/s, {res['rebuilds']} rebuilds, {res['neighbours_per_particle']:.2f} "
                      f"neighbours/particle", flush=True)

        def lammps_round(k):
            nonlocal lammps
            for s in a.skins:
                for r in a.ranks:
                    if not lammps:
                        return
                    try:
                        res = run_lammps(a.steps, r, skin=s)
                    except LammpsMissing as err:
                        print(f"LAMMPS skipped: {err}")
                        lammps = False
                        return
                    theirs[(s, r)].append(res)
                    print(f"round {k + 1} skin {s:g}: LAMMPS {r} rank(s) "
                          f"{res['particle_steps_per_s'] / 1e6:6.2f} M/s, {res['rebuilds']} "
                          f"rebuilds", flush=True)

        for k in range(a.rounds):
            for stage in ((taichi_round, lammps_round) if k % 2 == 0
                          else (lammps_round, taichi_round)):
                stage(k)

    def med(runs, key="particle_steps_per_s"):
        return statistics.median(x[key] for x in runs)

    print(f"\nmedians of {a.rounds} rounds (million particle-steps per second; rebuilds in "
          f"{a.steps} steps); [ratio paired within a round]")
    header = "| skin | taichi_dem M/s | rebuilds |"
    for r in a.ranks:
        header += f" LAMMPS {r} rank(s) M/s | rebuilds | taichi_dem / LAMMPS {r} |"
    print(header)
    print("|" + "---|" * (3 + 3 * len(a.ranks)))
    for s in a.skins:
        line = f"| {s:g} | {med(ours[s]) / 1e6:.2f} | {med(ours[s], 'rebuilds'):.0f} |"
        for r in a.ranks:
            runs = theirs[(s, r)]
            if not runs:
                line += " - | - | - |"
                continue
            paired = statistics.median(x["particle_steps_per_s"] / y["particle_steps_per_s"]
                                       for x, y in zip(ours[s], runs))
            builds = [x["rebuilds"] for x in runs if x["rebuilds"] is not None]
            line += (f" {med(runs) / 1e6:.2f} | {statistics.median(builds) if builds else '-'} |"
                     f" {med(ours[s]) / med(runs):.2f} [{paired:.2f}] |")
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
