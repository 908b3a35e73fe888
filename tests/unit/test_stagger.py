"""``taichi-dem map --stagger`` (issue 44 item 5): the slice holds the repeating unit of paddle
rows turned by any stagger. The 45 deg unit of the one-row slice must be the two-row slice
written by hand (bench/seed_cooler/cooler_slice_two_rows.toml): the same bodies, vertex for
vertex, the same period and fill region."""
import tomllib
from pathlib import Path

import numpy as np
import pytest

from taichi_dem.app.overrides import apply, to_text
from taichi_dem.app.slice_map import holdup_count, slice_geometry
from taichi_dem.app.stagger import rows_to_repeat, staggered_doc
from taichi_dem.errors import SceneError
from taichi_dem.scene.loader import parse_scene

ROOT = Path(__file__).resolve().parents[2]
SLICE = ROOT / "demos" / "cooler_slice.toml"
TWO_ROWS = ROOT / "bench" / "seed_cooler" / "cooler_slice_two_rows.toml"


@pytest.mark.parametrize("stagger, paddles, rows", [
    (0, 4, 1), (90, 4, 1), (45, 4, 2), (30, 4, 3), (22.5, 4, 4), (60, 4, 3), (-45, 4, 2),
    (45, 2, 4), (120, 3, 1), (7, 4, 0)])
def test_rows_to_repeat(stagger, paddles, rows):
    assert rows_to_repeat(stagger, paddles) == rows


def _scene(doc):
    return parse_scene(to_text(doc), source=str(SLICE), base_dir=SLICE.parent)


def test_the_45_degree_unit_is_the_hand_written_two_row_slice():
    doc = tomllib.loads(SLICE.read_text())
    g = slice_geometry(_scene(doc))
    made, rows = staggered_doc(doc, 45.0, str(SLICE), g.axis, g.length)
    assert rows == 2
    # the hand-written slice's material is the free-rolling ash: compare the geometry
    mine = _scene(made)
    theirs = parse_scene(TWO_ROWS.read_text(), source=str(TWO_ROWS), base_dir=TWO_ROWS.parent)
    assert mine.domain.max == theirs.domain.max and mine.domain.min == theirs.domain.min
    for a, b in zip(mine.bodies, theirs.bodies):
        assert a.name == b.name
        np.testing.assert_allclose(a.vertices, b.vertices, atol=1e-12)
        np.testing.assert_array_equal(a.faces, b.faces)
    assert mine.fills[0].region == theirs.fills[0].region
    # the hold-up per metre gives twice the particles in the twice as long slice
    g2 = slice_geometry(mine)
    assert g2.length == pytest.approx(2 * g.length)
    one = holdup_count(_scene(doc), g, ("kg/m", 60.0))[0]
    two = holdup_count(mine, g2, ("kg/m", 60.0))[0]
    assert abs(two - 2 * one) <= 1


def test_stagger_90_with_four_paddles_is_the_one_row_slice():
    doc = tomllib.loads(SLICE.read_text())
    g = slice_geometry(_scene(doc))
    made, rows = staggered_doc(doc, 90.0, str(SLICE), g.axis, g.length)
    assert rows == 1 and made == doc


def test_three_rows_at_30_degrees_turn_each_row():
    doc = tomllib.loads(SLICE.read_text())
    g = slice_geometry(_scene(doc))
    made, rows = staggered_doc(doc, 30.0, str(SLICE), g.axis, g.length)
    assert rows == 3
    shaft = made["bodies"][1]["mesh"]
    assert shaft["rows"] == 3 and shaft["stagger_deg"] == 30.0
    assert shaft["length"] == pytest.approx(0.75)
    assert made["domain"]["max"][0] == pytest.approx(0.75)
    assert slice_geometry(_scene(made)).length == pytest.approx(0.75)


@pytest.mark.parametrize("change, key, reason", [
    ({"bodies.1.mesh.rows": 2}, "bodies[1].mesh.rows", "one-row slice"),
    ({"bodies.1.mesh.row_spacing": 0.25}, "bodies[1].mesh.row_spacing", "drop row_spacing"),
])
def test_a_slice_it_cannot_stagger_is_refused(change, key, reason):
    doc = apply(tomllib.loads(SLICE.read_text()), change, str(SLICE))
    with pytest.raises(SceneError) as e:
        staggered_doc(doc, 45.0, str(SLICE), 0, 0.25)
    assert e.value.key == key and reason in e.value.reason


def test_a_stagger_that_never_repeats_is_refused():
    doc = tomllib.loads(SLICE.read_text())
    with pytest.raises(SceneError) as e:
        staggered_doc(doc, 7.0, str(SLICE), 0, 0.25)
    assert "repeats after more than 8 rows" in e.value.reason
    with pytest.raises(SceneError):
        staggered_doc(doc, float("nan"), str(SLICE), 0, 0.25)
