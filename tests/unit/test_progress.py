"""Progress of a run (issue 33 item 6, in part): plain lines, not carriage returns, when stderr
is a log file; the particle-steps counted as done; an ETA from the recent simulated-time rate."""
import math
import sys

import pytest
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


def test_the_eta_learns_from_the_filling():
    """eta_seconds: the recent wall cost per particle and simulated second times the
    particle-seconds to come, the count growing at its recent rate up to the scene's slots.
    100 particles at 0.01 s per particle-second, 10 s to go: 10 s at a constant count; growing
    by 10 per s, 1,000 + 10 x 10^2 / 2 = 1,500 particle-seconds: 15 s (an ETA from the recent
    simulated-time rate said 10); full at 150 slots after 5 s: 500 + 125 + 750 = 1,375: 13.75 s.
    The growth stops after ``horizon`` simulated seconds (the run's own length so far)."""
    from taichi_dem.run.simulation import eta_seconds
    assert eta_seconds(10.0, 0.01, 100, 0.0, 1e9) == pytest.approx(10.0)
    assert eta_seconds(10.0, 0.01, 100, 10.0, 1e9) == pytest.approx(15.0)
    assert eta_seconds(10.0, 0.01, 100, 10.0, 150) == pytest.approx(13.75)
    assert eta_seconds(10.0, 0.01, 100, -5.0, 1e9) == pytest.approx(10.0)   # draining: today's
    assert eta_seconds(0.0, 0.01, 100, 10.0, 1e9) == 0.0
    # growing for 4 s more only: 1,000 + 10 x 16 / 2 + 140 x 6 - 100 x 6 = 1,320: 13.2 s
    assert eta_seconds(10.0, 0.01, 100, 10.0, 1e9, horizon=4.0) == pytest.approx(13.2)
