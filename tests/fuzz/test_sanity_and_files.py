"""Issue 43, items 3 and 4 (and the size tracebacks of item 2): physical sanity before a run,
and files that stay where the user put the run.

Each case is the smallest scene that reproduced the fault (a 200-bead pile), through the
command line: exit 2 and one ``file: key: reason`` line, never a traceback, and ``check``
without starting the Taichi runtime (the ``no_taichi_runtime`` fixture refuses it). Each
refusal has a neighbour that is accepted, so a test fails if the check refuses everything."""
from __future__ import annotations

import os
import re

import h5py
import numpy as np
import pytest

from taichi_dem.app.cli import main
from taichi_dem.errors import SceneError

PILE = """
[simulation]
end_time = 1.2
gravity = [0.0, 0.0, -9.81]
seed = 1
{simulation}
[domain]
min = [-0.1, -0.1, -0.01]
max = [0.1, 0.1, 0.35]

[materials.glass]
density = {density}
youngs_modulus = {youngs}
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3
{materials}
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.6
friction = 0.5

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.6
friction = 0.5

[[walls]]
name = "floor"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "steel"

[[particles]]
material = "glass"
radius = {radius}
count = {count}
region = {{ box = {{ min = [-0.06, -0.06, 0.05], max = [0.06, 0.06, 0.3] }} }}
{extra}
[output]
interval = {interval}
{output}
"""


def pile(simulation="", density="2500.0", youngs="5.0e7", materials="", radius='"4 mm"',
         count=200, extra="", interval="0.05", output="") -> str:
    """The pile scene's text with the given pieces in place."""
    return PILE.format(simulation=simulation, density=density, youngs=youngs,
                       materials=materials, radius=radius, count=count, extra=extra,
                       interval=interval, output=output)


def write(folder, text, name="scene.toml"):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(text)
    return path


def check(path, capsys, *extra):
    """(exit status, stderr) of `taichi-dem check`."""
    rc = main(["check", str(path), *extra])
    return rc, capsys.readouterr().err


def refused(path, capsys, key, *fragments):
    """Assert `check` exits 2 with one line naming the file and ``key``; the message."""
    rc, err = check(path, capsys)
    assert rc == 2, err
    assert "Traceback" not in err
    assert f"{path}: {key}: " in err, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    return err


# ----------------------------------------------------------------------------- the time step
def test_a_step_so_small_the_run_never_ends_is_refused(tmp_path, capsys, no_taichi_runtime):
    """density = 1e-25 gave dt 1.5e-19 s (3.4e17 steps): `check` said OK and `run` hung. The
    density is blamed, with the step and the step count; the real glass is accepted."""
    err = refused(write(tmp_path, pile(density="1e-25")), capsys, "materials.glass.density",
                  "steps", "1e+10")
    assert re.search(r"time step is 1\.\d+e-19 s", err), err
    assert check(write(tmp_path / "ok", pile()), capsys)[0] == 0


@pytest.mark.parametrize("simulation, key", [
    ("dt = 1e-10", "simulation.dt"),                      # below 1e-9 s
    ("dt = 1e-6\nend_time = 1e5", "simulation.end_time"),  # 1e11 steps
], ids=["dt below 1e-9 s", "1e11 steps"])
def test_an_explicit_step_or_a_run_too_long_is_refused(simulation, key, tmp_path, capsys,
                                                        no_taichi_runtime):
    """A given dt under 1e-9 s, or a run of more than 1e10 steps, names the key that made it;
    dt = 1e-6 s over 1.2 s (1.2e6 steps) is accepted."""
    text = pile(simulation=simulation).replace("end_time = 1.2\n", "") \
        if "end_time" in simulation else pile(simulation=simulation)
    refused(write(tmp_path, text), capsys, key, "steps")
    assert check(write(tmp_path / "ok", pile(simulation="dt = 1e-6")), capsys)[0] == 0


