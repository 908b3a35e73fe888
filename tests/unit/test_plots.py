"""`taichi-dem plot RESULTS.h5`: the PNGs of a results file, and that what they plot is the
file's series (the data read back from the drawn matplotlib artists).

One tiny process run (tests/unit/plot_drum.toml: hot beads fed into a small cooled rotating
drum with plug-flow gas, 0.8 s simulated; about 25 s, most of it compiling) feeds every test."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from taichi_dem.app import plots

from conftest import ROOT

SCENE = Path(__file__).with_name("plot_drum.toml")
EXPECTED = {"particles", "body_drum", "residence_residence", "mass_flows", "temperatures",
            "gas_profile", "heat_flows", "energy_balance"}


def _cli(*args, cwd=ROOT, timeout=300):
    return subprocess.run([sys.executable, "-m", "taichi_dem", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=timeout)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """`taichi-dem run plot_drum.toml --h5 ... --plots`: the results file, the plots the run
    wrote beside it, and the run's stdout."""
    d = tmp_path_factory.mktemp("plot")
    h5 = d / "drum.h5"
    r = _cli("run", str(SCENE), "--h5", str(h5), "--plots", "--quiet")
    assert r.returncode == 0, r.stderr[-2000:]
    return h5, r.stdout


@pytest.fixture(scope="module")
def made(run, tmp_path_factory):
    h5, _ = run
    out = tmp_path_factory.mktemp("figs")
    return {f.name: f for f in plots.plot_results(str(h5), str(out))}, out


def _pixels(path):
    import matplotlib.image as mpimg
    return mpimg.imread(str(path))


def test_every_expected_png_is_written_and_not_blank(made):
    figs, out = made
    assert set(figs) == EXPECTED
    for name in EXPECTED:
        png = out / f"{name}.png"
        assert png.is_file() and figs[name].path == str(png)
        img = _pixels(png)[..., :3]
        assert img.shape[0] > 300 and img.shape[1] > 600
        # a blank canvas is all white: a drawn figure has many non-white pixels of several shades
        ink = np.any(img < 0.9, axis=2)
        assert ink.mean() > 0.01, name
        assert np.std(img) > 0.05, name


