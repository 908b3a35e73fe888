"""[body_force] (effects/body_force/): the worked example of docs/architecture.md, checked
against its analytic solution, its series and its bound.

A free sphere (no gravity, no contact) under a constant acceleration f a moves as
x(t) = x0 + v0 t + f a t^2 / 2. Velocity Verlet integrates a constant acceleration exactly, so
in f64 the position agrees to round-off: 1e-12 m after thousands of steps (a missing factor,
a sign or the force applied twice errs by order 1). A particle a factory inserts starts in
free flight under the force: its velocity is exactly f a (t - t_birth); without the force in
its first acceleration it would lag by f a dt / 2 for good (5e-6 m/s here, 5e4 times the
tolerance).
"""
import h5py
import numpy as np
import pytest

import taichi_dem
from taichi_dem.errors import SceneError
from taichi_dem.scene.loader import parse_scene
import dem_helpers as h

A = np.array([2.0, 0.0, -1.0])      # m/s^2
DT = 1e-5                           # s


def _scene(tmp_path, force=f"[body_force]\nacceleration = {h.vec(A)}\n", factor="0.5",
           lo=(-1, -1, -1), hi=(1, 1, 1), factory=""):
    iron = h.material("iron", 7800.0, 1e7, 0.25)
    if factor is not None:
        iron += f"body_force_factor = {factor}\n\n"
    return (h.header(dt=DT, lo=lo, hi=hi, output_interval=0.01)
            + iron + h.material("glass", 2500.0, 1e7, 0.25)
            + h.all_interactions(["iron", "glass"])
            + h.csv_fill(tmp_path, "iron.csv", "iron", [[0.0, 0.0, 0.0]], 0.005,
                         velocities=[0.1, 0.2, 0.0])
            + h.csv_fill(tmp_path, "glass.csv", "glass", [[0.5, 0.5, 0.5]], 0.005)
            + factory + force)


def test_a_free_sphere_moves_as_f_a_t2_over_2_and_the_series_is_m_f_a(tmp_path):
    h5 = tmp_path / "out.h5"
    with taichi_dem.Simulation.from_text(_scene(tmp_path), base_dir=str(tmp_path),
                                         h5=str(h5)) as sim:
        assert "body_force" in sim.engine.model.effect_names
        sim.run(0.05)
        t = sim.time
        p = sim.particles()
        mass = p["mass"]
    iron, glass = np.argsort(p["position"][:, 1])  # iron starts at the origin, glass at 0.5
    expected = np.array([0.1, 0.2, 0.0]) * t + 0.5 * 0.5 * A * t * t
    np.testing.assert_allclose(p["position"][iron], expected, rtol=0, atol=1e-12)
    # glass has no factor of its own: 1, the declared default
    np.testing.assert_allclose(p["position"][glass], [0.5, 0.5, 0.5] + 0.5 * A * t * t,
                               rtol=0, atol=1e-12)
    with h5py.File(h5, "r") as f:
        series = f["series/body_force/force"]
        assert series.attrs["units"] == "N"
        np.testing.assert_allclose(series[-1], (0.5 * mass[iron] + mass[glass]) * A, rtol=1e-12)


def test_inserted_particles_start_under_the_force(tmp_path):
    factory = """[[factories]]
name = "inlet"
material = "iron"
radius = 0.005
region = { box = { min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5] } }
velocity = [0.0, 0.0, 0.0]
mass_rate = [[0.0, "5 kg/s"]]

"""
    with taichi_dem.Simulation.from_text(_scene(tmp_path, factory=factory),
                                         base_dir=str(tmp_path)) as sim:
        sim.run(0.02)
        s, n = sim.engine.state, sim.engine.count
        alive = s.alive.to_numpy()[:n] != 0
        born = s.birth_time.to_numpy()[:n][alive]
        velocity = s.velocity.to_numpy()[:n][alive]
        origin = s.origin.to_numpy()[:n][alive]
        t = sim.time
    inserted = origin >= 0             # (-1: the initial fills)
    assert inserted.sum() >= 10, "the factory inserted particles"
    age = t - born[inserted]
    np.testing.assert_allclose(velocity[inserted], 0.5 * A * age[:, None], rtol=0, atol=1e-10)


def test_a_fast_push_is_expected_by_the_step_and_the_divergence_guard(tmp_path):
    # 20 m/s^2 for 0.25 s: 5 m/s, in a 2 m box with no gravity. Without the effect's bound the
    # expected speed was 1e-3 m/s and the guard stopped the run at 10x that.
    text = _scene(tmp_path, force="[body_force]\nacceleration = [20.0, 0.0, 0.0]\n",
                  factor="1.0", lo=(-1.0, -1, -1), hi=(2.5, 1, 1))
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path)) as sim:
        assert sim.timestep.expected_speed >= np.sqrt(2 * 20.0 * 3.5)
        sim.run(0.25)
        v = sim.particles()["velocity"]
    assert v[:, 0].max() == pytest.approx(5.0 + 0.1, rel=1e-9)


def test_off_means_absent_and_a_lone_factor_is_refused(tmp_path):
    scene = parse_scene(_scene(tmp_path, force="", factor=None), base_dir=str(tmp_path))
    assert scene.settings == {}
    from taichi_dem.effects import effect_names
    assert "body_force" not in effect_names(scene)
    with pytest.raises(SceneError) as e:
        parse_scene(_scene(tmp_path, force=""), source="scene.toml", base_dir=str(tmp_path))
    assert e.value.key == "materials.iron.body_force_factor"
    assert "[body_force]" in e.value.reason


@pytest.mark.parametrize("force,factor,key,fragment", [
    ("[body_force]\n", "1", "body_force.acceleration", "required"),
    ("[body_force]\nacceleration = [1, 2]\n", "1", "body_force.acceleration", ""),
    ("[body_force]\nacceleraton = [1, 2, 3]\n", "1", "body_force.acceleraton",
     "did you mean 'acceleration'"),
    ("[body_force]\nacceleration = [1, 2, 3]\n", '"x"', "materials.iron.body_force_factor",
     "cannot read"),
])
def test_bad_input_names_the_file_and_key(tmp_path, force, factor, key, fragment):
    with pytest.raises(SceneError) as e:
        parse_scene(_scene(tmp_path, force=force, factor=factor), source="scene.toml",
                    base_dir=str(tmp_path))
    assert e.value.key == key and fragment in e.value.reason
    assert "scene.toml" in str(e.value)
