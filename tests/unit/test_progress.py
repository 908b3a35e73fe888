"""Progress of a run (issue 33 item 6, in part): plain lines, not carriage returns, when stderr
is a log file; the particle-steps counted as done; an ETA from the recent simulated-time rate."""
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from resume_scene import scene_text  # noqa: E402

import taichi_dem as td  # noqa: E402
from taichi_dem.run import simulation as simulation_module  # noqa: E402


def test_progress_into_a_log_is_plain_lines_with_a_finite_eta(capsys, monkeypatch):
    monkeypatch.setattr(simulation_module, "PLAIN_PROGRESS_S", 0.0)   # a line per block
    with td.Simulation.from_text(scene_text("f32"), h5="") as sim:
        start_count = sim.particle_count
        steps = int(round(0.02 / sim.dt))
        sim.run(0.02, progress=True)
        counted = sim.progress_particle_steps
        count = sim.particle_count
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = [x for x in err.splitlines() if "particle-steps/s" in x]
    assert len(lines) >= 2
    etas = [float(x.split("ETA")[1].split()[0]) for x in lines]
    assert all(math.isfinite(e) and e >= 0.0 for e in etas) and etas[-1] == 0.0
    # no factory here: every block counted count x steps
    assert start_count == count and counted == steps * count