def test_torque_and_power_are_the_series(run, made):
    figs, _ = made
    h5, _ = run
    fig = figs["body_drum"]
    with h5py.File(h5) as f:
        t = f["series/time"][()]
        tq = f["series/bodies/drum/axial_torque"][()]
        pw = f["series/bodies/drum/power"][()]
        w = f["series/bodies/drum/angular_speed"][()]
    x, y = fig.drawn[0]["axial torque"]
    assert np.array_equal(x, t) and np.array_equal(y, tq)
    x, y = fig.drawn[1]["power"]
    assert np.array_equal(x, t) and np.array_equal(y, pw)
    assert np.any(tq != 0) and np.any(pw != 0)          # the drum carried the bed
    # the dashed mean is the summaries' one: the last quarter of the samples
    q = len(t) - max(1, len(t) // 4)
    _, m = fig.drawn[0]["mean, last quarter"]
    assert np.allclose(m, np.mean(tq[q:]))
    _, rpm = fig.drawn[2]["speed"]
    assert np.allclose(rpm, 30.0) and np.allclose(rpm, w * 60 / (2 * np.pi))
    assert "N m" in fig.panels[0].ylabel and "W" in fig.panels[1].ylabel


def test_residence_histogram_counts_every_record(run, made):
    figs, _ = made
    h5, _ = run
    with h5py.File(h5) as f:
        rt = f["residence/residence/t_out"][()] - f["residence/residence/t_in"][()]
    assert len(rt) > 10
    edges, counts = figs["residence_residence"].drawn[0]["hist"]
    assert counts.sum() == len(rt)
    assert edges[0] == pytest.approx(rt.min()) and edges[-1] == pytest.approx(rt.max())
    assert np.array_equal(counts, np.histogram(rt, bins=edges)[0])
    label = figs["residence_residence"].panels[0].title
    assert f"{len(rt)} particles" in label and f"median {np.median(rt):.3g} s" in label


def test_mass_flows_temperatures_gas_and_heat(run, made):
    figs, _ = made
    h5, _ = run
    with h5py.File(h5) as f:
        s = {k: f["series/" + k][()] for k in (
            "time", "factories/feed/mass", "outlets/discharge/mass_flow",
            "sensors/mid_plane/mass_flow", "outlets/discharge/mean_temperature",
            "particles/mean_temperature", "gas/temperature", "bodies/drum/heat_flow",
            "bodies/drum/heat_transfer_coefficient", "thermal/particle_heat_loss",
            "thermal/wall_heat", "thermal/gas_heat", "sample_interval")}
    t = s["time"]
    rates = figs["mass_flows"].drawn[0]
    x, y = rates["factory 'feed' (fed)"]
    assert np.array_equal(x, t[1:])
    # the fed mass over what each sample covers: the interval since the sample before, and
    # for a short closing sample that interval and the one before it (sensors/pooling.py)
    fed = s["factories/feed/mass"]
    start = t[1:] - s["sample_interval"][1:]
    assert np.allclose(y, (fed[1:] - np.interp(start, t, fed)) / (t[1:] - start))
    assert np.allclose(y[:-1], np.diff(fed)[:-1] / np.diff(t)[:-1])
    # the factory's schedule: 0.15 kg/s to 0.4 s, 0.3 kg/s after (whole particles, so on average)
    late = x > 0.45
    assert np.mean(y[late]) == pytest.approx(0.3, rel=0.15)
    assert np.array_equal(rates["outlet 'discharge'"][1], s["outlets/discharge/mass_flow"])
    assert np.array_equal(rates["sensor 'mid_plane' (plane)"][1], s["sensors/mid_plane/mass_flow"])
    temps = figs["temperatures"].drawn[0]
    # NaN while the bed is empty (the factory has not fed yet), not 0 K
    assert np.isnan(s["particles/mean_temperature"][0])
    assert np.array_equal(temps["particles, mean"][1], s["particles/mean_temperature"],
                          equal_nan=True)
    got = temps["outlet 'discharge' (removed in the interval)"][1]
    assert np.array_equal(np.isnan(got), np.isnan(s["outlets/discharge/mean_temperature"]))
    # gas profile at the end: the cells' exit temperatures, at the cells' upstream faces (the
    # gas flows against the axis, 4 cells over 0.12 m), and the inlet at 600 C at x = 0.12 m
    last = figs["gas_profile"].drawn[0]
    x, y = last[max(last, key=lambda k: float(k.split()[2]))]
    assert np.allclose(x, [0.0, 0.03, 0.06, 0.09, 0.12])
    assert np.allclose(y[:4], s["gas/temperature"][-1]) and y[4] == pytest.approx(873.15)
    heat = figs["heat_flows"].drawn
    assert np.array_equal(heat[0]["body 'drum'"][1], s["bodies/drum/heat_flow"])
    h = s["bodies/drum/heat_transfer_coefficient"]
    assert np.array_equal(heat[1]["'drum'"][1], h[np.isfinite(h)]) and np.any(np.isfinite(h))
    bal = figs["energy_balance"].drawn[0]
    assert np.array_equal(bal["heat out of the particles"][1], s["thermal/particle_heat_loss"])
    assert np.allclose(bal["walls - gas (booked)"][1], s["thermal/wall_heat"] - s["thermal/gas_heat"])


def test_titles_and_units(made):
    figs, _ = made
    for fig in figs.values():
        assert fig.title
        for p in fig.panels:
            assert p.xlabel and p.ylabel and p.title
            assert "," in p.ylabel or p.ylabel == "particles"      # "quantity, unit"


def test_run_with_plots_says_where_they_are(run):
    h5, stdout = run
    line = next(ln for ln in stdout.splitlines() if ln.startswith("plots:"))
    folder = Path(plots.default_dir(str(h5)))
    assert str(folder) in line
    assert {p.stem for p in folder.glob("*.png")} == EXPECTED


def test_plot_command(run, tmp_path):
    h5, _ = run
    r = _cli("plot", str(h5), "--out", str(tmp_path / "p"), timeout=120)
    assert r.returncode == 0, r.stderr
    assert f"8 PNGs in {tmp_path / 'p'}" in r.stdout
    assert {p.stem for p in (tmp_path / "p").glob("*.png")} == EXPECTED


def test_bad_files_exit_2_without_traceback(tmp_path):
    missing = tmp_path / "nothing.h5"
    text = tmp_path / "scene.h5"
    text.write_text("[simulation]\n")
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = np.zeros(3)
    for path, reason in ((missing, "no such file"), (text, "cannot open as an HDF5 file"),
                         (foreign, "not a taichi_dem results file")):
        r = _cli("plot", str(path), timeout=120)
        assert r.returncode == 2, (path, r.stderr)
        assert str(path) in r.stderr and reason in r.stderr
        assert "Traceback" not in r.stderr and r.stdout == ""
    with pytest.raises(plots.PlotError, match="no such file"):
        plots.plot_results(str(missing))


def test_demo_writes_plots_beside_its_results(tmp_path):
    """`taichi-dem demo pile` (cut to 0.15 s) writes its plots beside its results file and
    prints the folder; the floor's load is the series' force along the floor's normal."""
    r = _cli("demo", "pile", "--until", "0.15", "--out", str(tmp_path), "--quiet")
    assert r.returncode == 0, r.stderr[-2000:]
    folder = tmp_path / "pile_plots"
    assert f"plots: {folder}/" in r.stdout
    assert {"particles", "walls"} <= {p.stem for p in folder.glob("*.png")}
    figs = {f.name: f for f in plots.plot_results(str(tmp_path / "pile.h5"), str(tmp_path / "again"))}
    with h5py.File(tmp_path / "pile.h5") as f:
        fz = f["series/walls/floor/force"][()][:, 2]
    assert np.allclose(figs["walls"].drawn[0]["wall 'floor'"][1], -fz) and np.max(-fz) > 0
