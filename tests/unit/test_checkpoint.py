"""Divergence checks through the API (a speed, a NaN and an overlap injected just before an
output sample), the last good state they leave, the atomic checkpoint write, and a resume
that starts a new results file."""
import dataclasses
import os

import h5py
import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.run import checkpoint
from taichi_dem.errors import DivergenceError


@pytest.fixture(scope="module")
def small_text():
    from tests.conftest import SMALL_SCENE
    return SMALL_SCENE.format(precision="f64", rolling=0.05, count=200)


def to_sample_minus_one(sim):
    """Advance to one step before the next output sample."""
    sim.step(sim.output_every - sim.step_count % sim.output_every - 1)


def diverge(sim, inject):
    """Inject into the state one step before a sample; return the error and the time of the
    last good sample."""
    sim.run(0.01)
    to_sample_minus_one(sim)
    t_good = float(sim.series["time"][-1])
    inject(sim.engine.state)
    with pytest.raises(DivergenceError) as info:
        sim.step(1)
    return str(info.value), t_good, info.value


def test_speed_beyond_the_bound_stops_with_the_particle_and_the_last_good_state(small_text, tmp_path):
    sim = td.Simulation.from_text(small_text, h5="")
    sim.checkpointer.path = str(tmp_path / "s.checkpoint.h5")
    sim.checkpointer.keep_last_good = True           # as the CLI does
    limit = sim.divergence.speed_limit
    assert limit == pytest.approx(10 * sim.timestep.expected_speed)
    pid = None

    def inject(s):
        nonlocal pid
        pid = int(s.particle_id[7])
        # 3x the limit: the particle moves ~3e-4 m in the one step and stays in the domain
        s.velocity[7] = [3 * limit, 0.0, 0.0]
    message, t_good, err = diverge(sim, inject)
    assert f"particle {pid} at (" in message and "moves at" in message
    assert "reduce simulation.dt" in message and sim.checkpointer.path in message
    assert err.checkpoint == sim.checkpointer.path
    snap = checkpoint.load(sim.checkpointer.path)
    assert snap.time == pytest.approx(t_good)
    # the last good state does not hold the injected speed
    assert np.max(np.linalg.norm(snap.fields["position"]["velocity"], axis=1)) < limit
    sim.close()

    # it resumes, into a new results file that starts with the series so far
    h5 = tmp_path / "resumed.h5"
    b = td.Simulation.from_checkpoint(sim.checkpointer.path, h5=str(h5))
    assert b.time == pytest.approx(t_good)
    n_before = len(snap.series["time"])
    b.step(2 * b.output_every)
    b.close()
    with h5py.File(h5, "r") as f:
        times = f["series/time"][()]
        assert len(times) == n_before + 2 and np.all(np.diff(times) > 0)
        assert len(f["frames"]) == 2


def test_non_finite_velocity_is_named(small_text, tmp_path):
    sim = td.Simulation.from_text(small_text, h5="")
    sim.checkpointer.path = str(tmp_path / "n.checkpoint.h5")
    assert not sim.checkpointer.keep_last_good      # from Python: off by default
    message, _, err = diverge(sim, lambda s: s.velocity.__setitem__(3, [np.nan, 0.0, 0.0]))
    # the quantity named (issue 43: not "position or velocity"), with its cause
    assert "has a non-finite velocity ([nan" in message and "time step too large" in message
    assert "No checkpoint was written" in message and err.checkpoint == ""
    assert not os.listdir(tmp_path)
    sim.close()


def test_overlap_beyond_the_limit_is_named(small_text, tmp_path):
    sim = td.Simulation.from_text(small_text, h5="")
    sim.checkpointer.path = str(tmp_path / "o.checkpoint.h5")

    def inject(s):
        # put particle 5 0.8 radius into particle 9 (overlap 0.8 r > 0.6 r); the next
        # step rebuilds the list (it moved more than half the skin) and the check sees it
        x9 = s.position[9]
        r = float(s.radius[9])
        s.position[5] = [x9[0] + 1.2 * r, x9[1], x9[2]]
        s.velocity[5] = [0.0, 0.0, 0.0]
    message, _, _ = diverge(sim, inject)
    assert "overlaps a neighbour" in message and "limit 0.6" in message
    ratio = float(message.split("by ")[1].split(" of the")[0])
    # 0.8 r placed; the repulsion moves them apart by ~1e-6 m in the one step
    assert ratio == pytest.approx(0.8, abs=0.02)
    sim.close()


