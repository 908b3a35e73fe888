#!/usr/bin/env python3
"""Change a drum's speed while it runs and compare the axial torque before and after.

    python demos/change_speed.py [--until 2.0] [--at 1.0] [--rpm 40]

Runs demos/small_drum.toml (400 beads, 4 lifting flights, 20 rpm) to ``--at`` seconds, calls
``sim.set_speed("drum", ...)`` and runs on to ``--until``; prints the mean axial torque on the
drum (N m, from ``sim.series``) over the second half of each part. The torque is the
particles' load about the axis: negative while it resists the turning.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
import taichi_dem as td  # noqa: E402

SCENE = ROOT / "demos" / "small_drum.toml"


def run(until: float = 2.0, at: float = 1.0, rpm: float = 40.0, **kwargs) -> dict:
    """Run, change the speed at ``at`` s, and return speeds (rad/s) and mean torques (N m)
    before and after."""
    sim = td.Simulation.from_toml(str(SCENE), h5="", **kwargs)
    sim.run(at)
    sim.set_speed("drum", f"{rpm} rpm")
    sim.run(until)
    s = sim.series
    sim.close()
    t = s["time"]
    torque = s["bodies/drum/axial_torque"]
    speed = s["bodies/drum/angular_speed"]
    before = (t > 0.5 * at) & (t <= at)
    after = t > at + 0.5 * (until - at)
    out = {"time": t, "speed": speed, "torque": torque,
           "speed_before": float(speed[before][-1]), "speed_after": float(speed[after][-1]),
           "torque_before": float(np.mean(torque[before])),
           "torque_after": float(np.mean(torque[after]))}
    rpm_factor = 60.0 / (2.0 * np.pi)
    print(f"before t = {at:g} s: {out['speed_before'] * rpm_factor:.1f} rpm, mean axial torque "
          f"{out['torque_before']:.4g} N m")
    print(f"after:            {out['speed_after'] * rpm_factor:.1f} rpm, mean axial torque "
          f"{out['torque_after']:.4g} N m")
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--until", type=float, default=2.0, help="end time, s")
    p.add_argument("--at", type=float, default=1.0, help="when to change the speed, s")
    p.add_argument("--rpm", type=float, default=40.0, help="the new speed, rpm")
    a = p.parse_args(argv)
    run(a.until, a.at, a.rpm)
    return 0


if __name__ == "__main__":
    sys.exit(main())
