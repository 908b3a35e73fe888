"""[[bodies]] in the scene TOML: meshes through geometry/, motion, temperature, validation."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from taichi_dem.scene.loader import parse_scene
from taichi_dem.errors import SceneError
from taichi_dem.scene.model import Body, SpeedSchedule

ROOT = Path(__file__).resolve().parents[2]
RPM = 2.0 * math.pi / 60.0

HEAD = """
[simulation]
end_time = 1.0

[domain]
min = [-0.2, -0.6, -0.6]
max = [3.2, 0.6, 0.6]
periodic = {periodic}

[materials.ash]
density = 870.0
youngs_modulus = 1.1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5

{steel_pair}

[[particles]]
material = "ash"
radius = 0.01
count = 10
region = {{ box = {{ min = [0.5, -0.2, -0.2], max = [1.5, 0.2, 0.2] }} }}
"""

STEEL_PAIR = """[[interactions]]
pair = ["ash", "steel"]
restitution = 0.6
friction = 0.5
"""

DRUM = """
[[bodies]]
name = "drum"
material = "steel"
mesh = { builder = "drum", radius = 0.5, length = 3.0, flights = 6, flight_height = 0.08 }
"""


def scene(bodies: str, *, steel_pair: bool = True, periodic: str = "[]"):
    text = HEAD.format(periodic=periodic, steel_pair=STEEL_PAIR if steel_pair else "") + bodies
    return parse_scene(text, source="scene.toml", base_dir=ROOT)


def error(bodies: str, key: str, *fragments, **kw) -> SceneError:
    with pytest.raises(SceneError) as e:
        scene(bodies, **kw)
    err = e.value
    assert err.file == "scene.toml"
    assert err.key == key, f"key {err.key!r} != {key!r}: {err}"
    for frag in fragments:
        assert frag in err.reason, f"{frag!r} not in {err.reason!r}"
    return err


# --- what loads ---------------------------------------------------------------------------------

def test_drum_with_rotation_loads():
    s = scene(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [2, 0, 0], '
                     'speed = "10 rpm" } }\ntemperature = "27 C"\n')
    assert len(s.bodies) == 1
    b = s.bodies[0]
    assert isinstance(b, Body) and b.key == "bodies[0]" and b.name == "drum"
    assert b.material == "steel"
    assert b.vertices.dtype == np.float64 and b.vertices.ndim == 2 and b.vertices.shape[1] == 3
    assert np.issubdtype(b.faces.dtype, np.integer) and b.faces.shape[1] == 3
    assert len(b.faces) > 0 and b.faces.max() < len(b.vertices) and b.faces.min() >= 0
    # the drum shell has radius 0.5 about +x, from x = 0 to 3
    r = np.hypot(b.vertices[:, 1], b.vertices[:, 2])
    assert r.max() == pytest.approx(0.5, rel=1e-6)
    assert b.vertices[:, 0].min() == pytest.approx(0.0, abs=1e-9)
    assert b.vertices[:, 0].max() == pytest.approx(3.0, rel=1e-9)
    m = b.motion
    assert m.axis_point == (0.0, 0.0, 0.0) and m.axis_direction == (1.0, 0.0, 0.0)
    assert isinstance(m.speed, SpeedSchedule)
    assert m.speed.points == ((0.0, pytest.approx(10 * 2 * math.pi / 60)),)
    assert m.speed.at(5.0) == pytest.approx(10 * RPM)
    assert m.velocity == (0.0, 0.0, 0.0)
    assert b.temperature == pytest.approx(300.15)


def test_body_without_motion_is_static():
    b = scene(DRUM).bodies[0]
    assert b.motion.speed is None and b.motion.velocity == (0.0, 0.0, 0.0)
    assert b.temperature is None


def test_speed_schedule_in_si():
    s = scene(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], '
                     'speed = [[0.0, "10 rpm"], ["0.5 min", "20 rpm"], [60, 1.5]] } }\n')
    sp = s.bodies[0].motion.speed
    assert len(sp.points) == 3
    assert sp.points[0] == (0.0, pytest.approx(10 * RPM))
    assert sp.points[1] == (pytest.approx(30.0), pytest.approx(20 * RPM))
    assert sp.points[2] == (pytest.approx(60.0), pytest.approx(1.5))
    assert sp.at(29.0) == pytest.approx(10 * RPM) and sp.at(45.0) == pytest.approx(20 * RPM)


def test_rotate_axis_defaults_to_the_builder_axis():
    s = scene('\n[[bodies]]\nname = "shaft"\nmaterial = "steel"\n'
              'mesh = { builder = "paddle_shaft", length = 3.0, shaft_radius = 0.05, rows = 4, '
              'paddles_per_row = 2, paddle_length = 0.2, paddle_width = 0.1, '
              'origin = [0, 0.1, 0] }\n'
              'motion = { rotate = { speed = "5 rpm" }, translate = { velocity = [0, 0, 0.1] } }\n')
    m = s.bodies[0].motion
    assert m.axis_point == pytest.approx((0.0, 0.1, 0.0))
    assert m.axis_direction == pytest.approx((1.0, 0.0, 0.0))
    assert m.speed.points[0][1] == pytest.approx(5 * RPM)
    assert m.velocity == pytest.approx((0.0, 0.0, 0.1))


def test_list_of_meshes_merges_into_one_body():
    from taichi_dem import geometry
    a = {"builder": "paddle_shaft", "length": 3.0, "shaft_radius": 0.05, "start": 1.0,
         "rows": 4, "paddles_per_row": 2, "paddle_length": 0.2, "paddle_width": 0.1}
    b = {"builder": "screw", "length": 0.9, "shaft_radius": 0.05, "outer_radius": 0.25,
         "pitch": 0.3, "include_shaft": False}
    fa = geometry.build_mesh(a).n_faces
    fb = geometry.build_mesh(b).n_faces
    s = scene('\n[[bodies]]\nname = "shaft"\nmaterial = "steel"\nmesh = [\n'
              '  { builder = "paddle_shaft", length = 3.0, shaft_radius = 0.05, start = 1.0, '
              'rows = 4, paddles_per_row = 2, paddle_length = 0.2, paddle_width = 0.1 },\n'
              '  { builder = "screw", length = 0.9, shaft_radius = 0.05, outer_radius = 0.25, '
              'pitch = 0.3, include_shaft = false },\n]\n')
    body = s.bodies[0]
    assert len(body.faces) == fa + fb
    assert body.faces.max() == len(body.vertices) - 1


def test_mesh_outside_domain_allowed_on_periodic_axis():
    # x runs from -0.2 to 3.2: a 5 m drum is far beyond it, but x is periodic
    s = scene(DRUM.replace("length = 3.0", "length = 5.0"), periodic='["x"]')
    assert s.bodies[0].vertices[:, 0].max() == pytest.approx(5.0)


def test_mesh_slightly_beyond_domain_within_margin_loads():
    # the domain's y extent is 1.2 m; 10 % is 0.12 m, so a radius 0.65 drum still fits
    scene(DRUM.replace("radius = 0.5", "radius = 0.65"))


# --- errors -------------------------------------------------------------------------------------

def test_unknown_builder():
    error('\n[[bodies]]\nname = "d"\nmaterial = "steel"\nmesh = { builder = "dum", radius = 0.5 }\n',
          "bodies[0].mesh.builder", "unknown builder", "'drum'")


def test_bad_builder_parameter_names_the_key():
    error(DRUM.replace("flight_height", "flight_hieght"), "bodies[0].mesh.flight_hieght",
          "flight_height")


def test_missing_interaction_for_body_material():
    error(DRUM, "interactions", "('ash', 'steel')", "body 'drum'", steel_pair=False)


def test_schedule_times_must_increase():
    error(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], '
                 'speed = [[0.0, "10 rpm"], [30.0, "20 rpm"], [20.0, "5 rpm"]] } }\n',
          "bodies[0].motion.rotate.speed[2][0]", "must increase")


def test_schedule_must_start_at_zero():
    error(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], '
                 'speed = [[5.0, "10 rpm"], [30.0, "20 rpm"]] } }\n',
          "bodies[0].motion.rotate.speed[0][0]", "start at time 0")


def test_schedule_entry_shape_and_dimension():
    error(DRUM + 'motion = { rotate = { speed = [[0.0, "10 rpm", 3]] } }\n',
          "bodies[0].motion.rotate.speed[0]", "[start time, angular speed]")
    error(DRUM + 'motion = { rotate = { speed = [[0.0, "10 m"]] } }\n',
          "bodies[0].motion.rotate.speed[0][1]")
    error(DRUM + 'motion = { rotate = { speed = "10 m/s" } }\n',
          "bodies[0].motion.rotate.speed", "angular speed")


def test_zero_axis_direction():
    error(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [0, 0, 0], '
                 'speed = "10 rpm" } }\n',
          "bodies[0].motion.rotate.axis_direction", "nonzero")


def test_duplicate_body_name():
    error(DRUM + DRUM, "bodies[1].name", "duplicate", "'drum'", "bodies[0]")


def test_body_name_clashes_with_wall():
    wall = ('\n[[walls]]\nname = "drum"\nmaterial = "steel"\n'
            'plane = { point = [0, 0, -0.5], normal = [0, 0, 1] }\n')
    error(wall + DRUM, "bodies[0].name", "duplicate", "walls[0]")


def test_unknown_key_in_motion():
    error(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], '
                 'sped = "10 rpm" } }\n',
          "bodies[0].motion.rotate.sped", "unknown key 'sped'", "did you mean 'speed'")
    error(DRUM + 'motion = { rotation = { speed = "10 rpm" } }\n',
          "bodies[0].motion.rotation", "unknown key", "did you mean 'rotate'")


def test_unknown_and_missing_body_keys():
    error(DRUM + "temprature = 300.0\n", "bodies[0].temprature", "did you mean 'temperature'")
    error('\n[[bodies]]\nname = "d"\nmaterial = "steel"\n', "bodies[0].mesh",
          "required key is missing")
    error(DRUM.replace('"steel"', '"steal"'), "bodies[0].material", "unknown material",
          "did you mean 'steel'")


def test_rotate_needs_speed():
    error(DRUM + 'motion = { rotate = { axis_point = [0, 0, 0] } }\n',
          "bodies[0].motion.rotate.speed", "required")


def test_file_mesh_rotation_needs_an_axis(tmp_path):
    from taichi_dem import geometry
    import trimesh
    m = geometry.build("box", {"min": [0.0, -0.1, -0.1], "max": [0.5, 0.1, 0.1]})
    trimesh.Trimesh(m.vertices, m.faces, process=False).export(tmp_path / "part.stl")
    text = HEAD.format(periodic="[]", steel_pair=STEEL_PAIR) + (
        '\n[[bodies]]\nname = "part"\nmaterial = "steel"\nmesh = { file = "part.stl" }\n'
        'motion = { rotate = { axis_direction = [1, 0, 0], speed = "10 rpm" } }\n')
    with pytest.raises(SceneError) as e:
        parse_scene(text, source="scene.toml", base_dir=tmp_path)
    assert e.value.key == "bodies[0].motion.rotate.axis_point"
    s = parse_scene(text.replace("{ axis_direction", "{ axis_point = [0, 0, 0], axis_direction"),
                    source="scene.toml", base_dir=tmp_path)
    assert len(s.bodies[0].faces) == 12


def test_mesh_outside_domain():
    error(DRUM.replace("length = 3.0", "length = 5.0"), "bodies[0].mesh",
          "mesh lies outside the domain", "on x")


# --- command line -------------------------------------------------------------------------------

def test_check_builders_lists_the_builders():
    r = subprocess.run([sys.executable, "-m", "taichi_dem", "check", "--builders"],
                       capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "drum" in r.stdout and "paddle_shaft" in r.stdout
    assert "none yet" not in r.stdout