def test_checkpoint_write_is_atomic(small_text, tmp_path):
    sim = td.Simulation.from_text(small_text, h5="")
    path = str(tmp_path / "a.checkpoint.h5")
    sim.checkpointer.path = path
    sim.checkpointer.save(sim=sim)
    before = open(path, "rb").read()

    class Broken:
        def state_dict(self):
            return {"bad/key": 1}          # '/' is refused while writing

        def load_state_dict(self, d):
            pass
    sim.checkpointables["broken"] = Broken()
    sim.step(sim.output_every)
    with pytest.raises(ValueError):
        sim.checkpointer.save(sim=sim)
    # the failed write left the previous checkpoint as it was, and no temporary file
    assert open(path, "rb").read() == before
    assert os.listdir(tmp_path) == ["a.checkpoint.h5"]
    sim.close()


def test_checkpoint_without_the_per_step_sums_restores_them_silently(small_text, capsys):
    """A checkpoint written before the serial mode's scattered_* sums existed lacks them; they
    are zero at every whole step, so they restore as zero with no warning, and the run goes
    on exactly as from a checkpoint that holds them. Any other missing field is still named."""
    with td.Simulation.from_text(small_text) as sim:
        sim.step(300)
        full = checkpoint.capture(sim)
    assert "scattered_force" in full.fields["position"]
    old = dataclasses.replace(full, fields={
        label: {n: a for n, a in arrays.items() if not n.startswith("scattered_")}
        for label, arrays in full.fields.items()})
    ends = []
    for snap in (full, old):
        with td.Simulation.from_text(small_text) as sim:
            capsys.readouterr()
            checkpoint.restore(sim, snap)
            assert "warning" not in capsys.readouterr().err
            sim.step(200)
            ends.append(sim.particles()["velocity"])
    assert np.array_equal(ends[0], ends[1])
    gone = dataclasses.replace(full, fields={
        label: {n: a for n, a in arrays.items() if n != "owned_force"}
        for label, arrays in full.fields.items()})
    with td.Simulation.from_text(small_text) as sim:
        capsys.readouterr()
        checkpoint.restore(sim, gone)
        assert "position/owned_force" in capsys.readouterr().err


def test_checkpoint_with_fewer_slots_restores_into_the_first(small_text):
    """A checkpoint written before the particle slots came in buckets holds the scene's own
    count of slots: its per-slot rows fill the first slots and the run goes on exactly as from
    a checkpoint of the bucket. One with more slots than the scene allocates is refused."""
    import json
    with td.Simulation.from_text(small_text) as sim:
        sim.step(300)
        full = checkpoint.capture(sim)
        slots, used = sim.engine.state.capacity, sim.engine.model.particle_limit
    assert used < slots            # (the scene's 200 in a bucket of 256)
    caps = json.loads(full.attrs["capacities"])

    def cut(a):
        if a.ndim and a.shape[0] in (slots, slots + 1):
            return a[: a.shape[0] - (slots - used)].copy()
        return a
    old = dataclasses.replace(
        full, fields={label: {n: cut(a) for n, a in arrays.items()}
                      for label, arrays in full.fields.items()},
        attrs=dict(full.attrs, capacities=json.dumps(dict(caps, particles=used))))
    assert old.fields["position"]["position"].shape[0] == used
    ends = []
    for snap in (full, old):
        with td.Simulation.from_text(small_text) as sim:
            checkpoint.restore(sim, snap)
            sim.step(200)
            ends.append(sim.particles()["velocity"])
    assert np.array_equal(ends[0], ends[1])
    more = dataclasses.replace(full, attrs=dict(full.attrs, capacities=json.dumps(
        dict(caps, particles=slots + 1))))
    with td.Simulation.from_text(small_text) as sim:
        with pytest.raises(td.CheckpointError, match="particle slots"):
            checkpoint.restore(sim, more)
