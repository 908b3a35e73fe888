"""bench/gpu_cooler.py, the 6 m seed cooler the GPU check steps (issue 45 item 5), at a reduced
size on the CPU: the machine is built with the count the hold-up asks for, steps, reports a
rate, and reads the one-row map's figures at that hold-up (at a mapped hold-up, exactly the
map's)."""
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import gpu_cooler  # noqa: E402


def test_the_map_is_read_at_the_holdup():
    rows = json.loads((gpu_cooler.MAPS[0] / "map.json").read_text())["rows"]
    at_60 = [r for r in rows if r["holdup_kg_per_m"] == 60.0 and abs(r["incline_deg"] - 5) < 1e-6][0]
    got = gpu_cooler.mapped(60.0)
    assert got["shaft/torque_per_metre"][0] == at_60["shaft/torque_per_metre"]
    # between 90 kg/m (the original map) and 200 kg/m (the full-shell points): interpolated
    mid = gpu_cooler.mapped(145.0)["shaft/torque_per_metre"][0]
    assert min(at_60["shaft/torque_per_metre"], -650.0) < mid < -300.0
    assert math.isnan(gpu_cooler.mapped(500.0)["axial_mass_flow"][0])


def test_a_small_machine_steps_on_the_cpu():
    r = gpu_cooler.run(rows=1, holdup=30.0, seconds=0.3)
    assert r["length_m"] == 0.25
    # the count the hold-up asks for: 30 kg/m x 0.25 m of 1.54 g spheres
    assert abs(r["particles"] - 30.0 * 0.25 / (870.0 * 4 / 3 * math.pi * 0.0075 ** 3)) < 2
    assert r["particle_steps_per_s"] > 0.0 and math.isfinite(r["particle_steps_per_s"])
