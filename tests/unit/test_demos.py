"""The demo registry: every demo has a scene that loads, a summary, and a line in the listing.

(Running the demos themselves is left to tests/regression, which runs the angle-of-repose scene,
and to `taichi-dem demo NAME`.)"""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from taichi_dem.app import demos
from taichi_dem.scene.loader import load_scene
from taichi_dem.setup.placement import place_fills

from conftest import ROOT


@pytest.mark.parametrize("name", list(demos.DEMOS))
def test_demo_scene_loads_and_places(name):
    demo = demos.get(name)
    assert demo.path.exists()
    scene = load_scene(str(demo.path))
    placed = place_fills(scene, np.random.default_rng(scene.simulation.seed))
    assert len(placed.radius) > 0 or scene.factories     # process demos start empty
    assert callable(demo.summary) and demo.description


def test_demo_listing_names_every_demo():
    r = subprocess.run([sys.executable, "-m", "taichi_dem", "demo"], capture_output=True, text=True,
                       cwd=ROOT, timeout=120)
    assert r.returncode == 0
    listing = r.stdout.splitlines()
    split = next(k for k, ln in enumerate(listing) if ln.startswith("tutorial scenes"))
    lines = [ln.split()[0] for ln in listing[1:split] if ln.strip()]
    assert lines == list(demos.DEMOS)
    # and the tutorials' scenes, which come with the package (--copy)
    assert [ln.split()[0] for ln in listing[split + 1:] if ln.strip()] == ["first_drum",
                                                                          "hot_cooler"]
    r = subprocess.run([sys.executable, "-m", "taichi_dem", "demo", "no_such_demo"],
                       capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert r.returncode == 2 and "available" in r.stderr


def test_a_scene_is_copied_out_to_edit_and_nothing_is_overwritten(tmp_path, capsys):
    """``taichi-dem demo NAME --copy DIR`` (a wheel user has no demos/ folder): the scene as
    the package holds it, which then checks; a second copy refuses and leaves the first."""
    from taichi_dem.app.cli import main
    assert main(["demo", "first_drum", "--copy", str(tmp_path / "mine")]) == 0
    copied = tmp_path / "mine" / "first_drum.toml"
    assert copied.read_text() == demos.tutorial_scenes()["first_drum"].read_text()
    assert main(["check", str(copied)]) == 0
    copied.write_text(copied.read_text() + "\n# my edit\n")
    capsys.readouterr()
    assert main(["demo", "first_drum", "--copy", str(tmp_path / "mine")]) == 2
    assert "exists already" in capsys.readouterr().err
    assert copied.read_text().endswith("# my edit\n")
    assert main(["demo", "pile", "--copy", str(tmp_path)]) == 0
    assert (tmp_path / "pile.toml").read_text() == demos.get("pile").path.read_text()
    assert main(["demo", "no_such_scene", "--copy", str(tmp_path)]) == 2


def test_a_copy_takes_the_files_the_scene_names(tmp_path):
    """A scene's CSV fill (or STL mesh) beside it is copied with it, under the same name."""
    folder = tmp_path / "pkg"
    folder.mkdir()
    (folder / "beads.csv").write_text("x,y,z,radius\n0,0,0,0.01\n")
    scene = folder / "s.toml"
    scene.write_text('[[particles]]\nmaterial = "glass"\nfile = "beads.csv"\n'
                     'note = "not/a/file"\n')
    assert demos._named_files(scene) == [__import__("pathlib").Path("beads.csv")]


def test_the_dryer_demo_gives_the_maps_answers_with_their_uncertainty(capsys):
    """The dryer demo's whole-dryer lines (the real-size design on its slices' map, the pilot
    dryer on the 1 m drum's maps): each map figure a user acts on carries its change when the
    map's closures move by their standard errors, the same figures `taichi-dem dryer` prints."""
    from taichi_dem.app.dryer_command import run
    demos.get("dryer_drum")._whole_dryer()
    out = capsys.readouterr().out
    _, m, moved = run(demos.DEMOS_DIR / "dryers" / "aggregate_dryer_map.toml", capacity=False)
    line = next(x for x in out.splitlines() if "same dryer on the DEM map" in x)
    assert (f"residence {m['residence_time'] / 60:.3g} +- "
            f"{moved['combined']['residence_time'] / 60:.2g} min") in line
    assert f"the gas at {m['gas_outlet_temperature'] - 273.15:.0f} +- " in line
    _, ms, _ = run(demos.DEMOS_DIR / "dryers" / "aggregate_dryer_map.toml", capacity=False,
                   exposure="surface")
    line = next(x for x in out.splitlines() if "flights' loads' open surface" in x)
    assert f"gas-solids {ms['conductance_per_metre']:.3g} W/(m K)" in line
    assert f"the gas at {ms['gas_outlet_temperature'] - 273.15:.0f} +- " in line
    pilot = next(x for x in out.splitlines() if "pilot dryer fed" in x)
    on_map, on_correlations = pilot.split("; on the correlations")
    assert "residence" in on_map and " +- " in on_map.split("residence", 1)[1]
    assert " +- " not in on_correlations.split(". The map's")[0]
    # the same maps with the gas meeting the bed's and the loads' open surface too
    _, surface, _ = run(demos.DEMOS_DIR / "dryers" / "pilot_dryer.toml", capacity=False,
                        exposure="surface")
    counted = on_map.split("the gas also meeting", 1)[1]
    assert f"{surface['conductance_per_metre']:.3g} W/(m K) per metre" in counted
    assert " +- " in counted
