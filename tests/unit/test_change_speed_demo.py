"""demos/change_speed.py: set_speed in the middle of a run, torque read from sim.series."""
import importlib.util
import math
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def test_change_speed_demo_runs_and_switches_speed(capsys):
    spec = importlib.util.spec_from_file_location("change_speed", ROOT / "demos/change_speed.py")
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    out = demo.run(until=0.6, at=0.3, rpm=40.0)
    printed = capsys.readouterr().out
    assert "20.0 rpm" in printed and "40.0 rpm" in printed and "axial torque" in printed
    t, w = out["time"], out["speed"]
    rad = 2 * math.pi / 60
    # the schedule switches at the first sample after set_speed, not before
    assert np.allclose(w[t <= 0.3], 20 * rad) and np.allclose(w[t > 0.3 + 0.02], 40 * rad)
    # the settled bed resists the turning, and its torque about the axis cannot exceed its
    # weight times the drum radius (M g R = 400 beads x 0.67 g x 9.81 m/s^2 x 0.1 m = 0.26 N m)
    weight_arm = 400 * 4 / 3 * math.pi * 0.004 ** 3 * 2500 * 9.81 * 0.1
    for torque in (out["torque_before"], out["torque_after"]):
        assert -weight_arm < torque < 0.0
