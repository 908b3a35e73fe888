"""The sheet inlet (``[[factories]] pattern = "sheet"``): it delivers the scheduled mass rate and
never inserts a sphere overlapping another, a wall or the stream ahead of it.

Tolerance of the mass rate: layer j goes in when the schedule reaches the mass before it plus
half its own, at the first whole step after, so at any time the inserted mass differs from the
schedule by at most half the largest layer plus one step's feed (max(M_layer)/2 + rate dt);
over a run of many layers the mean rate is then exact to that over the run time.
"""
import math
from pathlib import Path

import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.scene.model import RateSchedule

SCENE = """
[simulation]
end_time = {end}
dt = 5.0e-6
gravity = {gravity}
seed = 3

[domain]
min = [0.0, 0.0, 0.0]
max = [0.05, 0.01, 0.01]

[materials.grain]
density = 811.54
youngs_modulus = 5.17e6
poisson_ratio = 0.25

[materials.wall]
density = 7800.0
youngs_modulus = 5.17e6
poisson_ratio = 0.25

[[interactions]]
pair = ["grain", "grain"]
restitution = 0.55
friction = 0.4877

[[interactions]]
pair = ["grain", "wall"]
restitution = 0.55
friction = 0.4245

{walls}

[[factories]]
name = "inlet"
pattern = "sheet"
material = "grain"
radius = 0.0005
face = {{ point = [0.0, 0.0, 0.0], width = [0.0, 0.01, 0.0], depth = [0.0, 0.0, 0.008] }}
velocity = [1.0, 0.0, 0.0]
mass_rate = {rate}

[output]
interval = 0.001
"""


def _sim(tmp_path: Path, rate, end=0.02, gravity="[0.0, 0.0, 0.0]", walls=""):
    p = tmp_path / "sheet.toml"
    p.write_text(SCENE.format(end=end, gravity=gravity, walls=walls, rate=rate))
    return td.Simulation.from_toml(str(p), arch="cpu")


def _watch_insertions(sim):
    """Wrap Engine.insert: before each insertion, the smallest gap (m) between a new sphere and
    the spheres already there or inserted with it, and between a new sphere and each wall."""
    engine = sim.engine
    original = engine.insert
    gaps = []

    def insert(arrays):
        st = engine.state
        n = engine.count
        alive = st.alive.to_numpy()[:n] != 0
        old_x = st.position.to_numpy()[:n][alive].astype(float)
        old_r = st.radius.to_numpy()[:n][alive].astype(float)
        x, r = np.asarray(arrays["position"], float), np.asarray(arrays["radius"], float)
        allx, allr = np.concatenate([old_x, x]), np.concatenate([old_r, r])
        d = np.sqrt(np.sum((x[:, None] - allx[None]) ** 2, axis=-1)) - (r[:, None] + allr[None])
        d[np.arange(len(x)), len(old_x) + np.arange(len(x))] = np.inf      # itself
        wall = min([float(np.min((x - np.asarray(w.point)) @ np.asarray(w.normal) - r))
                    for w in sim.scene.walls], default=np.inf)
        gaps.append(min(float(d.min()), wall))
        original(arrays)
    engine.insert = insert
    return gaps


def test_schedule_time_for_mass():
    s = RateSchedule(points=((0.0, 2.0), (1.0, 0.0), (3.0, 1.0)))
    assert s.time_for_mass(1.0) == pytest.approx(0.5)
    assert s.time_for_mass(2.0) == pytest.approx(1.0)
    assert s.time_for_mass(2.5) == pytest.approx(3.5)       # nothing is fed from 1 to 3 s
    assert s.mass_until(s.time_for_mass(2.7)) == pytest.approx(2.7)
    assert math.isinf(RateSchedule(points=((0.0, 1.0), (1.0, 0.0))).time_for_mass(2.0))


def test_sheet_delivers_the_scheduled_mass_without_overlaps(tmp_path):
    # a free stream (no gravity, no walls): 0.03 kg/s (99 % of what this lattice carries at
    # 1 m/s, so successive layers are at their least spacing), then 0.015 kg/s from t = 10 ms
    with _sim(tmp_path, '[[0.0, "0.03 kg/s"], [0.01, "0.015 kg/s"]]') as sim:
        gaps = _watch_insertions(sim)
        sim.run()
        f = sim.factories
        m_layer = max(f.layer_mass(0, 0), f.layer_mass(0, 1))
        schedule = sim.scene.factories[0].mass_rate
        t = sim.series["time"]
        fed = sim.series["factories/inlet/mass"]
        scheduled = np.array([schedule.mass_until(x) for x in t])
        tol = 0.5 * m_layer + 0.03 * sim.dt
        assert np.max(np.abs(fed - scheduled)) <= tol
        assert np.max(np.abs(fed - scheduled)) > 0.05 * tol        # (not vacuous: layers are discrete)
        # the mean rate over the run, to the same bound over the run time
        assert fed[-1] / t[-1] == pytest.approx(schedule.mass_until(t[-1]) / t[-1], abs=tol / t[-1])
        assert sim.series["factories/inlet/behind"][-1] == 0.0
        # no insertion overlapped anything, and the free stream keeps every gap (rigid motion)
        assert len(gaps) >= 18 and min(gaps) >= 0.0     # 13 layers at 0.03 kg/s, 6 at 0.015
        x = sim.particles()["position"].astype(float)
        d2 = np.sum((x[:, None] - x[None]) ** 2, axis=-1)
        np.fill_diagonal(d2, np.inf)
        assert math.sqrt(d2.min()) >= 1e-3 * (1.0 - 1e-5)


def test_a_blocked_stream_drops_sites_instead_of_overlapping(tmp_path, capsys):
    # a wall 4 mm in front of the face and gravity pushing the stream back: the spheres pile
    # up at the face, layers that would overlap them lose those sites, and the run says so
    walls = ('[[walls]]\nname = "stop"\nplane = { point = [0.004, 0, 0], normal = [-1, 0, 0] }\n'
             'material = "wall"\n'
             '[[walls]]\nname = "back"\nplane = { point = [0.0, 0, 0], normal = [1, 0, 0] }\n'
             'material = "wall"')
    with _sim(tmp_path, '"0.03 kg/s"', end=0.015, gravity="[-9.81, 0.0, 0.0]", walls=walls) as sim:
        gaps = _watch_insertions(sim)
        sim.run()
        assert min(gaps) >= 0.0
        behind = sim.series["factories/inlet/behind"][-1]
        assert behind > 0.3 * 0.03 * 0.015                       # most of the feed had no room
        assert "dropped" in capsys.readouterr().err


def test_resumed_sheet_continues_its_layers(tmp_path):
    # a checkpoint carries the layer count and the mass of the layers done: the resumed run
    # inserts the same layers at the same steps as the uninterrupted one
    full = _sim(tmp_path, '"0.03 kg/s"', end=0.01)
    full.run()
    fed_full = full.series["factories/inlet/mass"].copy()
    layers_full = int(full.factories.layers[0])
    full.close()
    first = _sim(tmp_path, '"0.03 kg/s"', end=0.01)
    first.run(until=0.005)
    first.checkpointer.path = str(tmp_path / "sheet.checkpoint.h5")
    first.checkpointer.save(sim=first)
    first.close()
    resumed = td.Simulation.from_checkpoint(str(tmp_path / "sheet.checkpoint.h5"), arch="cpu")
    resumed.run(until=0.01)
    assert int(resumed.factories.layers[0]) == layers_full
    assert np.allclose(resumed.series["factories/inlet/mass"], fed_full, rtol=0, atol=1e-12)
    resumed.close()
