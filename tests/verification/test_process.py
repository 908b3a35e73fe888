"""Process tooling: factories follow their schedule, outlets and lost particles close the mass
balance, sensors measure what the kinematics says they must.

The free-fall scenes insert spheres so sparsely that they never touch: every particle's path
is then the analytic z(t) = z0 - v0 t - g t^2 / 2, which fixes residence times and crossings.
"""
import math

import h5py
import numpy as np
import pytest

import taichi_dem as td

G = 9.81


def scene(rate='[[0.0, "0.2 kg/s"], [0.6, "0.4 kg/s"]]', extra="", region_z=(0.40, 0.4102),
          velocity=-0.5, end=1.2, thermal=False, max_particles=None):
    lo, hi = region_z
    return f"""
[simulation]
end_time = {end}
precision = "f64"
dt = 5e-5
{"max_particles = %d" % max_particles if max_particles else ""}
[domain]
min = [0, 0, 0]
max = [0.6, 0.6, 0.5]
[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = 1.0
heat_capacity = 800.0
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
[[factories]]
name = "inlet"
material = "glass"
radius = 0.005
region = {{ box = {{ min = [0.05, 0.05, {lo}], max = [0.55, 0.55, {hi}] }} }}
velocity = [0, 0, {velocity}]
temperature = 450.0
mass_rate = {rate}
[[outlets]]
name = "drain"
region = {{ box = {{ min = [0.0, 0.0, 0.0], max = [0.6, 0.6, 0.1] }} }}
[[sensors]]
kind = "residence_time"
name = "res"
from = "inlet"
to = "drain"
[[sensors]]
kind = "mass_flow"
name = "mid"
plane = {{ point = [0, 0, 0.25], normal = [0, 0, -1] }}
{extra}
{"[thermal]" if thermal else ""}
[output]
interval = 0.02
"""


def flight_time(z0, v0, z1):
    """Time to fall from z0 to z1 starting downwards at v0 (> 0) under gravity, s."""
    return (-v0 + math.sqrt(v0 * v0 + 2.0 * G * (z0 - z1))) / G


class _Finished:
    """What the tests read of a finished run, taken before it is closed: a simulation left
    alive would make every later one of this worker compile its kernels afresh instead of
    reading them from the cache (engine/backend.py acquire)."""

    def __init__(self, sim, residence_sensor):
        self.series, self.scene, self.dt = sim.series, sim.scene, sim.dt
        self._particles, self._balance = sim.particles(), sim.mass_balance()
        self._records = {residence_sensor: sim.residence_times(residence_sensor)}

    def particles(self):
        return self._particles

    def mass_balance(self):
        return self._balance

    def residence_times(self, sensor):
        return self._records[sensor]


@pytest.fixture(scope="module")
def falling():
    with td.Simulation.from_text(scene(), arch="cpu") as sim:
        sim.run(1.2)
        return _Finished(sim, "res")


def test_inserted_mass_follows_the_schedule(falling):
    """At every sample the inserted mass is the scheduled mass to within half a particle (the
    factory rounds to whole particles, and samples fall on insertions); so over any 1 s window
    within one particle, 0.5 % of the 0.28 kg fed in the slowest window (issue 5: 1 %)."""
    s = falling.series
    sched = falling.scene.factories[0].mass_rate
    particle = 4 / 3 * math.pi * 0.005 ** 3 * 2500.0
    t = s["time"]
    inserted = s["factories/inlet/mass"]
    scheduled = np.array([sched.mass_until(x) for x in t])
    # samples fall on insertions; a particle goes in once half of it is due
    assert np.all(np.abs(inserted - scheduled) <= 0.5 * particle + 1e-12)
    assert np.all(s["factories/inlet/behind"] <= 0.5 * particle + 1e-12)
    for a in range(len(t)):
        for b in range(a + 1, len(t)):
            if abs(t[b] - t[a] - 1.0) < 0.011:
                fed = inserted[b] - inserted[a]
                want = scheduled[b] - scheduled[a]
                assert abs(fed - want) / want < 0.01


