"""The run-time values' arrays (engine/values.py) hold a scene with many sensors: each
mass-flow plane takes 13 real slots and each outlet 6, and the dryer demo alone takes 75 (its
gas, drying, drag, radiation region, outlet and plane). With 96 slots, four more planes made
the build fail with "more runtime values than the 96 slots"."""
from pathlib import Path

import taichi_dem as td

ROOT = Path(__file__).resolve().parents[2]


def test_the_dryer_demo_with_a_dozen_more_mass_flow_planes_builds_and_steps():
    scene = ROOT / "demos" / "dryer_drum.toml"
    planes = "".join(f'\n[[sensors]]\nkind = "mass_flow"\nname = "plane_{k}"\n'
                     f'plane = {{ point = [{0.05 + 0.09 * k:.2f}, 0, 0], normal = [1, 0, 0] }}\n'
                     for k in range(12))
    text = scene.read_text().replace("[thermal]\n", planes + "\n[thermal]\n", 1)
    assert text.count('kind = "mass_flow"') == 13
    with td.Simulation.from_text(text, source=str(scene), h5="") as sim:
        sim.step(2)
        used = sum(width for _, width in sim.engine.values._real_slots.values())
        assert used > 96 + 50       # more than the former arrays held, by a margin
        assert sim.time > 0.0
