"""[[sensors]] kind = "contact_statistics" (issue 48 item 1): contacts, normal forces and
normal speeds per pair kind, against Hertz's F = 4/3 E* sqrt(R*) d^(3/2) for overlaps set
exactly in the initial state (no gravity, f64: the state at t = 0 is the placed one).

Two spheres of radius r overlap by d = 2e-5 m (R* = r/2); a third sphere sits on a plane wall,
overlapping it by 1e-5 m (R* = r) and moving into it at 0.1 m/s; a fourth rests on a box body
(a steel plate) and is read after one step, by the overlap the mesh contacts hold. Two
fixed spheres overlapping each other and the wall exert no force (the step leaves them out)
and are not counted. Each force
agrees with Hertz to round-off (the overlaps are differences of coordinates near 1e-2 m:
relative 1e-10 in f64), and a wrong E*, R* or exponent errs by order 1.
"""
import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.scene.loader import parse_scene
import dem_helpers as h

R = 0.005
E, NU = 1.0e7, 0.25
E_STEEL, NU_STEEL = 2.0e11, 0.3


def _scene(tmp_path):
    gap = 2.0 * R - 2e-5
    positions = [[0.0, 0.0, 0.05], [gap, 0.0, 0.05], [0.03, 0.0, R - 1e-5]]
    velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -0.1]]
    return (h.header(dt=1e-6, lo=(-0.05, -0.05, 0.0), hi=(0.1, 0.05, 0.1), output_interval=1e-3)
            + h.material("glass", 2500.0, E, NU) + h.material("steel", 7800.0, E_STEEL, NU_STEEL)
            + h.all_interactions(["glass", "steel"])
            + h.csv_fill(tmp_path, "beads.csv", "glass", positions, R, velocities=velocities)
            + h.csv_fill(tmp_path, "fixed.csv", "glass", [[-0.03, 0.0, R - 1e-5],
                                                           [-0.03 + gap, 0.0, R - 1e-5]], R)
            .replace("[[particles]]\n", "[[particles]]\nfixed = true\n")
            + h.wall("floor", [0, 0, 0], [0, 0, 1], "steel")
            + '[[sensors]]\nkind = "contact_statistics"\nname = "contacts"\n')


def test_pairs_and_walls_against_hertz(tmp_path):
    with taichi_dem.Simulation.from_text(_scene(tmp_path), base_dir=str(tmp_path)) as sim:
        measured = sim.sensors["contact_statistics"].measure()
    e_pair = h.youngs_eff(E, NU)
    pair = 4.0 / 3.0 * e_pair * math.sqrt(R / 2) * (2e-5) ** 1.5
    assert measured["particle"]["contacts"] == 1
    assert measured["particle"]["normal_force_max"] == pytest.approx(pair, rel=1e-6)
    assert measured["particle"]["normal_speed_max"] == 0.0
    e_wall = h.youngs_eff(E, NU, E_STEEL, NU_STEEL)
    wall = 4.0 / 3.0 * e_wall * math.sqrt(R) * (1e-5) ** 1.5
    assert measured["wall"]["contacts"] == 1
    assert measured["wall"]["normal_force_mean"] == pytest.approx(wall, rel=1e-6)
    assert measured["wall"]["normal_speed_max"] == pytest.approx(0.1, rel=1e-9)
    assert measured["body"]["contacts"] == 0


def test_a_body_contact_and_the_series(tmp_path):
    plate = ('[[bodies]]\nname = "plate"\nmaterial = "steel"\nmesh = { builder = "box", '
             'min = [0.055, -0.02, 0.01], max = [0.095, 0.02, 0.02] }\n\n')
    text = _scene(tmp_path).replace("[[sensors]]", plate + h.csv_fill(
        tmp_path, "rest.csv", "glass", [[0.075, 0.0, 0.02 + R - 1e-5]], R) + "[[sensors]]")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path)) as sim:
        sim.step(1)
        measured = sim.sensors["contact_statistics"].measure()
        sim.sample_now()
        series = {k: np.asarray(v) for k, v in sim.series.items() if k.startswith("sensors/")}
    assert measured["body"]["contacts"] == 1
    e_body = h.youngs_eff(E, NU, E_STEEL, NU_STEEL)
    # after one step of 1e-6 s at rest the overlap is still 1e-5 m to 1e-12
    body = 4.0 / 3.0 * e_body * math.sqrt(R) * (1e-5) ** 1.5
    assert measured["body"]["normal_force_max"] == pytest.approx(body, rel=1e-5)
    assert series["sensors/contacts/body/contacts"][-1] == 1
    # contacts that exist in the initial state are not collisions (none begins in the step)
    for kind in ("particle", "wall", "body"):
        assert list(series[f"sensors/contacts/{kind}/collisions"]) == [0, 0], kind
    assert series["sensors/contacts/particle/normal_force_p90"][-1] > 0


def test_the_sensor_takes_no_other_key(tmp_path):
    text = _scene(tmp_path).replace('name = "contacts"\n', 'name = "contacts"\nbody = "x"\n')
    with pytest.raises(taichi_dem.SceneError) as e:
        parse_scene(text, source="scene.toml", base_dir=str(tmp_path))
    assert e.value.key.startswith("sensors[0]")
