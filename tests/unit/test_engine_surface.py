"""The engine's user-facing surface: effects composed from the scene (only what it enables is
allocated and compiled), several simulations in one process, the HDF5 names of CONTRACT.md,
and the command line's exit codes and messages."""
import subprocess
import sys

import h5py
import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.effects import effect_names
from taichi_dem.scene.loader import parse_scene

from conftest import PLATE_SCENE, ROOT


def test_effects_follow_the_scene(small_scene_text):
    with_rolling = effect_names(parse_scene(small_scene_text(rolling=0.05)))
    without = effect_names(parse_scene(small_scene_text(rolling=0.0)))
    assert "rolling_constant_torque" in with_rolling and "plane_walls" in with_rolling
    assert "rolling_constant_torque" not in without
    assert "rolling_epsd" not in with_rolling


def test_disabled_effects_allocate_nothing(small_scene_text):
    # no EPSD: no rolling history anywhere; walls: a wall history per particle and wall
    with td.Simulation.from_text(small_scene_text(rolling=0.05)) as sim:
        assert sim.engine.pairs.rolling_history is None
        assert not hasattr(sim.engine.state, "wall_rolling_history")
        assert sim.engine.state.wall_tangential_history.shape == (sim.engine.state.capacity, 1)
    text = small_scene_text(rolling=0.05).replace("rolling_friction = 0.05",
                                                  "rolling_friction = 0.05\nmodel = \"epsd\"")
    with td.Simulation.from_text(text) as sim:
        assert sim.engine.pairs.rolling_history is not None
        assert "rolling_epsd" in sim.engine.model.effect_names


def test_two_simulations_in_one_process_do_not_interfere(small_scene_text):
    """Stepping two simulations alternately gives what each gives alone (f64, one process)."""
    text = small_scene_text()
    with td.Simulation.from_text(text) as alone:
        alone.step(300)
        reference = alone.particles()["position"]
    a = td.Simulation.from_text(text)
    b = td.Simulation.from_text(text.replace("count = 200", "count = 150"))
    try:
        for _ in range(3):
            a.step(100)
            b.step(100)
        assert np.array_equal(a.particles()["position"], reference)
        assert b.particle_count == 150
    finally:
        a.close()
        b.close()


FRESH_RUNTIME_SCRIPT = r'''
import sys
import numpy as np
import taichi_dem as td
from taichi_dem.engine import backend

text = open(sys.argv[1]).read()


def first_field_number(sim):
    """The number Taichi gave the simulation's first field (its kernels' cache keys name it)."""
    return next(iter(sim.engine.trees[0].fields.values())).snode._id


with td.Simulation.from_text(text) as first:
    first.step(50)
    reference = first.particles()["position"]
    number = first_field_number(first)
    generation = backend.generation()
closed = first
with td.Simulation.from_text(text) as second:
    assert backend.generation() == generation + 1, "a fresh runtime"
    assert first_field_number(second) == number, "the same kernel-cache keys"
    with td.Simulation.from_text(text) as third:            # shares the live runtime
        assert backend.generation() == generation + 1
        assert first_field_number(third) != number
        third.step(50)
        assert np.array_equal(third.particles()["position"], reference)
    second.step(50)
    assert np.array_equal(second.particles()["position"], reference)
try:
    closed.step(1)
    raise AssertionError("a closed simulation stepped")
except td.StaleSimulationError as err:
    assert "closed" in str(err)
# a simulation dropped without close() is garbage, not alive: the next one starts afresh
dropped = td.Simulation.from_text(text)
generation = backend.generation()
del dropped
with td.Simulation.from_text(text) as after:
    assert backend.generation() == generation + 1, "a fresh runtime after a dropped one"
    after.step(50)
    assert np.array_equal(after.particles()["position"], reference)
print("fresh runtime: ok")
'''


def test_a_simulation_alone_gets_a_fresh_runtime_and_its_cached_kernels(tmp_path, small_scene_text):
    """With no other simulation alive, a new one starts a fresh Taichi runtime: its fields get
    the numbers an identical scene got before, so its kernels are found in Taichi's cache
    instead of compiled again. While another lives, the runtime is shared and both work.
    In a child process: in this worker a simulation of another test may still be alive (held
    by a traceback, a fixture), which rightly keeps the runtime shared."""
    scene = tmp_path / "small.toml"
    scene.write_text(small_scene_text())
    script = tmp_path / "fresh.py"
    script.write_text(FRESH_RUNTIME_SCRIPT)
    out = subprocess.run([sys.executable, str(script), str(scene)], capture_output=True,
                         text=True, timeout=300, check=False, cwd=ROOT)
    assert "fresh runtime: ok" in out.stdout, out.stdout + out.stderr


