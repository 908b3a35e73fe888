"""``taichi-dem analyse`` (issue 48 item 1): profiles in bins, selections, tracks, residence
records and a video, each checked on a synthetic results file whose answer is known exactly.

Ten particles on the x axis at x_i = 0.05 + 0.1 i (m), mass 1 + i (kg), temperature 300 + i
(K); the even ones are "ash" moving at +2 m/s, the odd ones "steel" at -1 m/s. Two bins of
0.2 m hold particles 2b and 2b + 1: mass 3 + 4b, mass-weighted velocity 2b / (3 + 4b). Frames at
0 and 1 s are identical; the frame at 2 s has every particle moved into the last bin, so a
window that wrongly takes it in changes every bin.
"""
import csv
import io

import h5py
import numpy as np
import pytest

from taichi_dem.app import analyse
from taichi_dem.app.cli import main

N = 10


def _frame(f, k, t, x):
    g = f.create_group(f"frames/{k}")
    g.attrs["time"] = t
    i = np.arange(N)
    g.create_dataset("id", data=i)
    g.create_dataset("position", data=x)
    g.create_dataset("velocity", data=np.column_stack([np.where(i % 2 == 0, 2.0, -1.0),
                                                       np.zeros(N), np.zeros(N)]))
    g.create_dataset("mass", data=1.0 + i)
    g.create_dataset("radius", data=np.full(N, 0.02))
    g.create_dataset("temperature", data=300.0 + i)
    g.create_dataset("material", data=(i % 2).astype(np.int32))


@pytest.fixture
def results(tmp_path):
    path = tmp_path / "line.h5"
    x = np.column_stack([0.05 + 0.1 * np.arange(N), np.zeros(N), np.zeros(N)])
    with h5py.File(path, "w") as f:
        f.attrs["materials"] = ["ash", "steel"]
        _frame(f, 0, 0.0, x)
        _frame(f, 1, 1.0, x)
        _frame(f, 2, 2.0, np.column_stack([np.full(N, 0.95), np.zeros(N), np.zeros(N)]))
        r = f.create_group("residence/outlet")
        r.create_dataset("id", data=[4, 9])
        r.create_dataset("t_in", data=[0.5, 1.0])
        r.create_dataset("t_out", data=[2.0, 4.5])
    return path


def test_axial_profile_over_a_window(results):
    p = analyse.profile(results, bins=5, axis="x", span=(0.0, 1.0), t1=1.0)
    b = np.arange(5)
    assert p["frames"] == 2
    np.testing.assert_allclose(p["centre"], 0.1 + 0.2 * b)
    np.testing.assert_allclose(p["mass"], 3 + 4 * b)
    np.testing.assert_allclose(p["mass_per_length"], (3 + 4 * b) / 0.2)
    np.testing.assert_allclose(p["count"], 2)
    np.testing.assert_allclose(p["axial_velocity"], 2 * b / (3 + 4 * b))
    heat = (1 + 2 * b) * (300 + 2 * b) + (2 + 2 * b) * (301 + 2 * b)
    np.testing.assert_allclose(p["temperature"], heat / (3 + 4 * b))
    # the whole run, the moved frame included: a third of the time all mass is in the last bin
    whole = analyse.profile(results, bins=5, axis="x", span=(0.0, 1.0))
    np.testing.assert_allclose(whole["mass"][-1], (2 * 19 + 55) / 3)


def test_selections_by_material_and_region(results):
    ash = analyse.profile(results, bins=5, span=(0.0, 1.0), t1=1.0, material="ash")
    np.testing.assert_allclose(ash["mass"], 1 + 2 * np.arange(5))
    np.testing.assert_allclose(ash["axial_velocity"], 2.0)
    boxed = analyse.profile(results, bins=5, span=(0.0, 1.0), t1=1.0,
                            region=(0, -1, -1, 0.5, 1, 1))
    np.testing.assert_allclose(boxed["count"], [2, 2, 1, 0, 0])
    assert np.isnan(boxed["axial_velocity"][-1])
    with pytest.raises(analyse.SceneError, match="no material 'clay'"):
        analyse.profile(results, bins=5, material="clay")


def test_radial_rings(tmp_path):
    path = tmp_path / "rings.h5"
    with h5py.File(path, "w") as f:
        g = f.create_group("frames/0")
        g.attrs["time"] = 0.0
        r = np.array([0.05, 0.15, 0.25, 0.35])
        g.create_dataset("position", data=np.column_stack([np.arange(4.0), r * 0.6, r * 0.8]))
        g.create_dataset("mass", data=[1.0, 2.0, 3.0, 4.0])
    p = analyse.profile(path, bins=4, axis="x", radial=0.4)
    np.testing.assert_allclose(p["mass"], [1, 2, 3, 4])
    assert "mass_per_length" not in p


def test_tracks_and_the_profile_csv_from_the_command_line(results, tmp_path):
    rows = analyse.tracks(results, [7, 3])
    assert [(r[0], r[2]) for r in rows] == [(0, 3), (0, 7), (1, 3), (1, 7), (2, 3), (2, 7)]
    assert rows[1][3:10] == [0.05 + 0.1 * 7, 0.0, 0.0, -1.0, 0.0, 0.0, 307.0]
    assert rows[-1][3] == 0.95
    out = tmp_path / "p.csv"
    assert main(["analyse", str(results), "profile", "--bins", "5", "--range", "0", "1",
                 "--to", "1", "--out", str(out), "--plot", str(tmp_path / "p.png")]) == 0
    table = list(csv.reader(out.read_text().splitlines()))
    assert table[0][:3] == ["centre [m]", "mass [kg]", "mass_per_length [kg/m]"]
    assert float(table[3][1]) == 11.0 and (tmp_path / "p.png").stat().st_size > 0


def test_residence_records_as_csv(results, tmp_path, capsys):
    assert main(["analyse", str(results), "residence", "--out", "-"]) == 0
    rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert rows == [["id", "t_in [s]", "t_out [s]", "residence [s]"],
                    ["4", "0.5", "2.0", "1.5"], ["9", "1.0", "4.5", "3.5"]]


def test_a_gif_of_the_frames(results, tmp_path):
    from PIL import Image
    target = tmp_path / "line.gif"
    assert analyse.video(results, target, view="xz") == 3
    with Image.open(target) as gif:
        assert gif.n_frames == 3


def test_bad_requests_name_the_key(results, capsys):
    assert main(["analyse", str(results), "track"]) == 2
    assert "--ids" in capsys.readouterr().err
    assert main(["analyse", str(results), "video", "--view", "xx"]) == 2
    assert "--view" in capsys.readouterr().err
    assert main(["analyse", str(results), "profile", "--from", "5"]) == 2
    assert "no frame in" in capsys.readouterr().err