@pytest.mark.parametrize("density, youngs, key", [
    ("2500.0", "1e-3", "materials.glass.youngs_modulus"),   # automatic dt 0.22 s
    ("1e25", "5.0e7", "materials.glass.density"),           # automatic dt 5,118 s
], ids=["youngs_modulus 1e-3", "density 1e25"])
def test_a_contact_too_soft_to_carry_a_particle_is_refused(density, youngs, key, tmp_path,
                                                           capsys, no_taichi_runtime):
    """Both ran "simulated 0 s, 0 steps" with exit 0. A bead's own weight would press it
    thousands of radii into the floor (Hertz); refused when more than 1 radius. The
    softest contact a DEM scene of mm beads uses (1 MPa: 0.2 radii) is accepted."""
    refused(write(tmp_path, pile(density=density, youngs=youngs)), capsys, key,
            "radii into its partner")
    assert check(write(tmp_path / "ok", pile(youngs="1e6")), capsys)[0] == 0


def test_a_step_longer_than_the_output_interval_is_refused(tmp_path, capsys,
                                                           no_taichi_runtime):
    """The automatic dt of the pile is 1.2e-5 s: an interval of 5e-6 s cannot be sampled at
    (the run would sample every step, silently at another interval); 1e-4 s is fine."""
    refused(write(tmp_path, pile(interval="5e-6")), capsys, "output.interval", "longer than")
    assert check(write(tmp_path / "ok", pile(interval="1e-4")), capsys)[0] == 0


def test_an_output_interval_longer_than_the_run_is_valid(tmp_path, capsys, no_taichi_runtime):
    """CONTRACT.md: the interval may exceed end_time (a benchmark wants no samples; the closing
    sample records the end). It was refused ("no sample after its start")."""
    rc, err = check(write(tmp_path, pile(interval="5.0")), capsys)
    assert rc == 0, err


def test_a_damping_time_constant_below_five_steps_is_refused(tmp_path, capsys,
                                                             no_taichi_runtime):
    """time_constant = 1e-6 s with dt 1.2e-5 s lost all 200 beads in 0.02 s (the explicit
    decay flips sign for dt > tau). The message names dt and the least time constant (5 dt,
    where the per-step decay is within 2.5 % of exact); 1 ms is accepted."""
    damping = "\n[viscous_damping]\ntime_constant = {}\n"
    err = refused(write(tmp_path, pile(extra=damping.format("1e-6"))), capsys,
                  "viscous_damping.time_constant", "dt = ", "time_constant >= ")
    least = float(re.search(r"time_constant >= ([0-9.e+-]+) s", err).group(1))
    dt = float(re.search(r"dt = ([0-9.e+-]+) s", err).group(1))
    assert least == pytest.approx(5 * dt, rel=1e-2)
    assert check(write(tmp_path / "ok", pile(extra=damping.format("1e-3"))), capsys)[0] == 0


# ----------------------------------------------------------------------------- sizes
def test_max_particles_below_the_placed_count_is_refused(tmp_path, capsys, no_taichi_runtime):
    """max_particles = 10 with 200 placed was ignored; both numbers in the message. 200
    slots for 200 beads are enough."""
    refused(write(tmp_path, pile(simulation="max_particles = 10")), capsys,
            "simulation.max_particles", "10 particle slots", "200 particles")
    rc, err = check(write(tmp_path / "ok", pile(simulation="max_particles = 200")), capsys)
    assert rc == 0, err


def test_max_particles_without_factories_is_named_as_unused(tmp_path, capsys,
                                                             no_taichi_runtime):
    """Without factories the fills alone set the slots: max_particles = 2147483647 allocates
    nothing more, and check says so rather than ignoring it silently (the estimate stays that
    of the 200 beads)."""
    path = write(tmp_path, pile(simulation="max_particles = 2147483647"))
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "max_particles = 2,147,483,647 is not used" in out, out
    assert "(200)" in out


FACTORY = """
[[factories]]
name = "inlet"
material = "glass"
radius = "4 mm"
region = { box = { min = [-0.06, -0.06, 0.25], max = [0.06, 0.06, 0.3] } }
mass_rate = "0.1 kg/s"
"""