def test_insertions_at_rebuilds_keep_free_flight_exact():
    """A batch due at the end of a run of steps goes in at a neighbour rebuild within the run
    (FactorySet.insert_at_rebuild), mid-step, with v0 - g dt/2 so that the half kick that
    follows gives it v0 at its insertion time. In free flight every particle's velocity is
    then exactly v0 - g (t - t_in) (f64: to round-off), whether it went in at its due step or
    earlier at a rebuild; and insertions at rebuilds spare rebuilds (here: most insertions
    happen at one)."""
    sim = td.Simulation.from_text(scene(end=0.3), arch="cpu")
    sim.run(0.3)
    s = sim.engine.state
    n = sim.engine.count
    alive = s.alive.to_numpy()[:n] != 0
    birth = s.birth_time.to_numpy()[:n][alive]
    vz = s.velocity.to_numpy()[:n][alive, 2]
    every = sim.factories.every[0] * sim.dt
    steps_off_schedule = np.abs(birth / every - np.round(birth / every)) > 1e-6
    assert steps_off_schedule.sum() > 0.5 * len(birth)        # went in at a rebuild
    assert np.max(np.abs(vz - (-0.5 - G * (sim.time - birth)))) < 1e-9
    sim.close()


def test_mass_balance_closes(falling):
    """initial + fed = inside + removed + lost, summed in float64 from the stored masses."""
    b = falling.mass_balance()
    assert b["fed"] > 0.2 and b["removed"] > 0.05
    assert abs(b["error"]) < 1e-12 * b["fed"]


def test_residence_time_is_the_free_fall_time(falling):
    """Every particle enters at z0 = 0.4051 +- 0.0001 m moving down at 0.5 m/s and is removed
    when its centre enters the outlet (z <= 0.1): t_out - t_in = flight time, to within one
    step (removal is checked every step) plus the spread of z0."""
    rec = falling.residence_times("res")
    assert len(rec) > 50
    flight = rec[:, 2] - rec[:, 1]
    lo = flight_time(0.4051 - 0.0001, 0.5, 0.1)
    hi = flight_time(0.4051 + 0.0001, 0.5, 0.1)
    assert np.all(flight >= lo - 1e-9) and np.all(flight <= hi + falling.dt + 1e-9)
    s = falling.series
    done = s["sensors/res/count"] > 0
    assert np.all(np.abs(s["sensors/res/median"][done] - 0.5 * (lo + hi)) < 2 * falling.dt + 1e-4)
    # ids are unique, t_in are insertion times
    assert len(np.unique(rec[:, 0])) == len(rec)


def test_mass_flow_plane_counts_every_crossing(falling):
    """Mass through the plane z = 0.25 (normal down, so downward flow is positive) equals what
    the outlet removed plus what is in flight below the plane."""
    s = falling.series
    crossed = float(np.sum(s["sensors/mid/mass_flow"][1:] * np.diff(s["time"])))
    p = falling.particles()
    below = float(np.sum(p["mass"][p["position"][:, 2] < 0.25]))
    removed = falling.mass_balance()["removed"]
    assert crossed == pytest.approx(removed + below, rel=1e-9)
    # in steady fall the plane sees the feed rate, 0.4 kg/s after the change at 0.6 s
    t = s["time"]
    late = t > 0.6 + flight_time(0.405, 0.5, 0.25) + 0.05
    assert np.mean(s["sensors/mid/mass_flow"][late]) == pytest.approx(0.4, rel=0.05)


def test_outlet_series(falling):
    s = falling.series
    assert s["outlets/drain/mass"][-1] == pytest.approx(falling.mass_balance()["removed"])
    assert np.all(np.diff(s["outlets/drain/mass"]) >= 0)
    particle = 4 / 3 * math.pi * 0.005 ** 3 * 2500.0
    assert s["outlets/drain/count"][-1] * particle == pytest.approx(s["outlets/drain/mass"][-1])


