"""Bad files and bad strings a scene names (issue 43, item 2): a settled-start HDF5 frame
validated like a scene, a NUL byte in a path, TOML nested thousands deep, names with control
characters, a CSV whose error must not echo the file, and divergence messages that name the
quantity that is not finite.

Every bad input exits 2 with ``FILE: KEY: reason`` and no traceback, from ``check`` (which
must not start the Taichi runtime) and from ``run``; a diverged state says which quantity
(position, velocity, angular velocity, temperature, moisture) and the cause for it.
"""
import contextlib
import io
from pathlib import Path

import h5py
import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.errors import DivergenceError

N = 20
RADIUS = 0.004

SCENE = """[simulation]
end_time = 0.01
gravity = [0.0, 0.0, -9.81]

[domain]
min = [-0.1, -0.1, -0.01]
max = [0.1, 0.1, 0.35]

[materials.glass]
density = 2500.0
youngs_modulus = 5.0e7
poisson_ratio = 0.25

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.6
friction = 0.5

[[walls]]
name = "floor"
plane = { point = [0, 0, 0], normal = [0, 0, 1] }
material = "glass"

[[particles]]
material = "glass"
FILL

[output]
interval = 0.005
"""

REGION_FILL = ('radius = 0.004\ncount = 20\n'
               'region = { box = { min = [-0.05, -0.05, 0.01], max = [0.05, 0.05, 0.2] } }')


def cli(*argv) -> tuple:
    """``taichi-dem ARGV`` in-process: (exit status, stderr + stdout). Any exception escaping
    main() is what a user would see as a traceback, and fails the test."""
    from taichi_dem.app.cli import main
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as e:
            rc = e.code
    return rc, err.getvalue() + out.getvalue()


def refused(folder, scene_text, key, *fragments, command="check"):
    """Write ``scene_text`` to FOLDER/scene.toml, run ``command`` on it and check the contract:
    exit 2, no traceback, ``scene.toml: KEY:`` and each fragment in the message."""
    scene = folder / "scene.toml"
    scene.write_text(scene_text)
    argv = [command, scene] + (["--quiet", "--out", folder / "out"] if command == "run" else [])
    rc, message = cli(*argv)
    assert rc == 2, message
    assert "Traceback" not in message, message
    head = f"{scene}: {key}: " if key else f"{scene}: "
    assert head in message, message
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    return message


# -- settled-start HDF5 frames -----------------------------------------------------------------

def _frame(**override) -> dict:
    """A good frame of N beads inside SCENE's domain, with datasets replaced by ``override``
    (None: left out)."""
    rng = np.random.default_rng(1)
    position = np.column_stack([rng.uniform(-0.05, 0.05, N), rng.uniform(-0.05, 0.05, N),
                                0.01 + 0.012 * np.arange(N)])
    frame = dict(id=np.arange(N), position=position, radius=np.full(N, RADIUS),
                 velocity=np.zeros((N, 3)), angular_velocity=np.zeros((N, 3)),
                 temperature=np.full(N, 300.0))
    frame.update(override)
    return {k: v for k, v in frame.items() if v is not None}


def _one_row(value, row=3, columns=None):
    """A column of N good values (``columns`` wide) with ``value`` at ``row``."""
    good = np.full(N, RADIUS) if columns is None else np.zeros((N, columns))
    good[row] = value
    return good


def write_results(path, frames=None, group="0", **override):
    with h5py.File(path, "w") as f:
        g = f.create_group(f"frames/{group}")
        for name, value in (frames or _frame(**override)).items():
            g[name] = value


