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
    lines = [ln.split()[0] for ln in r.stdout.splitlines()[1:] if ln.strip()]
    assert lines == list(demos.DEMOS)
    r = subprocess.run([sys.executable, "-m", "taichi_dem", "demo", "no_such_demo"],
                       capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert r.returncode == 2 and "available" in r.stderr