def test_outlet_temperature_and_hdf5(tmp_path):
    """Removed particles carry their temperature and moisture into the outlet's means; with no
    heat exchange (thermal on, nothing enabled to exchange with) they are the factory's (350 K, below the evaporation temperature). The
    residence records land in /residence/<name>/ as CONTRACT.md names them."""
    h5 = tmp_path / "r.h5"
    text = scene(thermal=True, rate='"0.2 kg/s"').replace("[thermal]", "[thermal]\nconduction = false")
    text = text.replace("temperature = 450.0", "temperature = 350.0\nmoisture = 0.1")
    sim = td.Simulation.from_text(text, arch="cpu", h5=str(h5))
    sim.run(0.6)
    rec = sim.residence_times("res")
    s = sim.series
    sim.close()
    temps = s["outlets/drain/mean_temperature"]
    assert np.any(np.isfinite(temps))
    assert np.allclose(temps[np.isfinite(temps)], 350.0, rtol=0, atol=1e-9)
    # wet particles (0.1 kg water per kg solid) below the evaporation temperature keep their
    # water: the outlet's moisture is the factory's
    wet = s["outlets/drain/mean_moisture"]
    assert np.allclose(wet[np.isfinite(wet)], 0.1, rtol=1e-6)
    with h5py.File(h5) as f:
        assert np.array_equal(f["residence/res/id"][:], rec[:, 0].astype(np.int64))
        assert np.allclose(f["residence/res/t_out"][:], rec[:, 2])
        assert "series/outlets/drain/mass" in f and "series/sensors/mid/mass_flow" in f
        # every series carries its unit (sensors/series.py and the effects' SERIES)
        names = []
        f["series"].visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
        assert len(names) > 15
        assert all(f["series"][n].attrs.get("units") for n in names), \
            [n for n in names if not f["series"][n].attrs.get("units")]
        assert f["series/outlets/drain/mass_flow"].attrs["units"] == "kg/s"
        ids = f[f"frames/{len(f['frames']) - 1}/id"][:]
        assert len(np.unique(ids)) == len(ids)
        # and every frame and residence dataset (issue 33 item 3)
        frame = f[f"frames/{len(f['frames']) - 1}"]
        assert frame["position"].attrs["units"] == "m" and frame.attrs["time_units"] == "s"
        assert frame["mass"].attrs["units"] == "kg" and np.all(frame["mass"][()] > 0)
        assert "moisture" in frame            # this scene dries: each particle's water
        datasets = []                          # the particles' and the bodies' poses
        frame.visititems(lambda n, o: datasets.append(n) if isinstance(o, h5py.Dataset) else None)
        assert all(frame[n].attrs.get("units") for n in datasets), datasets
        assert "material" in frame and all(f[f"bodies/{b}/vertices"].attrs["units"] == "m"
                                           for b in f.get("bodies", {}))
        assert f["residence/res/t_out"].attrs["units"] == "s"


def test_full_region_waits_and_says_so(capfd):
    """A region that holds a few particles, fed far more than can leave it: the factory
    inserts what fits, says so, and never runs ahead of the schedule."""
    text = scene(rate='"20 kg/s"', region_z=(0.40, 0.4102), velocity=0.0)
    text = text.replace("max = [0.55, 0.55, 0.4102]", "max = [0.08, 0.08, 0.4102]")
    sim = td.Simulation.from_text(text, arch="cpu")
    sim.run(0.1)
    s = sim.series
    sim.close()
    err = capfd.readouterr().err
    assert "region is full" in err and "behind schedule" in err
    assert s["factories/inlet/behind"][-1] > 1.0
    t = s["time"][-1]
    assert s["factories/inlet/mass"][-1] < 20 * t


def test_capacity_limit_waits_and_says_so(capfd):
    sim = td.Simulation.from_text(scene(max_particles=20), arch="cpu")
    sim.run(0.4)
    s = sim.series
    sim.close()
    assert s["particles/count"].max() <= 20
    assert "capacity" in capfd.readouterr().err
    assert s["factories/inlet/behind"][-1] > 0.0


def test_contact_count_on_a_body():
    """Spheres resting on a box body: each touches it once; contact_count is their number."""
    text = """
[simulation]
end_time = 0.2
precision = "f64"
[domain]
min = [-0.1, -0.1, -0.05]
max = [0.1, 0.1, 0.1]
[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.3
friction = 0.5
[[bodies]]
name = "plate"
material = "glass"
mesh = { builder = "box", min = [-0.09, -0.09, -0.02], max = [0.09, 0.09, 0.0] }
[[particles]]
material = "glass"
radius = 0.004
count = 12
region = { box = { min = [-0.08, -0.08, 0.001], max = [0.08, 0.08, 0.0095] } }
[[sensors]]
kind = "contact_count"
name = "touching"
body = "plate"
[output]
interval = 0.05
"""
    sim = td.Simulation.from_text(text, arch="cpu")
    sim.run(0.2)
    s = sim.series
    sim.close()
    assert s["sensors/touching/contact_count"][-1] == 12
    assert s["sensors/touching/contact_count"][0] == 0