def test_device_memory_beyond_the_machine_is_refused(tmp_path, capsys, no_taichi_runtime):
    """max_particles = 2147483647 (with a factory, so the slots are allocated) printed an
    estimate of 2,105,344 MiB, said OK, and the run crashed. The estimate (some TiB: more than
    any machine this runs on) and the machine's memory are in the message; 100,000 slots pass."""
    err = refused(write(tmp_path, pile(simulation="max_particles = 2147483647", extra=FACTORY)),
                  capsys, "simulation.max_particles", "MiB of device memory", "machine's memory")
    estimate = float(re.search(r"estimated ([0-9,]+) MiB", err).group(1).replace(",", ""))
    assert estimate > 1e6
    rc, err = check(write(tmp_path / "ok", pile(simulation="max_particles = 100000",
                                                 extra=FACTORY)), capsys)
    assert rc == 0, err


def test_a_fill_too_large_for_the_machine_is_refused_before_placement(tmp_path, capsys,
                                                                     no_taichi_runtime):
    """count = 200,000,000 of radius 2e-5 m raised MemoryError (11.9 GiB) in placement; now
    refused from the count alone (device estimate ~200 GiB)."""
    refused(write(tmp_path, pile(radius="2e-5", count=200_000_000)), capsys,
            "particles[0].count", "MiB of device memory")


def test_placement_refuses_a_count_beyond_the_machine_from_the_count_alone(tmp_path,
                                                                           monkeypatch):
    """Placement itself (the Python API places before any estimate) refuses a fill whose
    placement needs more than the machine's memory, before allocating: with the machine's
    memory set to 1 GiB, 2 million spheres (about 2 GiB at the measured 1,000 bytes each) are
    refused at once, while 1,000 are placed."""
    from taichi_dem.scene.loader import load_scene
    from taichi_dem.setup import memory
    from taichi_dem.setup.placement import place_fills
    monkeypatch.setattr(memory, "host_memory_bytes", lambda: 2 ** 30)
    scene = load_scene(write(tmp_path, pile(radius="2e-5", count=2_000_000)))
    with pytest.raises(SceneError) as e:
        place_fills(scene, np.random.default_rng(1))
    assert e.value.key == "particles[0].count" and "GiB" in e.value.reason
    small = load_scene(write(tmp_path / "ok", pile(radius="2e-5", count=1000)))
    assert len(place_fills(small, np.random.default_rng(1)).radius) == 1000


def test_thousands_of_unused_materials_are_refused_before_the_pair_tables(
        tmp_path, capsys, no_taichi_runtime):
    """140,000 unused materials asked for a 146 GiB pair table (MemoryError). Every pair of
    declared materials is tabled (52 bytes), capped at 256 MiB: 2,300 materials are refused
    with their number and the tables' size, 2,000 accepted."""
    def materials(n):
        return "".join(f"\n[materials.m{i}]\ndensity = 1000.0\nyoungs_modulus = 1e7\n"
                       f"poisson_ratio = 0.25\n" for i in range(n))
    refused(write(tmp_path, pile(materials=materials(2300))), capsys, "materials",
            "2,302 materials", "GiB")
    rc, err = check(write(tmp_path / "ok", pile(materials=materials(2000))), capsys)
    assert rc == 0, err


def test_a_domain_of_1e29_is_refused(tmp_path, capsys, no_taichi_runtime):
    """+-1e29 m overflowed the cell count in `run` (OverflowError). Coordinates beyond 1e6 m
    are refused on load (float32 resolves them to centimetres); +-1e3 m passes."""
    text = pile().replace("min = [-0.1, -0.1, -0.01]", "min = [-1e29, -1e29, -1e29]") \
        .replace("max = [0.1, 0.1, 0.35]", "max = [1e29, 1e29, 1e29]")
    refused(write(tmp_path, text), capsys, "domain.min", "1e+06 m")
    ok = pile().replace("max = [0.1, 0.1, 0.35]", "max = [1e3, 1e3, 1e3]")
    rc, err = check(write(tmp_path / "ok", ok), capsys)
    assert rc == 0, err