# (what, how to write the file, the fragments the message must hold)
FRAME_CASES = [
    ("negative radii", lambda p: write_results(p, radius=np.full(N, -RADIUS)),
     ("/frames/0/radius", "20 particle(s)", "not > 0", "-0.004")),
    ("zero radii", lambda p: write_results(p, radius=np.zeros(N)),
     ("/frames/0/radius", "not > 0")),
    ("a NaN radius", lambda p: write_results(p, radius=_one_row(np.nan)),
     ("/frames/0/radius", "not finite", "row 3")),
    ("an infinite radius", lambda p: write_results(p, radius=_one_row(np.inf)),
     ("/frames/0/radius", "not finite")),
    ("a NaN position", lambda p: write_results(p, position=np.where(
        np.arange(N)[:, None] == 5, np.nan, _frame()["position"])),
     ("/frames/0/position", "not finite", "row 5")),
    ("a NaN velocity", lambda p: write_results(p, velocity=_one_row(np.nan, 2, 3)),
     ("/frames/0/velocity", "not finite", "row 2")),
    ("an infinite angular velocity",
     lambda p: write_results(p, angular_velocity=_one_row(-np.inf, 0, 3)),
     ("/frames/0/angular_velocity", "not finite")),
    ("a NaN temperature", lambda p: write_results(p, temperature=np.where(
        np.arange(N) == 7, np.nan, 300.0)), ("/frames/0/temperature", "not finite", "row 7")),
    ("a temperature below 0 K", lambda p: write_results(p, temperature=np.full(N, -3.0)),
     ("/frames/0/temperature", "not > 0")),
    ("a negative moisture", lambda p: write_results(p, moisture=np.full(N, -0.1)),
     ("/frames/0/moisture", "negative")),
    ("an absurd radius", lambda p: write_results(p, radius=np.full(N, 1e-40)),
     ("/frames/0/radius", "absurd")),
    ("positions shaped (N, 2)", lambda p: write_results(p, position=_frame()["position"][:, :2]),
     ("/frames/0/position", "shape (20, 2)", "(N, 3)")),
    ("radii shorter than positions", lambda p: write_results(p, radius=np.full(5, RADIUS)),
     ("/frames/0/radius", "5 rows", "20")),
    ("velocities shorter than positions", lambda p: write_results(p, velocity=np.zeros((5, 3))),
     ("/frames/0/velocity", "5 rows")),
    ("radii shaped (N, 1)", lambda p: write_results(p, radius=np.full((N, 1), RADIUS)),
     ("/frames/0/radius", "shape (20, 1)", "(N,)")),
    ("a scalar radius", lambda p: write_results(p, radius=np.float64(RADIUS)),
     ("/frames/0/radius", "is a scalar")),
    ("a string radius", lambda p: write_results(p, radius="abc"),
     ("/frames/0/radius", "expected real numbers")),
    ("byte-string radii", lambda p: write_results(p, radius=np.array([b"a"] * N)),
     ("/frames/0/radius", "byte strings")),
    ("boolean radii", lambda p: write_results(p, radius=np.ones(N, bool)),
     ("/frames/0/radius", "booleans")),
    ("complex radii", lambda p: write_results(p, radius=np.full(N, RADIUS, complex)),
     ("/frames/0/radius", "complex")),
    ("no radius", lambda p: write_results(p, radius=None), ("no 'radius' dataset",)),
    ("a frame group named 'first'", lambda p: write_results(p, group="first"),
     ("/frames/first", "not named by a frame number")),
    ("/frames a dataset", lambda p: _frames_dataset(p), ("/frames is a dataset",)),
    ("a radius group", lambda p: _radius_group(p), ("/frames/0/radius is a group",)),
    ("a checkpoint-like file with an empty /fields", lambda p: _empty_checkpoint(p),
     ("/fields has no 'alive' dataset",)),
    ("a material index of the wrong shape", lambda p: _bad_materials(p),
     ("/frames/0/material", "one material index")),
]


def _frames_dataset(path):
    with h5py.File(path, "w") as f:
        f["frames"] = np.zeros(3)


def _radius_group(path):
    with h5py.File(path, "w") as f:
        g = f.create_group("frames/0")
        g["position"] = _frame()["position"]
        g.create_group("radius")


def _empty_checkpoint(path):
    with h5py.File(path, "w") as f:
        f.create_group("fields")
        f.attrs["count"] = 5
        f.attrs["scene"] = SCENE.replace("FILL", REGION_FILL)


def _bad_materials(path):
    write_results(path)
    with h5py.File(path, "a") as f:
        f.attrs["materials"] = ["glass"]
        f["frames/0/material"] = np.zeros((N, 2), dtype=np.int32)


def _start_scene(tmp_path, name="start.h5") -> str:
    return SCENE.replace("FILL", f'file = "{name}"')


@pytest.mark.parametrize("what, write, fragments", FRAME_CASES, ids=[c[0] for c in FRAME_CASES])
def test_check_validates_a_settled_start_file(tmp_path, no_taichi_runtime, what, write,
                                             fragments):
    """Each broken frame: exit 2 naming the scene, particles[0].file, the HDF5 file and the
    dataset (the string fragments are exact; there is no tolerance)."""
    write(tmp_path / "start.h5")
    refused(tmp_path, _start_scene(tmp_path), "particles[0].file", "start.h5", *fragments)


