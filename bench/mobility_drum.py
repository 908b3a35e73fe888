"""[mobility] in a rotating drum (issue 12): the rolling bed of tests/regression/test_drum_torque.py
(1100 beads of 8 mm, R = 0.1 m, 10 rpm) with mobility off, on in mode "body_frame" (velocities
relative to the drum's rigid rotation; inactive particles carried with it) and on in mode
"at_rest" (a bed that turns with its drum is moving, so it stays active: the control).

Prints, per variant: mean axial torque over the window (N m), dynamic angle of repose (deg),
inactive fraction at the end, stepping wall time of the window (s).

    .venv/bin/python bench/mobility_drum.py [repeats] [variant,variant,...]
"""
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "regression"))

import taichi_dem  # noqa: E402
from taichi_dem.app import analysis  # noqa: E402
from test_drum_torque import R_P, SETTLE, WINDOW, drum_scene  # noqa: E402

VARIANTS = {
    "off": "",
    "body_frame": '\n[mobility]\nmode = "body_frame"\nbody = "drum"\n',
    "at_rest": "\n[mobility]\n",
    # the first default threshold (5e-3 g d) and a looser solid fraction: the drum is only
    # 12 d across, so its cells of 3 d are cut by the shell
    "body_frame_loose": '\n[mobility]\nmode = "body_frame"\nbody = "drum"\n'
                        'granular_temperature_threshold = 3.9e-4\nsolid_fraction_threshold = 0.25\n',
}


def run(variant: str) -> dict:
    with taichi_dem.Simulation.from_text(drum_scene(1) + VARIANTS[variant]) as sim:
        sim.run(SETTLE)
        first = len(sim.series["time"])
        thetas = []
        wall = 0.0
        while sim.time < SETTLE + WINDOW - 1e-9:
            t0 = time.perf_counter()
            sim.step(sim.output_every)
            wall += time.perf_counter() - t0
            p = sim.particles()
            thetas.append(analysis.bed_surface(p["position"][:, 1], p["position"][:, 2],
                                               p["radius"], 2 * R_P)[0])
        torque = float(np.mean(sim.series["bodies/drum/axial_torque"][first:]))
        inactive = (sim.engine.model.effect("mobility").statistics()["inactive_particles"] / sim.particle_count
                    if sim.engine.model.effect("mobility") is not None else 0.0)
    return dict(torque=torque, theta=math.degrees(float(np.mean(thetas))), inactive=inactive,
                wall=wall)


if __name__ == "__main__":
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 1
    chosen = sys.argv[2].split(",") if len(sys.argv) > 2 else list(VARIANTS)
    results = {v: [] for v in chosen}
    for _ in range(repeats):
        for v in chosen:                         # interleaved
            results[v].append(run(v))
            r = results[v][-1]
            print(f"{v:10s} torque {r['torque']:.4f} N m  theta {r['theta']:.1f} deg  inactive "
                  f"{r['inactive']:.0%}  window wall {r['wall']:.1f} s", flush=True)
    print("medians:")
    for v, rs in results.items():
        print(f"{v:10s} torque {np.median([r['torque'] for r in rs]):.4f} N m  window wall "
              f"{np.median([r['wall'] for r in rs]):.1f} s")