def test_a_grid_too_fine_to_number_is_refused(tmp_path):
    """Inside the coordinate bound, tiny particles in a wide domain still make more cells than
    a 64-bit count holds (grid.py overflowed): 2e3 m / 2e-9 m = 1e12 cells per axis is
    refused naming the domain; 4 mm beads in it (2.5e5 per axis, 1.6e16 cells) are fine (the
    grid then coarsens itself to 8 per particle)."""
    from taichi_dem.scene.loader import load_scene
    from taichi_dem.setup.timestep import refuse_uncountable_grid
    text = pile().replace("min = [-0.1, -0.1, -0.01]", "min = [-1e3, -1e3, -1e3]") \
        .replace("max = [0.1, 0.1, 0.35]", "max = [1e3, 1e3, 1e3]")
    scene = load_scene(write(tmp_path, text))
    with pytest.raises(SceneError) as e:
        refuse_uncountable_grid(scene, np.array([1e-9]))
    assert e.value.key == "domain" and "cells" in e.value.reason
    refuse_uncountable_grid(scene, np.array([4e-3]))


# ----------------------------------------------------------------------------- files
@pytest.mark.parametrize("h5, fragment", [
    ("/tmp/results.h5", "absolute path"),
    ("../results.h5", "leaves the scene's folder"),
    ("sub/../../results.h5", "leaves the scene's folder"),
    ("~/results.h5", "starts with ~"),
    ("nonexistent_base/", "names a folder"),
], ids=["absolute", "dotdot", "nested dotdot", "tilde", "trailing slash"])
def test_a_scene_output_path_outside_its_folder_is_refused(h5, fragment, tmp_path, capsys,
                                                           no_taichi_runtime, monkeypatch):
    """A scene alone writes nothing outside its folder (an absolute path overwrote a text file
    it was pointed at; "nonexistent_base/" raised IsADirectoryError). "sub/ok.h5" passes."""
    monkeypatch.chdir(tmp_path)
    refused(write(tmp_path / "scene", pile(output=f'h5 = "{h5}"')), capsys, "output.h5",
            fragment)
    rc, err = check(write(tmp_path / "ok", pile(output='h5 = "sub/ok.h5"')), capsys)
    assert rc == 0, err
    assert not any(tmp_path.glob("**/~")), "a ./~ folder was created"


def test_a_nul_byte_in_an_output_path_is_refused(tmp_path, capsys, no_taichi_runtime):
    """`h5` with a NUL byte raised ValueError in `run`: exit 2 naming output.h5 (the loader or
    the path resolver, whichever sees it first); the resolver refuses one given directly."""
    from taichi_dem.scene.sections.consistency import resolve_output_path
    refused(write(tmp_path, pile(output='h5 = "a\\u0000b.h5"')), capsys, "output.h5", "NUL")
    with pytest.raises(SceneError) as e:
        resolve_output_path(tmp_path / "scene.toml", "output.h5", "a\x00b.h5")
    assert e.value.key == "output.h5" and "NUL" in e.value.reason


def test_output_paths_resolve_against_the_scene_folder_or_the_command_line(tmp_path,
                                                                           monkeypatch):
    """output.h5 resolved against the current folder, not the scene's as documented. The one
    resolver: the scene's folder; --out DIR (the file name in it, ~ expanded); --h5 as the
    user gave it (~ expanded, never a ./~ folder)."""
    from types import SimpleNamespace

    from taichi_dem.app.cli import _resolve_outputs
    from taichi_dem.scene.loader import load_scene
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    path = write(tmp_path / "scenes", pile(output='h5 = "out/p.h5"\nrrd = "p.rrd"'))
    scene = load_scene(path)
    h5, rrd, checkpoint = _resolve_outputs(str(path), scene)
    assert h5 == str(tmp_path / "scenes" / "out" / "p.h5")
    assert rrd == str(tmp_path / "scenes" / "p.rrd")
    assert checkpoint == str(tmp_path / "scenes" / "out" / "scene.checkpoint.h5")
    args = SimpleNamespace(h5=None, rrd=None, out="~/runs")
    h5, rrd, checkpoint = _resolve_outputs(str(path), scene, args)
    assert h5 == str(tmp_path / "home" / "runs" / "p.h5")
    assert checkpoint == str(tmp_path / "home" / "runs" / "scene.checkpoint.h5")
    args = SimpleNamespace(h5="~/mine.h5", rrd="/elsewhere/r.rrd", out=None)
    h5, rrd, _ = _resolve_outputs(str(path), scene, args)
    assert (h5, rrd) == (str(tmp_path / "home" / "mine.h5"), "/elsewhere/r.rrd")


