"""The narrowest gap between coaxial bodies (geometry/gaps.py) and `check`'s warning when the
largest sphere cannot pass it (issue 31 item 5)."""
import math
from pathlib import Path

import numpy as np
import pytest

from taichi_dem.geometry.gaps import radial_gap, surface_points
from taichi_dem.geometry import build

ROOT = Path(__file__).resolve().parents[2]


def test_gap_between_a_paddle_shaft_and_a_faceted_shell_is_the_tip_to_facet_distance():
    shell = build("drum", {"radius": 0.4, "length": 0.3, "end_walls": False, "segments": 32})
    shaft = build("paddle_shaft", {"length": 0.3, "shaft_radius": 0.05, "rows": 1,
                                   "paddles_per_row": 4, "paddle_width": 0.08,
                                   "shell_radius": 0.4, "clearance": 0.03})
    gap, where = radial_gap(surface_points(shaft.vertices, shaft.faces),
                            surface_points(shell.vertices, shell.faces), (0, 0, 0), (1, 0, 0),
                            slab=0.01)
    # unpitched paddles lie in planes through the axis: their tip edge at 0.4 - 0.03 m; the
    # shell's facets come in to the apothem 0.4 cos(pi / 32): 1.9 mm less than the clearance
    assert gap == pytest.approx(0.4 * math.cos(math.pi / 32) - 0.37, abs=2e-4)
    assert 0.0 <= where <= 0.3


def _check_notes(radius: float) -> str:
    from taichi_dem.app.cli import describe_scene
    from taichi_dem.scene.loader import parse_scene
    text = (ROOT / "demos" / "cooler_slice.toml").read_text().replace(
        "radius = 0.0075", f"radius = {radius}")
    return describe_scene(parse_scene(text, source="cooler_slice.toml"))


def test_check_warns_when_the_largest_sphere_cannot_pass_the_paddle_tips():
    assert "cannot pass the narrowest gap between bodies 'shaft' and 'shell'" in _check_notes(0.015)
    assert "cannot pass" not in _check_notes(0.0075)     # the seed's 15 mm spheres pass
