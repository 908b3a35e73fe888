"""Impact speeds per collision (``[[sensors]] kind = "contact_statistics"``, effects/impacts.py):
each collision counted once, at its first touching step, with its approach speed, per pair
kind, against free flight under gravity (f64).

One scene, three collisions whose speeds are known in closed form:

- a sphere released at rest with its lowest point h_w = 20 mm above a plane wall hits it at
  sqrt(2 g h_w) = 0.6264 m/s, then bounces (restitution 0.5) and hits again at about half that;
- a sphere released h_b = 10 mm above a steel box body (a mesh) hits it at sqrt(2 g h_b) =
  0.4429 m/s at 0.045 s, and again at 0.090 s at e times that (Hertz with the damping set
  for e: to the few per cent the restitution tests hold);
- two spheres high above the floor approach each other at +-u = 0.1 m/s and meet at 2u: both
  fall alike, so gravity does not enter their relative speed.

Velocity Verlet moves a free particle exactly, but a contact is seen at the first step after
the surfaces meet, with the velocity the step holds then: within one step of gravity, g dt =
9.8e-6 m/s, of the speed at the instant of touching, which is the tolerance (absolute; the
head-on pair, with no relative acceleration, to round-off). The percentiles come from logarithmic bins and are exact to one bin (a factor
1.12). A counting error (a collision counted at every step it lasts, or again at a
neighbour-list rebuild) shows as hundreds of collisions instead of one.
"""
import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.effects import impacts
import dem_helpers as h

R = 0.005
G = 9.81
H_WALL, H_BODY = 0.02, 0.01
U = 0.1
DT = 1e-6


def _scene(tmp_path, sensor: bool = True):
    top = 0.02                                       # the box body's top face, m
    positions = [[0.0, 0.0, R + H_WALL],             # over the floor
                 [0.06, 0.0, top + R + H_BODY],      # over the box
                 [-0.04, 0.0, 0.09], [-0.04 + 2 * R + 0.004, 0.0, 0.09]]   # the pair
    velocities = [[0, 0, 0], [0, 0, 0], [U, 0, 0], [-U, 0, 0]]
    text = (h.header(dt=DT, gravity=(0.0, 0.0, -G), lo=(-0.08, -0.03, -0.01),
                     hi=(0.1, 0.03, 0.12), output_interval=0.05)
            + h.material("glass", 2500.0, 1e8, 0.25) + h.material("steel", 7800.0, 2e11, 0.3)
            + h.all_interactions(["glass", "steel"], restitution=0.5)
            + h.csv_fill(tmp_path, "beads.csv", "glass", positions, R, velocities=velocities)
            + h.wall("floor", [0, 0, 0], [0, 0, 1], "steel")
            + '[[bodies]]\nname = "box"\nmaterial = "steel"\nmesh = { builder = "box", '
              f'min = [0.04, -0.02, 0.01], max = [0.08, 0.02, {top}] }}\n\n')
    if sensor:
        text += '[[sensors]]\nkind = "contact_statistics"\nname = "contacts"\n'
    return text


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("impacts")
    h5 = tmp_path / "impacts.h5"
    with taichi_dem.Simulation.from_text(_scene(tmp_path), base_dir=str(tmp_path),
                                         h5=str(h5)) as sim:
        sim.run(until=0.1)             # samples at 0.05 and 0.1 s
        effects = [e.name for e in sim.effects]
        histogram = dict(sim.engine.model.effect("impacts").histogram)
        out = {k: np.asarray(v) for k, v in sim.series.items() if k.startswith("sensors/")}
        out["time"] = np.asarray(sim.series["time"])
    out["h5"] = h5
    return out, effects, histogram


def test_each_collision_counted_once_at_its_impact_speed(series):
    s, effects, _ = series
    assert "impacts" in effects
    assert list(s["time"]) == pytest.approx([0.0, 0.05, 0.1])
    # by 0.05 s: the pair met (t = 0.02 s) and the sphere on the box (at 0.045 s); the
    # sphere over the floor lands at 0.0639 s, and bounces into the air until ~0.128 s; the
    # one on the box lands again at 0.090 s
    wall_speed = math.sqrt(2 * G * H_WALL)
    body_speed = math.sqrt(2 * G * H_BODY)
    expected = {"particle": ([0, 1, 0], 2 * U), "wall": ([0, 0, 1], wall_speed),
                "body": ([0, 1, 1], body_speed)}
    for kind, (counts, speed) in expected.items():
        assert list(s[f"sensors/contacts/{kind}/collisions"]) == counts, kind
        k = counts.index(1)
        for stat in ("mean", "max"):
            assert s[f"sensors/contacts/{kind}/impact_speed_{stat}"][k] == pytest.approx(
                speed, abs=G * DT if kind != "particle" else 1e-12), (kind, stat)
        p50 = s[f"sensors/contacts/{kind}/impact_speed_p50"][k]
        assert speed / 1.13 < p50 < speed * 1.13, kind
        assert s[f"sensors/contacts/{kind}/collision_rate"][k] == pytest.approx(1 / 0.05)
    assert s["sensors/contacts/body/impact_speed_max"][2] == pytest.approx(0.5 * body_speed,
                                                                            rel=0.03)
    # no collision, no speed
    assert s["sensors/contacts/wall/impact_speed_max"][1] == 0.0


def test_the_run_histogram_holds_every_collision(series):
    _, _, histogram = series
    edges = impacts.bin_edges()
    for kind, speed in (("particle", 2 * U), ("wall", math.sqrt(2 * G * H_WALL))):
        counts = histogram[kind]
        assert counts.sum() == 1
        b = int(np.flatnonzero(counts)[0])
        assert edges[b - 1] <= speed < edges[b], kind


def test_percentiles_from_the_bins_against_numpy():
    rng = np.random.default_rng(4)
    speeds = 10.0 ** rng.uniform(-3, 1, 20000)       # 1 mm/s to 10 m/s
    edges = impacts.bin_edges()
    counts = np.zeros(impacts.N_BINS, np.int64)
    np.add.at(counts, np.searchsorted(edges, speeds, side="right"), 1)
    for q in (10, 50, 90):
        exact = np.percentile(speeds, q)
        assert impacts.percentile(counts, q) == pytest.approx(exact, rel=0.12), q
    assert impacts.percentile(np.zeros(impacts.N_BINS), 50) == 0.0


def test_a_scene_without_the_sensor_counts_nothing(tmp_path):
    from taichi_dem.effects.registry import enabled_effects
    from taichi_dem.scene.loader import parse_scene
    scene = parse_scene(_scene(tmp_path, sensor=False), source="scene.toml",
                        base_dir=str(tmp_path))
    assert "impacts" not in [e.name for e in enabled_effects(scene)]


def test_plot_draws_the_collisions(series):
    from taichi_dem.app.plots import plot_results
    s, _, _ = series
    figures = {f.name: f for f in plot_results(str(s["h5"]))}
    figure = figures["collisions_contacts"]
    # no sample caught a contact (each lasts a few ms): no force panel
    assert [p.title.split(" ")[0] for p in figure.panels] == ["collisions", "impact"]
    x, y = figure.drawn[0]["particle-body"]
    np.testing.assert_array_equal(y, s["sensors/contacts/body/collision_rate"])
    x, y = figure.drawn[1]["particle-wall, median"]
    np.testing.assert_array_equal(y, s["sensors/contacts/wall/impact_speed_p50"])
