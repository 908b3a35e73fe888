"""Periodic slices that hold (issue 11, items 1-2).

1. A floor made of two triangles that span the whole periodic length (what a CAD export of a
   slot hopper's floor plate gives), domain y in [-0.05, 0.05) periodic, plane walls at
   x = +-0.05: 200 glass spheres dropped on it must all stay above it. Before the fix the
   particle was imaged near the triangle's first vertex, which for a triangle longer than half
   the period is the wrong image: 122 of 200 fell through. The same floor subdivided 20 x 20
   (every triangle short) is the reference: both floors are the same plane, so the settled beds
   must agree in height to within the bed's random packing noise.
2. A periodic drum slice whose shell triangles span the slice: no particle leaves the shell.
3. A thin periodic slab (the seed-000 hopper has a depth of 2.5 diameters): a periodic length
   just over two contact distances runs, no pair is counted twice (each particle's contacts
   equal a brute-force minimum-image count) and the loader explains the true limit below it.
"""
from __future__ import annotations

import numpy as np
import pytest

import taichi_dem as td

from conftest import listed_pairs, pairs_within

R = 0.002
HALF = 0.05
# soft glass beads and steel, e 0.5, mu 0.5 (the floor and drum-slice scenes)
GLASS_ON_STEEL = """[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5"""


def _obj_floor(path, n: int) -> None:
    """A 0.1 m x 0.1 m floor at z = 0 from x, y = -0.05 to 0.05 as n x n quads of 2 triangles,
    normals up (+z)."""
    xs = np.linspace(-HALF, HALF, n + 1)
    lines, index = [], {}
    for i, x in enumerate(xs):
        for j, y in enumerate(xs):
            index[i, j] = len(index) + 1
            lines.append(f"v {float(x)!r} {float(y)!r} 0.0")
    for i in range(n):
        for j in range(n):
            a, b, c, d = index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]
            lines += [f"f {a} {b} {c}", f"f {a} {c} {d}"]
    path.write_text("\n".join(lines) + "\n")


def _floor_scene(mesh_file: str, periodic: bool, end_time: float) -> str:
    per = '["y"]' if periodic else "[]"
    return f"""
[simulation]
end_time = {end_time}
gravity = [0.0, 0.0, -9.81]
precision = "f64"
seed = 11
[domain]
min = [-0.05, -0.05, -0.02]
max = [0.05, 0.05, 0.2]
periodic = {per}
{GLASS_ON_STEEL}
[[walls]]
name = "left"
plane = {{ point = [-0.05, 0, 0], normal = [1, 0, 0] }}
material = "steel"
[[walls]]
name = "right"
plane = {{ point = [0.05, 0, 0], normal = [-1, 0, 0] }}
material = "steel"
[[bodies]]
name = "floor"
material = "steel"
mesh = {{ file = "{mesh_file}" }}
[[particles]]
material = "glass"
radius = {R}
count = 200
region = {{ box = {{ min = [-0.045, -0.05, 0.01], max = [0.045, 0.05, 0.08] }} }}
[output]
interval = 0.05
"""


def _settle(tmp_path, n_quads: int, periodic: bool, end_time: float = 0.3):
    mesh = tmp_path / f"floor_{n_quads}.obj"
    _obj_floor(mesh, n_quads)
    text = _floor_scene(mesh.name, periodic, end_time)
    with td.Simulation.from_text(text, base_dir=str(tmp_path), arch="cpu", precision="f64") as sim:
        sim.run()
        p = sim.particles()
        count = sim.particle_count
    return p, count


