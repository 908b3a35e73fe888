"""Reference runs of the scaled paddle cooler for tests/regression/test_cooler.py.

    .venv/bin/python tests/regression/cooler_reference.py [seeds...]

Runs demos/paddle_cooler.toml to UNTIL seconds for each seed and prints the pinned quantities:
the shaft's mean axial torque over [T0, UNTIL] and the median residence time of the particles
that left by UNTIL. The test pins the seed-1 values with a tolerance from the scatter over
seeds printed here.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import taichi_dem as td

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "demos" / "paddle_cooler.toml"
T0, UNTIL = 6.0, 12.0


def run(seed: int, heat: dict | None = None) -> tuple[float, float, int]:
    """(mean axial torque N m over [T0, UNTIL], median residence s, particles that left);
    ``heat``, when given, receives the energy balance: the heat the ash lost and the heat into
    the shell (J) and the shell's mean heat flow over [T0, UNTIL] (W)."""
    text = SCENE.read_text().replace("seed = 1", f"seed = {seed}")
    sim = td.Simulation.from_text(text, base_dir=str(SCENE.parent), arch="cpu")
    try:
        sim.run(UNTIL)
        s = sim.series
        window = s["time"] >= T0
        torque = float(np.mean(s["bodies/shaft/axial_torque"][window]))
        rec = sim.residence_times("residence")
        residence = float(np.median(rec[:, 2] - rec[:, 1]))
        if heat is not None:
            heat["particle_heat_loss"] = float(s["thermal/particle_heat_loss"][-1])
            heat["wall_heat"] = float(s["thermal/wall_heat"][-1])
            heat["shell_heat_flow"] = float(np.mean(s["bodies/shell/heat_flow"][window]))
        return torque, residence, len(rec)
    finally:
        sim.close()


if __name__ == "__main__":
    seeds = [int(a) for a in sys.argv[1:]] or [1, 2, 3]
    heats = [{} for _ in seeds]
    rows = [run(s, h) for s, h in zip(seeds, heats)]
    for s, (t, r, n), h in zip(seeds, rows, heats):
        print(f"seed {s}: axial torque {t:.4g} N m, median residence {r:.4g} s ({n} particles), "
              f"shell heat flow {h['shell_heat_flow']:.5g} W")
    q = np.array([h["shell_heat_flow"] for h in heats])
    print(f"shell heat flow mean {q.mean():.5g} std {q.std(ddof=1) if len(q) > 1 else 0:.3g}")
    t = np.array([r[0] for r in rows])
    r = np.array([r[1] for r in rows])
    print(f"torque mean {t.mean():.4g} std {t.std(ddof=1) if len(t) > 1 else 0:.3g}; "
          f"residence mean {r.mean():.4g} std {r.std(ddof=1) if len(r) > 1 else 0:.3g}")