def test_check_accepts_a_good_settled_start_file(tmp_path, no_taichi_runtime):
    """The same frame unbroken (ints as positions included) passes: the checks refuse what
    is wrong, not every file."""
    write_results(tmp_path / "start.h5", moisture=np.full(N, 0.05))
    (tmp_path / "scene.toml").write_text(_start_scene(tmp_path))
    rc, message = cli("check", tmp_path / "scene.toml")
    assert rc == 0, message
    from taichi_dem.scene.loader import load_scene
    fill = load_scene(tmp_path / "scene.toml").fills[0]
    assert fill.positions.shape == (N, 3) and np.all(fill.radii == RADIUS)
    # (the fields effects add to a frame are the fill's frame_values, by their names)
    frame = fill.frame_values
    assert frame["temperature"].shape == (N,) and np.all(frame["moisture"] == 0.05)


@pytest.mark.parametrize("override", [dict(radius=_one_row(np.nan)),
                                      dict(velocity=_one_row(np.nan, 2, 3))],
                         ids=["NaN radius", "NaN velocity"])
def test_run_refuses_a_non_finite_start_before_running(tmp_path, no_taichi_runtime, override):
    """`run` on a frame with a NaN radius or velocity (a traceback in grid.py before): exit 2
    on load, before the Taichi runtime starts, nothing written."""
    write_results(tmp_path / "start.h5", **override)
    refused(tmp_path, _start_scene(tmp_path), "particles[0].file", "not finite", command="run")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


# -- NUL bytes and control characters ----------------------------------------------------------

NUL = "\\u0000"          # as TOML writes it


@pytest.mark.parametrize("scene, key", [
    (SCENE.replace("FILL", f'file = "fill{NUL}.csv"'), "particles[0].file"),
    (SCENE.replace("FILL", f'file = "start{NUL}.h5"'), "particles[0].file"),
    (SCENE.replace("FILL", REGION_FILL) + f'h5 = "out/r{NUL}.h5"\n', "output.h5"),
    (SCENE.replace("FILL", REGION_FILL) + '\n[[bodies]]\nname = "b"\nmaterial = "glass"\n'
     f'mesh = {{ file = "part{NUL}.stl" }}\n', "bodies[0].mesh.file"),
    (SCENE.replace("FILL", REGION_FILL).replace('name = "floor"', f'name = "flo{NUL}or"'),
     "walls[0].name"),
    (SCENE.replace("FILL", REGION_FILL).replace('name = "floor"', 'name = "flo\\u001bor"'),
     "walls[0].name"),
    (SCENE.replace("FILL", REGION_FILL).replace('name = "floor"', 'name = "floor\\n"'),
     "walls[0].name"),
    (SCENE.replace("FILL", REGION_FILL) + '\n[[outlets]]\nname = "o\\u0007"\n'
     'region = { box = { min = [-0.1, -0.1, 0.3], max = [0.1, 0.1, 0.35] } }\n',
     "outlets[0].name"),
    (SCENE.replace("FILL", REGION_FILL).replace("[materials.glass]",
                                                '[materials."gl\\u0000ass"]'), "materials"),
], ids=["csv path", "h5 path", "output h5", "mesh path", "wall NUL", "wall escape",
        "wall newline", "outlet bell", "material key"])
def test_control_characters_are_refused_on_load(tmp_path, no_taichi_runtime, scene, key):
    """A NUL byte in a path (`ValueError: embedded null byte` before) or a control character
    in a name (an AttributeError in the recorder during `run` before): exit 2 with the key."""
    message = refused(tmp_path, scene, key, "control character U+")
    assert "\x00" not in message and "\x1b" not in message and "\x07" not in message


def test_run_refuses_a_wall_named_with_a_nul_byte(tmp_path, no_taichi_runtime):
    """The case that reached the recorder: refused by `run` before anything starts."""
    scene = SCENE.replace("FILL", REGION_FILL).replace('name = "floor"', f'name = "fl{NUL}"')
    refused(tmp_path, scene, "walls[0].name", "U+0000 (a NUL byte)", command="run")


# -- deep nesting ------------------------------------------------------------------------------

def _deep_scene(depth: int, kind: str) -> tuple:
    """SCENE with a value nested ``depth`` deep under [output]; (text, its line)."""
    value = ("[" * depth + "]" * depth if kind == "arrays"
             else "{ a = " * depth + "1" + " }" * depth)
    scene = SCENE.replace("FILL", REGION_FILL).replace("[output]", f"[output]\nx = {value}")
    lines = scene.split("\n")
    return scene, 1 + next(i for i, row in enumerate(lines) if row.startswith("x = "))


