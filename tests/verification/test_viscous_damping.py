"""[viscous_damping] (effects/viscous_damping/): the worked example of a new effect in
docs/architecture.md, checked against its analytic solution.

A free sphere (no gravity, no contact) under a = -v / tau keeps its direction and slows as
v(t) = v0 exp(-t / tau), and travels x(t) = v0 tau (1 - exp(-t / tau)). The step takes a
velocity-dependent load at the half-step velocity (as it does the contacts' damping), which
is first order for it: the half-step velocity shrinks by (1 - dt/tau) per step against
exp(-dt/tau), a relative error of t dt / (2 tau^2) = 1e-3 after two time constants at
dt / tau = 1e-3. The tolerance is twice that; a wrong law (a sign, a factor, the load applied
twice or not at all) errs by order 1.
"""
import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.errors import SceneError
from taichi_dem.scene.loader import parse_scene
import dem_helpers as h

TAU = 0.02          # s
DT = 2e-5           # s: dt / tau = 1e-3
V0 = np.array([0.3, -0.4, 0.0])     # m/s


def _scene(tmp_path, damping=f"[viscous_damping]\ntime_constant = \"{TAU * 1e3:g} ms\"\n"):
    return (h.header(dt=DT) + h.material("glass", 2500.0, 1e7, 0.25)
            + h.all_interactions(["glass"])
            + h.csv_fill(tmp_path, "one.csv", "glass", [[0.0, 0.0, 0.0]], 0.005, velocities=V0)
            + damping)


def test_a_free_sphere_slows_exponentially(tmp_path):
    with taichi_dem.Simulation.from_text(_scene(tmp_path), base_dir=str(tmp_path)) as sim:
        assert "viscous_damping" in sim.engine.model.effect_names
        steps = int(round(2 * TAU / DT))
        sim.step(steps)
        t = steps * DT
        p = sim.particles()
    decay = math.exp(-t / TAU)
    first_order = t * DT / (2 * TAU ** 2)           # the scheme's relative error, 1e-3
    np.testing.assert_allclose(p["velocity"][0], V0 * decay, rtol=2 * first_order, atol=1e-9)
    np.testing.assert_allclose(p["position"][0], V0 * TAU * (1 - decay), rtol=2 * first_order,
                               atol=1e-9)


def test_off_means_absent(tmp_path):
    scene = parse_scene(_scene(tmp_path, damping=""), base_dir=str(tmp_path))
    assert scene.settings == {}
    from taichi_dem.effects import effect_names
    assert "viscous_damping" not in effect_names(scene)


@pytest.mark.parametrize("value,fragment", [(0.0, "must be > 0"), ("5 m", "is a length"),
                                            ("x", "cannot read")])
def test_bad_values_name_the_key(tmp_path, value, fragment):
    text = _scene(tmp_path, damping=f"[viscous_damping]\ntime_constant = {value!r}\n".replace("'", '"'))
    with pytest.raises(SceneError) as e:
        parse_scene(text, source="scene.toml", base_dir=str(tmp_path))
    assert e.value.key == "viscous_damping.time_constant" and fragment in e.value.reason


def test_unknown_key_is_refused_with_a_suggestion(tmp_path):
    text = _scene(tmp_path, damping="[viscous_damping]\ntime_constnt = 0.1\n")
    with pytest.raises(SceneError) as e:
        parse_scene(text, source="scene.toml", base_dir=str(tmp_path))
    assert e.value.key == "viscous_damping.time_constnt"
    assert "did you mean 'time_constant'" in e.value.reason
