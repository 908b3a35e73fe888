#!/usr/bin/env python3
"""Mobility on a bed at rest: the heated bed of tests/verification/heated_bed.py (1,662 steel
spheres of 6.4 mm, f64, settled 0.8 s, then an hour of heat from one wall) with and without
``[mobility] enabled = true``, and with the judgement forced by the lists' age switched off
(``--judge-within none``: the cells judged at rebuilds only, as before 2026-12-07).

    python bench/mobility_heated_bed.py --mobility off
    python bench/mobility_heated_bed.py --mobility on
    python bench/mobility_heated_bed.py --mobility on --judge-within none

Prints the wall time and the rises at 4000 s against the measured ones (x the measured).
Run the variants one at a time, alone on the machine.
"""
import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "verification"))

import heated_bed as H  # noqa: E402

import taichi_dem.effects.mobility.effect as M  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mobility", choices=("on", "off"), default="on")
    ap.add_argument("--judge-within", default=str(M.JUDGE_WITHIN_STEPS),
                    help="steps between forced judgements, or 'none'")
    ap.add_argument("--time-scale", type=float, default=1000.0)
    a = ap.parse_args()
    M.Mobility.rebuild_within_steps = None if a.judge_within == "none" else int(a.judge_within)
    scene_text = H.scene_text
    extra = "\n[mobility]\nenabled = true\n" if a.mobility == "on" else ""
    H.scene_text = lambda *args, **kw: scene_text(*args, **kw) + extra
    t0 = time.perf_counter()
    r = H.heated_bed("schlunder", time_scale=a.time_scale)
    rows = {(d, t): dem / exp for d, t, dem, exp, _, _ in H.comparison(r)}
    rises = " / ".join(f"{rows[(d, 4000.0)]:.3f}" for d in H.DEPTHS)
    print(f"mobility {a.mobility}, judged within {a.judge_within} steps, time scale "
          f"{a.time_scale:g}: {time.perf_counter() - t0:.1f} s wall; rises at 4000 s {rises} x "
          f"the measured; {r['lost']} lost")


if __name__ == "__main__":
    main()