@pytest.fixture(scope="module")
def floors(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("floors")
    return {"quad": _settle(tmp, 1, True), "fine": _settle(tmp, 20, True)}


def test_big_triangle_floor_holds_every_particle(floors):
    p, count = floors["quad"]
    z = p["position"][:, 2]
    print(f"\nquad floor: {count} particles left, lowest centre z = {z.min():.5f} m")
    assert count == 200
    # resting on the floor the centre sits at r minus a Hertz overlap (~1e-5 m here)
    assert z.min() > 0.9 * R


def test_big_triangle_floor_matches_subdivided_floor(floors):
    zq = floors["quad"][0]["position"][:, 2]
    zf = floors["fine"][0]["position"][:, 2]
    assert floors["fine"][1] == 200
    # the same plane: the same bed, up to the random packing (200 spheres of 4 mm in 0.1 x 0.1
    # m make 0.5-1 layers; the mean centre height differs by a fraction of a radius at most)
    print(f"\nmean bed height: quad {zq.mean():.5f} m, subdivided {zf.mean():.5f} m")
    assert abs(zq.mean() - zf.mean()) < 0.25 * R
    assert abs(zq.min() - zf.min()) < 0.05 * R


# ------------------------------------------------------------------ periodic drum slice
R_DRUM = 0.06
SLICE = 0.03            # the shell's triangles run the whole slice (one segment along x)


DRUM_SLICE = f"""
[simulation]
end_time = 0.6
gravity = [0.0, 0.0, -9.81]
precision = "f64"
seed = 5
[domain]
min = [0.0, -0.065, -0.065]
max = [{SLICE}, 0.065, 0.065]
periodic = ["x"]
{GLASS_ON_STEEL}
[[bodies]]
name = "shell"
material = "steel"
mesh = {{ builder = "drum", radius = {R_DRUM}, length = {SLICE}, end_walls = false, flights = 4, flight_height = 0.012 }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "30 rpm" }} }}
[[particles]]
material = "glass"
radius = {R}
count = 150
region = {{ cylinder = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], length = {SLICE}, radius = 0.045 }} }}
[output]
interval = 0.05
"""


def test_periodic_drum_slice_keeps_every_particle_inside(tmp_path):
    with td.Simulation.from_text(DRUM_SLICE, base_dir=str(tmp_path), arch="cpu",
                                 precision="f64") as sim:
        longest = 0.0
        tris = sim.scene.bodies[0].vertices[sim.scene.bodies[0].faces]
        longest = float(np.max(np.ptp(tris[:, :, 0], axis=1)))
        sim.run()
        p = sim.particles()
        count = sim.particle_count
    rho = np.hypot(p["position"][:, 1], p["position"][:, 2])
    print(f"\ndrum slice: longest triangle along x {longest:.3f} m of a {SLICE} m period; "
          f"{count} of 150 left; outermost centre at {rho.max():.5f} m (shell {R_DRUM} m)")
    assert longest > 0.5 * SLICE          # the case this test is about
    assert count == 150
    # centres stay a radius inside the shell (less a Hertz overlap, ~1e-5 m here)
    assert rho.max() < R_DRUM - 0.9 * R


# ------------------------------------------------------------------ thin periodic slabs
def _slab_scene(depth: float, body: str, end_time: float = 0.3, skin: str = "") -> str:
    return f"""
[simulation]
end_time = {end_time}
gravity = [0.0, 0.0, -9.81]
precision = "f64"
seed = 2
{skin}
[domain]
min = [-0.03, 0.0, -0.01]
max = [0.03, {depth!r}, 0.12]
periodic = ["y"]
[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.9
friction = 0.2
[[walls]]
name = "floor"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "glass"
[[walls]]
name = "left"
plane = {{ point = [-0.03, 0, 0], normal = [1, 0, 0] }}
material = "glass"
[[walls]]
name = "right"
plane = {{ point = [0.03, 0, 0], normal = [-1, 0, 0] }}
material = "glass"
{body}
[output]
interval = 0.05
"""


@pytest.mark.parametrize("skin, cells", [(0.5e-3, 2), (3e-3, 1)])
def test_thin_slab_settles_with_every_pair_once(tmp_path, skin, cells):
    """The lists of a slab 2.5 diameters deep hold every pair within reach once, with a skin
    that leaves two cells along the periodic axis and with one that leaves one (its cutoff,
    2 r + skin = 7 mm, is more than half the period: the skin is not limited by the period)."""
    depth = 2.5 * 2 * R           # the seed-000 hopper's periodic depth: 2.5 diameters
    body = f"""
[[particles]]
material = "glass"
radius = {R}
count = 120
region = {{ box = {{ min = [-0.028, 0.0, 0.004], max = [0.028, {depth!r}, 0.11] }} }}
"""
    with td.Simulation.from_text(_slab_scene(depth, body, skin=f"skin = {skin!r}"),
                                 base_dir=str(tmp_path), arch="cpu", precision="f64") as sim:
        assert sim.engine.model.grid.dims[1] == cells     # the case being tested
        sim.run()
        # between rebuilds (as the run left them), every touching pair is listed
        stale = {tuple(sorted(pair)) for pair in listed_pairs(sim)[0]}
        touching = pairs_within(sim, 0.0)
        sim.engine.rebuild(sim.engine.count)      # the lists as of now, to compare exactly
        listed, _ = listed_pairs(sim)
        brute = pairs_within(sim, sim.skin)
        p = sim.particles()
        count = sim.particle_count
        ke = sim.kinetic_energy()
        used_skin = sim.skin
    print(f"\nthin slab {depth * 1e3:.1f} mm: skin {used_skin * 1e3:.3f} mm, {len(listed)} pairs "
          f"listed, {len(brute)} by brute force, lowest centre {p['position'][:, 2].min():.5f} m")
    assert count == 120
    assert used_skin == skin
    assert len(listed) == len(set(listed)), "a pair is listed twice"
    assert set(listed) == brute
    assert touching and touching <= stale
    assert np.all(np.isfinite(p["position"]))
    assert p["position"][:, 2].min() > 0.9 * R
    # 120 beads from <= 0.11 m: potential energy ~ 120 m g 0.06 ~ 5e-3 J; settled far below
    assert ke < 1e-5


def test_thin_slab_collision_across_the_face_is_hertz(tmp_path):
    """Two spheres meeting through the periodic face of a slab 2.2 contact distances deep:
    the largest overlap is the elastic Hertz one (a pair counted twice has twice the force and
    reaches (1/2)^(2/5) = 0.76 of it)."""
    depth = 2.2 * 2 * R
    gap = 0.2 * R
    v = 0.5
    y_a = depth - 0.5 * gap - R + 1e-4      # a: just below the upper face, moving +y
    y_b = y_a + 2 * R + gap - depth         # b: its partner through the face, moving -y
    csv = tmp_path / "pair.csv"
    csv.write_text("x,y,z,radius,vx,vy,vz\n"
                   f"0.0,{y_a!r},0.05,{R!r},0.0,{v!r},0.0\n"
                   f"0.0,{y_b!r},0.05,{R!r},0.0,{-v!r},0.0\n")
    m = 2500.0 * 4.0 / 3.0 * np.pi * R ** 3
    e_eff = 1e7 / (2 * (1 - 0.25 ** 2))
    d_max = (15.0 * (m / 2) * (2 * v) ** 2 / (16.0 * e_eff * np.sqrt(R / 2))) ** 0.4
    t_c = 2.943275 * d_max / (2 * v)
    body = f"""
[[particles]]
material = "glass"
file = "pair.csv"
"""
    text = _slab_scene(depth, body, skin=f"dt = {float(t_c / 200)!r}").replace(
        "gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, 0.0]").replace(
        "restitution = 0.9\nfriction = 0.2", "restitution = 1.0\nfriction = 0.0")
    with td.Simulation.from_text(text, base_dir=str(tmp_path), arch="cpu", precision="f64") as sim:
        deepest = 0.0
        position = sim.engine.state.position     # (f64; both particles stay: a periodic slab)
        for _ in range(int(1.5 * (gap / (2 * v) + t_c) / sim.dt)):
            sim.step(1)
            # the two centres read straight from the state after every step (sim.particles()
            # reads and sorts ten fields, most of this loop's time): |dy| does not depend on
            # which of the two comes first
            assert sim.engine.count == 2
            x = position.to_numpy()[:2]
            dy = x[0, 1] - x[1, 1]
            dy -= depth * np.round(dy / depth)
            deepest = max(deepest, 2 * R - abs(dy))
        vel = sim.particles()["velocity"]
    print(f"\nacross the face: largest overlap {deepest:.4e} m, Hertz {d_max:.4e} m; "
          f"velocities after {vel[0, 1]:.4f}, {vel[1, 1]:.4f} m/s")
    # elastic Hertz at 200 steps per contact: the peak is resolved to ~1e-4 relative
    assert deepest == pytest.approx(d_max, rel=0.01)
    assert vel[0, 1] == pytest.approx(-v, rel=0.01) and vel[1, 1] == pytest.approx(v, rel=0.01)


def _slab_fill(depth: float, count: int, extra: str = "") -> str:
    """A [[particles]] fill of ``count`` glass beads over the slab (``extra``: more keys)."""
    return f"""
[[particles]]
material = "glass"
radius = {R}
count = {count}
{extra}region = {{ box = {{ min = [-0.028, 0.0, 0.004], max = [0.028, {depth!r}, 0.11] }} }}
"""


def test_slab_below_two_contact_distances_is_refused(tmp_path):
    depth = 0.95 * 4 * R
    body = _slab_fill(depth, 5)
    with pytest.raises(td.SceneError) as err:
        td.Simulation.from_text(_slab_scene(depth, body), base_dir=str(tmp_path), arch="cpu",
                                precision="f64")
    msg = str(err.value)
    assert "domain.periodic" in msg and "two contact distances" in msg and "along y" in msg


@pytest.mark.parametrize("lens, refused", [(0.4, True), (0.1, False)])
def test_slab_narrower_than_two_gas_gap_reaches_names_the_lens(tmp_path, lens, refused):
    """A slab 2.2 contact distances deep (8.8 mm for 2 mm beads): pairs conducting through a
    fluid lens of 0.4 r reach 4.8 mm, more than half the period, so one image of a partner is
    no longer the only one in reach: refused, naming the key that sets the reach (the effect's
    ``margin_key``). A lens of 0.1 r (4.2 mm) fits and runs (`check` refuses the same way)."""
    depth = 2.2 * 2 * R
    body = _slab_fill(depth, 20, "temperature = 300.0\n") + f"""[thermal]
conduction = true
gas_gap = true
gap_gas_conductivity = 0.026
gas_gap_lens = {lens}
"""
    text = _slab_scene(depth, body).replace(
        "poisson_ratio = 0.25\n", "poisson_ratio = 0.25\nthermal_conductivity = 1.0\n"
        "heat_capacity = 840.0\n", 1)
    if not refused:
        with td.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
            sim.step(10)
            assert sim.particle_count == 20
        return
    with pytest.raises(td.SceneError) as err:
        td.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")
    msg = str(err.value)
    assert "thermal.gas_gap_lens" in msg and "along y" in msg and "gas_gap_pairs = false" in msg
    from taichi_dem.app.cli import main
    scene = tmp_path / "slab.toml"
    scene.write_text(text)
    assert main(["check", str(scene)]) == 2