@pytest.mark.parametrize("depth", [3000, 5000])
@pytest.mark.parametrize("kind", ["arrays", "inline tables"])
@pytest.mark.parametrize("command", ["check", "run"])
def test_deeply_nested_toml_is_refused(tmp_path, no_taichi_runtime, depth, kind, command):
    """TOML nested 3,000 - 5,000 deep made tomllib raise RecursionError (a traceback): exit 2
    naming the file and the line where the nesting starts."""
    scene, line = _deep_scene(depth, kind)
    refused(tmp_path, scene, "", "nests", "too deeply", f"from line {line}", command=command)


@pytest.mark.parametrize("argv", [["sweep", "--set", "simulation.end_time=0.01,0.02"],
                                  ["tradeoffs", "--duration", "0.01"]],
                         ids=["sweep", "tradeoffs"])
def test_other_commands_refuse_deep_nesting(tmp_path, no_taichi_runtime, argv):
    """sweep and tradeoffs read the scene's TOML themselves (a RecursionError traceback and
    "maximum recursion depth exceeded" before): the same exit 2 naming the file."""
    scene, line = _deep_scene(3000, "arrays")
    path = tmp_path / "scene.toml"
    path.write_text(scene)
    rc, message = cli(argv[0], path, *argv[1:])
    assert rc == 2 and "Traceback" not in message, message
    assert f"{path}: the TOML nests" in message and f"from line {line}" in message


# -- CSV files: say what is wrong, never what the file says ------------------------------------

SECRET = "hunter2-do-not-print"


@pytest.mark.parametrize("content, fragments", [
    (f"root:x:0:0:{SECRET}:/root:/bin/bash\ndaemon:x:1:1::/usr/sbin\n",
     ("line 1", "column 1 of the header", "found 1 column", "x,y,z,radius")),
    (f"x,{SECRET},z,radius\n0,0,0.1,0.004\n",
     ("line 1", "column 2 of the header", "found 4 columns")),
    (f"x,y,z,radius\n0,0,0.1,{SECRET}\n", ("line 2", "column 'radius'", "not a number")),
    (f"x,y,z,radius\n0,0,0.1,0.004,{SECRET}\n", ("line 2", "5 values")),
])
def test_a_csv_error_does_not_echo_the_file(tmp_path, no_taichi_runtime, content, fragments):
    """`file = "/etc/passwd"` printed its first line. The message says where and what is
    wrong; no part of a line of the file appears in it."""
    secret = tmp_path / "secret.txt"
    secret.write_text(content)
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.replace("FILL", f'file = "{secret}"'))
    rc, message = cli("check", scene)
    assert rc == 2 and "Traceback" not in message, message
    assert f"{secret}: particles[0].file: " in message
    assert SECRET not in message and "root:x" not in message and "daemon" not in message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


# -- divergence: the quantity that is not finite, and its cause --------------------------------

def _diverge(sim, inject) -> str:
    """Inject into the state one step before an output sample; the DivergenceError's text."""
    sim.run(0.01)
    sim.step(sim.output_every - sim.step_count % sim.output_every - 1)
    inject(sim.engine.state)
    with pytest.raises(DivergenceError) as info:
        sim.step(1)
    return str(info.value)


@pytest.fixture(scope="module")
def small_text():
    from tests.conftest import SMALL_SCENE
    return SMALL_SCENE.format(precision="f64", rolling=0.05, count=200)


@pytest.fixture(scope="module")
def thermal_text():
    from tests.unit.resume_scene import scene_text
    fill = "temperature = 400.0\nregion"
    text = scene_text(count=100)
    assert fill in text
    return text.replace(fill, "temperature = 400.0\nmoisture = 0.05\nregion")


def test_a_non_finite_position_is_not_blamed_on_the_time_step(small_text):
    """A NaN position beside a finite velocity cannot come from a step (it was "time step too
    large" before): the message names the position and says it was put into the state."""
    with td.Simulation.from_text(small_text, h5="") as sim:
        message = _diverge(sim, lambda s: s.position.__setitem__(4, [0.0, np.nan, 0.05]))
    assert "has a non-finite position ([" in message and "nan" in message
    assert "not the integration" in message and "time step too large" not in message


def test_a_non_finite_angular_velocity_is_named(small_text):
    """A NaN spin (not checked at all before): the angular velocity named, with the time
    step as the cause (the explicit integration blew up)."""
    with td.Simulation.from_text(small_text, h5="") as sim:
        message = _diverge(sim, lambda s: s.angular_velocity.__setitem__(6, [np.inf, 0, 0]))
    assert "has a non-finite angular velocity (" in message and "rad/s" in message
    assert "time step too large" in message