def _our_results(path):
    with h5py.File(path, "w") as f:
        f.attrs["taichi_dem_version"] = "test"
        f.attrs["scene"] = "[simulation]"


@pytest.mark.parametrize("output, target, key", [
    ('h5 = "r.h5"', "r.h5", "output.h5"),
    ('rrd = "r.rrd"', "r.rrd", "output.rrd"),
    ('h5 = "r.h5"\ncheckpoint_interval = 0.5', "scene.checkpoint.h5",
     "output.checkpoint_interval"),
], ids=["results", "recording", "checkpoint"])
def test_an_existing_file_not_ours_is_never_overwritten(output, target, key, tmp_path, capsys,
                                                        no_taichi_runtime):
    """A run opened a text file with mode "w" and overwrote it. A results file, recording or
    checkpoint path holding a file that is not ours is refused and left as it was; a
    file of ours (an HDF5 file with our root attributes, a rerun recording) is accepted."""
    path = write(tmp_path, pile(output=output))
    victim = tmp_path / target
    victim.write_text("precious\n")
    refused(path, capsys, key, "refusing to overwrite")
    assert victim.read_text() == "precious\n"
    victim.unlink()
    if target.endswith(".rrd"):
        victim.write_bytes(b"RRF2" + bytes(28))
    elif "checkpoint" in target:
        with h5py.File(victim, "w") as f:
            f.attrs["format"] = "taichi_dem checkpoint 1"
    else:
        _our_results(victim)
    rc, err = check(path, capsys)
    assert rc == 0, err


def test_an_hdf5_file_without_our_attributes_is_not_ours(tmp_path):
    """The signature alone is not enough: someone else's HDF5 file (no taichi_dem_version and
    scene root attributes) is refused too; ours passes; an empty file holds nothing to lose."""
    from taichi_dem.scene.sections.consistency import foreign_file_problem
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.create_dataset("x", data=[1, 2, 3])
    assert "not a taichi_dem results file" in foreign_file_problem(str(other), "results")
    assert "not a taichi_dem checkpoint" in foreign_file_problem(str(other), "checkpoint")
    ours = tmp_path / "ours.h5"
    _our_results(ours)
    assert foreign_file_problem(str(ours), "results") is None
    (tmp_path / "empty.h5").write_bytes(b"")
    assert foreign_file_problem(str(tmp_path / "empty.h5"), "results") is None


def test_the_recorder_itself_will_not_overwrite_a_foreign_file(tmp_path):
    """The Python API opens results through HDF5Recorder: it refuses a foreign file too (the
    command line checks first; this is the last guard)."""
    from taichi_dem.recorders.hdf5 import HDF5Recorder
    victim = tmp_path / "notes.h5"
    victim.write_text("precious\n")
    with pytest.raises(SceneError):
        HDF5Recorder(str(victim), scene_text="", dt=1e-5, arch="cpu", precision="f32")
    assert victim.read_text() == "precious\n"


def test_a_run_writes_beside_its_scene_not_in_the_current_folder(tmp_path, monkeypatch):
    """The end-to-end fault: `run` from another folder wrote output.h5 there. Now the results
    and the .xdmf land in the scene's folder, nothing in the current one, and a second run
    overwrites its own results file (ours) without complaint."""
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    path = write(tmp_path / "scenes", pile(count=20, output='h5 = "out/p.h5"'))
    for _ in range(2):
        assert main(["run", str(path), "--until", "0.001", "--quiet"]) == 0
    assert (tmp_path / "scenes" / "out" / "p.h5").is_file()
    assert not os.listdir(elsewhere)
    # the XDMF beside it is ours too, and replaced; a file of the user's in its place is not
    xdmf = tmp_path / "scenes" / "out" / "p.xdmf"
    assert xdmf.is_file()
    xdmf.write_text("my ParaView notes\n")
    assert main(["run", str(path), "--until", "0.001", "--quiet"]) == 0
    assert xdmf.read_text() == "my ParaView notes\n"
