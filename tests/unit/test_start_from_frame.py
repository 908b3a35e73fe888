"""Start a changed scene from a settled state (issue 33 item 5): a fill whose ``file`` is an
earlier run's results file takes the particles of its material from a frame - positions,
radii, velocities, spins, temperatures - while the bodies, walls and settings come from the new
scene. Bad input is refused with file: key: reason."""
import numpy as np
import pytest

import taichi_dem as td
from resume_scene import scene_text
from taichi_dem.errors import SceneError
from taichi_dem.scene.loader import parse_scene

FILL = """[[particles]]
material = "glass"
radius = 0.004
count = 300
temperature = 400.0
region = { box = { min = [-0.05, -0.05, -0.053], max = [0.05, 0.05, 0.05] } }
"""


def _from(text: str, h5, extra: str = "") -> str:
    assert FILL in text
    return text.replace(FILL, f'[[particles]]\nmaterial = "glass"\nfile = "{h5}"\n{extra}')


@pytest.fixture(scope="module")
def settled(tmp_path_factory):
    """The first run: 300 hot beads fall onto the floor for 0.04 s; its results file."""
    h5 = tmp_path_factory.mktemp("settle") / "settle.h5"
    with td.Simulation.from_text(scene_text(), h5=str(h5)) as sim:
        sim.run(0.04)
    return h5


def test_a_changed_scene_starts_from_the_last_frame(settled):
    import h5py
    with h5py.File(settled, "r") as f:
        keys = sorted(f["frames"], key=int)
        last = {k: f["frames"][keys[-1]][k][()] for k in f["frames"][keys[-1]]
                if k != "bodies"}
        first = f["frames"][keys[0]]["position"][()]
    assert not np.allclose(last["temperature"], 400.0)        # the beads have cooled unevenly
    # the new case: the paddle turns twice as fast; the particles are the settled ones
    text = _from(scene_text(speed="120 rpm"), settled)
    with td.Simulation.from_text(text) as sim:
        p = sim.particles()
        assert len(p["id"]) == len(last["id"])
        for name in ("position", "velocity", "angular_velocity", "radius", "temperature"):
            np.testing.assert_array_equal(p[name], last[name], err_msg=name)
        assert sim.scene.bodies[0].motion.speed.at(0.0) == pytest.approx(4 * np.pi)
        assert sim.time == 0.0
        sim.step(20)                                          # and it runs
        assert np.all(np.isfinite(sim.particles()["position"]))
    # frame = 0: the first frame, as the beads were placed
    with td.Simulation.from_text(_from(scene_text(), settled, "frame = 0\n")) as sim:
        np.testing.assert_array_equal(sim.particles()["position"], first)


def test_a_given_temperature_overrides_the_frames(settled):
    text = _from(scene_text(), settled, "temperature = 350.0\n")
    with td.Simulation.from_text(text) as sim:
        assert np.all(sim.particles()["temperature"] == 350.0)


@pytest.mark.parametrize("extra, key, words", [
    ("frame = 99\n", "particles[0].frame", "no such frame"),
    ("frame = -99\n", "particles[0].frame", "no such frame"),
])
def test_bad_frames_are_refused(settled, extra, key, words):
    with pytest.raises(SceneError) as err:
        parse_scene(_from(scene_text(), settled, extra))
    assert err.value.key == key and words in str(err.value)


def test_other_bad_sources_are_refused(settled, tmp_path):
    cases = [
        (_from(scene_text(), tmp_path / "none.h5"), "particles[0].file", "not found"),
        (_from(scene_text(), settled).replace('material = "glass"\nfile', 'material = "steel"\nfile'),
         "particles[0].file", "no particles of material 'steel'"),
    ]
    csv = tmp_path / "beads.csv"
    csv.write_text("x,y,z,radius\n0,0,0,0.004\n")
    cases.append((_from(scene_text(), csv, "frame = 1\n"), "particles[0].frame", "results file"))
    empty = tmp_path / "empty.h5"
    import h5py
    with h5py.File(empty, "w") as f:
        f.create_group("series")
    cases.append((_from(scene_text(), empty), "particles[0].file", "no particle frames"))
    for text, key, words in cases:
        with pytest.raises(SceneError) as err:
            parse_scene(text)
        assert err.value.key == key and words in str(err.value), str(err.value)


def test_a_checkpoint_is_a_settled_state_too(tmp_path):
    """A checkpoint file as the source: the alive particles as the engine held them."""
    path = tmp_path / "settle.checkpoint.h5"
    with td.Simulation.from_text(scene_text()) as sim:
        sim.run(0.02)
        sim.checkpointer.path = str(path)
        sim.checkpointer.save(sim=sim)
        want = sim.particles()
    with td.Simulation.from_text(_from(scene_text(speed="0 rpm"), path)) as sim:
        got = sim.particles()
        for name in ("position", "velocity", "angular_velocity", "radius", "temperature"):
            np.testing.assert_array_equal(got[name], want[name], err_msg=name)
