"""The sweep's key outputs read back from an HDF5 results file (taichi_dem/app/outputs.py)
are the numbers the demo summary prints (app/summaries.process_summary) for the same run:
residence time, mass flows of a sensor and an outlet, outlet temperature. The scene is
tests/verification/test_process.py's free fall (spheres inserted too sparsely to touch), with
heat on so the outlet temperature is recorded."""
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.app.outputs import key_outputs, unit
from taichi_dem.app.summaries import process_summary

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "verification"))
from test_process import scene  # noqa: E402


def test_outputs_from_hdf5_match_the_summary(tmp_path, capsys):
    h5 = tmp_path / "r.h5"
    text = scene(thermal=True, rate='"0.2 kg/s"').replace("[thermal]", "[thermal]\nconduction = false")
    text = text.replace("temperature = 450.0", "temperature = 350.0")
    sim = td.Simulation.from_text(text, arch="cpu", h5=str(h5))
    sim.run(0.8)
    summary = process_summary(sim)
    sim.close()
    capsys.readouterr()
    out = key_outputs(str(h5))
    assert out["res/residence_mean"] == pytest.approx(summary["res/mean"], rel=1e-12)
    assert out["res/residence_median"] == pytest.approx(summary["res/median"], rel=1e-12)
    for k in ("mid/mass_flow", "drain/mass_flow", "drain/temperature"):
        assert out[k] == pytest.approx(summary[k], rel=1e-12), k
    # what the numbers must be: the fed 0.2 kg/s crosses the plane and leaves by the drain
    # once the stream is established; nothing exchanges heat, so the ash leaves at 350 K
    assert out["mid/mass_flow"] == pytest.approx(0.2, rel=0.25)
    assert out["drain/mass_flow"] == pytest.approx(0.2, rel=0.25)
    assert out["drain/temperature"] == pytest.approx(350.0, abs=1e-9)
    assert out["particles/mean_temperature"] == pytest.approx(350.0, abs=1e-9)
    assert 0.0 < out["particles/kinetic_energy"] and math.isfinite(out["particles/kinetic_energy"])
    assert unit("drain/temperature") == "K" and unit("mid/mass_flow") == "kg/s"
    assert unit("res/residence_mean") == "s"


def test_discharge_rate_is_the_slope_while_15_to_60_percent_left(tmp_path):
    # a hopper's discharge read from its lost count: 1000 particles leaving at 400/s from
    # t = 0.5 s; the slope of the 15 - 60 % window is the rate, and a run that has not let 60 %
    # out has none
    import h5py
    from taichi_dem.app.outputs import key_outputs
    t = np.linspace(0.0, 3.0, 61)
    lost = np.clip(400.0 * (t - 0.5), 0.0, 1000.0)
    path = tmp_path / "r.h5"
    with h5py.File(path, "w") as f:
        s = f.create_group("series")
        s["time"] = t
        s["particles/count"] = 1000.0 - lost
        s["particles/lost"] = lost
        s["particles/kinetic_energy"] = np.ones_like(t)
    assert key_outputs(str(path))["particles/discharge_rate"] == pytest.approx(400.0, rel=1e-9)
    with h5py.File(path, "a") as f:
        del f["series/particles/lost"]
        f["series/particles/lost"] = np.minimum(lost, 500.0)
    assert "particles/discharge_rate" not in key_outputs(str(path))


def test_a_periodic_slice_reports_its_axial_flow_and_holdup(tmp_path):
    # two particles in a slice periodic along x, 0.2 m long: 1 kg at 0.1 m/s and 2 kg at
    # 0.3 m/s along x carry (0.1 + 0.6) / 0.2 = 3.5 kg/s through any section, 15 kg/m; the
    # window (the last quarter of 4 frames) is the last frame, earlier ones moving slower
    import h5py
    from taichi_dem.app.outputs import key_outputs, unit
    path = tmp_path / "slice.h5"
    with h5py.File(path, "w") as f:
        f.attrs["scene"] = ('[domain]\nmin = [-0.1, -1, -1]\nmax = [0.1, 1, 1]\n'
                            'periodic = ["x"]\n')
        s = f.create_group("series")
        s["time"] = np.arange(4.0)
        s["particles/kinetic_energy"] = np.ones(4)
        for k in range(4):
            g = f.create_group(f"frames/{k}")
            g["mass"] = np.array([1.0, 2.0])
            g["velocity"] = np.array([[0.1, 5.0, 0.0], [0.3, -5.0, 0.0]]) * (k + 1) / 4
    out = key_outputs(str(path))
    assert out["periodic_x/mass_flow"] == pytest.approx(3.5, rel=1e-12)
    assert out["periodic_x/holdup"] == pytest.approx(15.0, rel=1e-12)
    assert unit("periodic_x/mass_flow") == "kg/s" and unit("periodic_x/holdup") == "kg/m"
    assert "periodic_y/mass_flow" not in out