@pytest.mark.parametrize("model, named", [("constant_torque", True), ("epsd", False)])
def test_a_diverged_spin_names_the_constant_torque_rolling_limit(small_text, model, named):
    """With the constant-torque rolling model (the small scene's default) a diverged spin also
    names the model's known runaway (a sphere in a pocket of contacts, which no smaller time
    step cures: tests/verification/test_rolling_pocket.py) and EPSD as the way out; with
    EPSD the message does not."""
    text = small_text.replace("rolling_friction = 0.05",
                              f'rolling_friction = 0.05\nmodel = "{model}"')
    assert text.count(f'model = "{model}"') == 2
    with td.Simulation.from_text(text, h5="") as sim:
        message = _diverge(sim, lambda s: s.angular_velocity.__setitem__(6, [np.inf, 0, 0]))
    assert "time step too large" in message
    assert ("constant-torque rolling model at high friction" in message) is named, message
    assert ('set model = "epsd"' in message) is named


@pytest.mark.parametrize("quantity, value, fragments", [
    ("temperature", np.nan, ("has a non-finite temperature (nan K)", "heat")),
    ("temperature", -20.0, ("temperature of -20 K, not above absolute zero", "heat")),
    ("moisture", np.nan, ("has a non-finite moisture (nan kg/kg)", "drying")),
])
def test_a_non_finite_temperature_or_moisture_is_named(thermal_text, quantity, value,
                                                       fragments):
    """A NaN temperature was reported as "non-finite velocity": now the quantity and a
    thermal cause, not the mechanical time step."""
    with td.Simulation.from_text(thermal_text, h5="") as sim:
        message = _diverge(sim, lambda s: getattr(s, quantity).__setitem__(8, value))
        # the host-side search (Simulation._check_state's path) finds the same particle
        again = sim.divergence.non_finite_message(sim.time, None, {})
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert "velocity" not in message.split("Likely cause")[0]
    assert "time step too large for the stiffest contact" not in message
    assert again.split("Likely cause")[0] == message.split("Likely cause")[0]


def test_run_exits_3_naming_an_overflowing_temperature(tmp_path):
    """A valid thermal scene with absurd values (beads at 1e25 K radiating in f32): the heat
    balance overflows at the first step. `run` exits 3 naming the temperature and the
    overflow (before: "non-finite velocity", a time step too large)."""
    from tests.unit.resume_scene import scene_text
    text = scene_text(count=100, precision="f32")
    for old, new in (("heat_capacity = 800.0", "heat_capacity = 800.0\nemissivity = 0.9"),
                     ("heat_capacity = 480.0", "heat_capacity = 480.0\nemissivity = 0.9"),
                     ("end_time = 0.1", "end_time = 0.01"),
                     ("temperature = 400.0", "temperature = 1e25"),
                     ("wall_conduction = true", 'wall_conduction = true\nradiation = true\n'
                                                'radiation_to = "gas"')):
        assert old in text
        text = text.replace(old, new)
    scene = tmp_path / "hot.toml"
    scene.write_text(text)
    rc, message = cli("run", scene, "--quiet", "--out", tmp_path / "out")
    assert rc == 3 and "Traceback" not in message, message
    assert "has a non-finite temperature" in message and "heat balance overflowed" in message
    assert "velocity" not in message and "time step too large" not in message


@pytest.mark.parametrize("section,name", [("walls", "flo/or"), ("walls", ".."), ("walls", " floor"),
                                          ("bodies", "a/b"), ("bodies", "."),
                                          ("outlets", ".."), ("outlets", "a/b")])
def test_a_name_that_cannot_name_a_results_group_is_refused(section, name, tmp_path):
    """Walls, bodies, factories, outlets and sensors name HDF5 groups (/series/walls/<name>/):
    a '/' would silently nest the series under another group, '.' and '..' would name the
    group itself or the one above. Refused on load, naming the key."""
    from taichi_dem.errors import SceneError
    from taichi_dem.scene.loader import parse_scene
    base = Path(__file__).resolve().parents[2] / "demos" / "pile.toml"
    text = base.read_text()
    if section == "walls":
        text = text.replace('name = "floor"', f'name = "{name}"', 1)
    elif section == "bodies":
        text += f'''
[[bodies]]
name = "{name}"
material = "glass"
mesh = {{ builder = "box", min = [-0.05, -0.05, 0.0], max = [0.05, 0.05, 0.01] }}
'''
    else:
        text += f'''
[[outlets]]
name = "{name}"
region = {{ box = {{ min = [-0.3, -0.3, -0.01], max = [0.3, 0.3, 0.0] }} }}
'''
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as err:
        parse_scene(text, source=str(path))
    assert f"{section}[" in str(err.value) and ".name" in str(err.value), str(err.value)