def test_hdf5_results_follow_the_contract(tmp_path, small_scene_text):
    path = tmp_path / "r.h5"
    with td.Simulation.from_text(small_scene_text(), h5=str(path)) as sim:
        sim.run(0.02)
        n_samples = len(sim.series["time"])
    with h5py.File(path) as f:
        for key in ("taichi_dem_version", "scene", "dt", "arch", "precision"):
            assert key in f.attrs
        assert f["series/time"].shape == (n_samples,)
        assert f["series/particles/count"][-1] == 200
        assert f["series/particles/kinetic_energy"].shape == (n_samples,)
        assert f["series/walls/floor/force"].shape == (n_samples, 3)
        last = f[f"frames/{n_samples - 1}"]
        assert last.attrs["time"] == pytest.approx(f["series/time"][-1])
        assert last["position"].shape == (200, 3)
        assert sorted(last["id"][:]) == list(range(200))


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "taichi_dem", *args], capture_output=True,
                          text=True, cwd=cwd or ROOT, timeout=600)


@pytest.mark.parametrize("edit, key", [
    ("restitution = 0.5", "restitution = 1.5"),
    ("poisson_ratio = 0.25", "poisson_ratio = 0.7"),
    ("radius = 0.004", "radius = -0.004"),
    ("end_time = 0.02", "end_tme = 0.02"),
    ("count = 200", "count = 200000"),
    ("end_time = 0.02", "end_time = 0.02\ndt = 0.01"),
])
def test_bad_input_exits_2_with_one_paragraph(tmp_path, small_scene_text, edit, key):
    text = small_scene_text().replace(edit, key, 1)
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    r = _cli("check", str(scene))
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    assert str(scene) in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_missing_interaction_pair_is_named(tmp_path, small_scene_text):
    text = small_scene_text()
    cut = text.index("[[interactions]]", text.index("[[interactions]]") + 1)
    text = text[:cut] + text[text.index("[[particles]]"):]
    scene = tmp_path / "missing.toml"
    scene.write_text(text)
    r = _cli("check", str(scene))
    assert r.returncode == 2 and "glass" in r.stderr and "steel" in r.stderr
    assert "Traceback" not in r.stderr


def test_check_prints_effects_and_derived_figures():
    r = _cli("check", "demos/pile.toml")
    assert r.returncode == 0, r.stderr
    for text in ("hertz_mindlin", "plane_walls", "Rayleigh time", "time step", "memory",
                 "particles: 3000"):
        assert text in r.stdout


def test_run_writes_results(tmp_path, small_scene_text):
    scene = tmp_path / "ok.toml"
    scene.write_text(small_scene_text())
    r = _cli("run", str(scene), "--out", str(tmp_path / "out"), "--quiet", "--until", "0.01")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "out" / "ok.h5").exists()



def test_speed_schedule_and_set_speed(tmp_path):
    """The schedule switches at its times, set_speed between steps takes over from then on,
    the angle stays continuous, and the HDF5 holds the body series of CONTRACT.md."""
    path = tmp_path / "b.h5"
    with td.Simulation.from_text(PLATE_SCENE, h5=str(path)) as sim:
        sim.run(0.1)
        kin = sim.engine.kinematics
        assert kin.speed(0, 0.02) == 0.0
        assert kin.speed(0, 0.06) == pytest.approx(6 * 2 * np.pi / 60)
        t_set = sim.time
        before = kin.angle(0, t_set)
        sim.set_speed("paddle", "-12 rpm")
        assert kin.angle(0, sim.time) == pytest.approx(before)
        sim.run(0.2)
        w = sim.series["bodies/paddle/angular_speed"]
        assert w[-1] == pytest.approx(-12 * 2 * np.pi / 60)
        assert kin.angle(0, 0.2) == pytest.approx(before - (0.2 - t_set) * 12 * 2 * np.pi / 60)
        with pytest.raises(td.SceneError):
            sim.set_speed("nothing", "1 rpm")
    with h5py.File(path) as f:
        for name in ("force", "torque", "axial_torque", "power", "angular_speed"):
            assert f"series/bodies/paddle/{name}" in f
        assert f["series/bodies/paddle/torque"].shape[1] == 3


def test_check_lists_bodies(tmp_path):
    scene = tmp_path / "plate.toml"
    scene.write_text(PLATE_SCENE)
    r = _cli("check", str(scene))
    assert r.returncode == 0, r.stderr
    assert "mesh_contact" in r.stdout and "body paddle" in r.stdout and "fastest body surface" in r.stdout