def test_resume_continues_factories_outlets_and_residence(tmp_path):
    """A run checkpointed at 0.3 s and resumed to 0.6 s ends where a straight run ends:
    the same particles (ids, positions), the factory on schedule with the same random
    positions, the same removals and residence records (f64)."""
    text = scene(rate='"0.2 kg/s"')
    a = td.Simulation.from_text(text, arch="cpu")
    a.run(0.6)
    pa, ra, ba = a.particles(), a.residence_times("res"), a.mass_balance()
    a.close()
    b = td.Simulation.from_text(text, arch="cpu")
    b.run(0.3)
    b.checkpointer.path = str(tmp_path / "p.checkpoint.h5")
    b.checkpointer.save(sim=b)
    b.close()
    c = td.Simulation.from_checkpoint(str(tmp_path / "p.checkpoint.h5"), h5="")
    c.run(0.6)
    pc, rc, bc = c.particles(), c.residence_times("res"), c.mass_balance()
    c.close()
    assert np.array_equal(pa["id"], pc["id"])
    assert np.max(np.abs(pa["position"] - pc["position"])) < 1e-12
    assert np.array_equal(ra, rc)
    assert bc["fed"] == ba["fed"] and bc["removed"] == ba["removed"]
    assert abs(bc["error"]) < 1e-12


def test_a_short_closing_sample_biases_no_mean():
    """A run whose dt (30 us) does not divide its 20 ms output interval (samples fall every
    667 steps, 20.01 ms) and whose end falls 63 steps (1.89 ms) after its last regular sample
    closes with a sample at its last instant (``sample_now``, as ``taichi-dem run`` does).
    That sample's rates and counts are pooled with the interval before it
    (sensors/pooling.py), so that they stand for a full interval:

    - exactly: the outlet's closing mass flow is the mass it removed over the closing sample's
      ``sample_interval`` (its own 1.89 ms and the interval before), from the cumulative
      outlet mass, to round-off; the regular samples cover one interval each;
    - the plain mean of the mid plane's and the outlet's flow over the last 0.2 s (10 regular
      samples and the closing one) is the 0.2 kg/s feed within 7 %: the spheres fall apart,
      so the window holds 30.6 spheres' worth of flow and the count is off by at most one
      sphere in the window and one in the pooled sample (2 x 1.31 g / (0.2 kg/s x 0.2 s) =
      6.5 %). Unpooled, the 1.89 ms sample reads 0 kg/s or 3.5 x the feed (0 or 1 sphere),
      moving the mean by -9 % or +23 %.
    - the residence-time statistics of the closing sample are those of the records closed in
      both intervals, its count given per interval."""
    dt = 3e-5
    every = 667                                   # round(0.02 / dt)
    end = (60 * every + 63) * dt
    sim = td.Simulation.from_text(scene(rate='"0.2 kg/s"', end=end).replace(
        "dt = 5e-5", f"dt = {dt}"), arch="cpu")
    sim.run(end)
    assert sim.sample_now()
    s = sim.series
    t, covered = s["time"], s["sample_interval"]
    nominal = every * dt
    assert t[-1] - t[-2] == pytest.approx(63 * dt)
    assert covered[-1] == pytest.approx(nominal + 63 * dt)
    assert np.allclose(covered[1:-1], nominal) and covered[0] == 0.0
    removed = s["outlets/drain/mass"]
    want = (removed[-1] - removed[-3]) / (t[-1] - t[-3])
    assert s["outlets/drain/mass_flow"][-1] == pytest.approx(want, rel=1e-12, abs=1e-15)
    # the regular samples: the mass of their own interval
    assert s["outlets/drain/mass_flow"][-2] == pytest.approx(
        (removed[-2] - removed[-3]) / (t[-2] - t[-3]), rel=1e-12, abs=1e-15)
    window = t >= t[-1] - 0.2 - 1e-9
    assert window.sum() == 11
    sphere = 4 / 3 * math.pi * 0.005 ** 3 * 2500.0
    for name in ("sensors/mid/mass_flow", "outlets/drain/mass_flow"):
        mean = float(np.mean(s[name][window]))
        assert mean == pytest.approx(0.2, rel=0.07), (name, mean)
        # the closing sample itself: the feed within one sphere over what it covers
        assert abs(s[name][-1] - 0.2) <= sphere / covered[-1] + 1e-12, (name, s[name][-1])
    rec = sim.sensors["residence"].records("res")
    late = rec[rec[:, 2] > t[-3] + 1e-12]
    assert len(late) > 0
    assert s["sensors/res/mean"][-1] == pytest.approx(float(np.mean(late[:, 2] - late[:, 1])))
    assert s["sensors/res/count"][-1] == pytest.approx(len(late) * nominal / covered[-1])
    sim.close()
