"""Sun & Chen's collision conduction (issue 32): ``[thermal] contact_conduction_model =
"collision"``.

Two equal steel spheres (2 mm, real properties) meet head-on at 1 m/s, elastically (restitution
1), with no gravity and no gas, one at 400 K and one at 300 K. Over the one collision the heat
that crosses must be Sun & Chen's

    Q = 0.87 dT pi a_max^2 t_c^(1/2) / ((rho c k)_i^(-1/2) + (rho c k)_j^(-1/2))

with a_max and t_c of Hertz theory at that speed, computed here from the closed forms (not from
the code's tables). The tolerance is 2 %: the flux is evaluated once per step from the overlap at
the step (a rectangle rule over ~350 steps of the collision, an error of order dt/t_c ~ 0.3 %),
the collision window closes on the step after t_c, and the 2.87 of the code's t_c against the
exact 2.943 (15/16)^(2/5) = 2.868 moves Q by 1e-4; the temperature difference itself changes by
1e-5 during the collision. The same collision with a modulus softened 100x (``real_youngs_
modulus`` the steel's) must pass the same heat: the model uses the real a and t_c.

The default model (and "steady" given explicitly) is the spot law, bit for bit, and over an
elastic collision it passes 2 k dT int a dt = 2 k dT 0.7541 a_max t_c (same tolerance); the
collision passes ~0.9/sqrt(Fo) times that. Energy is conserved to round-off with the new term.
A sphere that settles on a fixed one conducts differently while it bounces and, at rest (its
contact older than its collision), exactly the spot law of the default model.
"""
import math

import numpy as np
import pytest
from scipy.special import beta

import taichi_dem
from taichi_dem.thermal.conduction import sun_chen_heat

R = 1.0e-3                       # m: 2 mm spheres
DENSITY, K, C = 7850.0, 45.0, 460.0            # steel: kg/m^3, W/(m K), J/(kg K)
YOUNGS, POISSON = 200.0e9, 0.3
SPEED = 1.0                      # m/s, the relative (normal) speed: each moves at 0.5 m/s
GAP = 1.0e-6                     # m between the surfaces at the start
T_HOT, T_COLD = 400.0, 300.0
DT = 2.0e-8
END = 1.2e-5                     # s: the approach (1 us) and the collision (6 us), then apart
SOFT_END = 4.5e-5                # s: the same with the 100x softer modulus (a 39 us contact)
TOLERANCE = 0.02


def hertz_collision(youngs=YOUNGS, speed=SPEED):
    """(a_max m, t_c s) of the elastic head-on impact of the two spheres (closed forms)."""
    mass = DENSITY * 4.0 / 3.0 * math.pi * R ** 3
    m_eff, r_eff = mass / 2.0, R / 2.0
    e_eff = youngs / (2.0 * (1.0 - POISSON ** 2))
    d_max = (15.0 * m_eff * speed ** 2 / (16.0 * e_eff * math.sqrt(r_eff))) ** 0.4
    # t_c = 2 int_0^d_max dd / (v sqrt(1 - (d/d_max)^(5/2))) = (4/5) B(2/5, 1/2) d_max / v
    t_c = 0.8 * beta(0.4, 0.5) * d_max / speed
    return math.sqrt(r_eff * d_max), t_c


def _scene(tmp_path, model=None, real_youngs=None):
    youngs = YOUNGS if real_youngs is None else YOUNGS / 100.0
    end = END if real_youngs is None else SOFT_END
    real = f"real_youngs_modulus = {real_youngs}\n" if real_youngs is not None else ""
    key = f'contact_conduction_model = "{model}"\n' if model is not None else ""
    x = R + GAP / 2.0
    for name, row in (("hot", (-x, 0.0, 0.0, R, SPEED / 2, 0.0, 0.0)),
                      ("cold", (x, 0.0, 0.0, R, -SPEED / 2, 0.0, 0.0))):
        (tmp_path / f"{name}.csv").write_text(
            "x,y,z,radius,vx,vy,vz\n" + ",".join(repr(float(c)) for c in row) + "\n")
    return f"""
[simulation]
end_time = {end!r}
dt = {DT!r}
gravity = [0.0, 0.0, 0.0]
precision = "f64"
[domain]
min = [-0.01, -0.01, -0.01]
max = [0.01, 0.01, 0.01]
[materials.steel]
density = {DENSITY}
youngs_modulus = {youngs!r}
{real}poisson_ratio = {POISSON}
thermal_conductivity = {K}
heat_capacity = {C}
[[interactions]]
pair = ["steel", "steel"]
restitution = 1.0
friction = 0.0
[[particles]]
material = "steel"
temperature = {T_HOT}
file = "hot.csv"
[[particles]]
material = "steel"
temperature = {T_COLD}
file = "cold.csv"
[thermal]
conduction = true
{key}
[output]
interval = {end / 4!r}
"""


def _collide(tmp_path, model=None, real_youngs=None):
    """(heat into the cold particle J, into the hot one J, temperatures, effect names, relative
    drift of sum m c T, the particles' velocities at the end)."""
    text = _scene(tmp_path, model, real_youngs)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        names = [e.name for e in sim.effects]
        energy = sim.thermal_energy()
        sim.run()
        p = sim.particles()
        drift = (sim.thermal_energy() - energy) / energy
    t = np.asarray(p["temperature"])            # in id order: the hot particle first
    thermal_mass = DENSITY * 4.0 / 3.0 * math.pi * R ** 3 * C
    return ((t[1] - T_COLD) * thermal_mass, (t[0] - T_HOT) * thermal_mass, t, names, drift,
            np.asarray(p["velocity"]))


def _sun_chen(youngs=YOUNGS):
    a_max, t_c = hertz_collision(youngs)
    return sun_chen_heat(T_HOT - T_COLD, a_max, t_c, DENSITY, C, K, DENSITY, C, K)


def test_one_collision_passes_sun_and_chens_heat(tmp_path):
    q_cold, q_hot, _, names, drift, velocity = _collide(tmp_path, "collision")
    assert "collision_conduction" in names and "conduction" in names
    # the collision is over and elastic: the spheres fly apart at their impact speeds
    assert velocity[0][0] == pytest.approx(-SPEED / 2, rel=1e-3)
    assert velocity[1][0] == pytest.approx(SPEED / 2, rel=1e-3)
    expected = _sun_chen()
    a_max, t_c = hertz_collision()
    kappa = K / (DENSITY * C)
    print(f"\n  a_max {a_max:.4e} m, t_c {t_c:.4e} s, Fo {kappa * t_c / a_max ** 2:.3g}: "
          f"DEM {q_cold:.6e} J, Sun & Chen {expected:.6e} J, ratio {q_cold / expected:.4f}")
    assert q_cold == pytest.approx(expected, rel=TOLERANCE)
    # energy: what one gains the other loses, to round-off (the heat is ~1e-9 of sum m c T)
    assert q_hot == pytest.approx(-q_cold, rel=1e-9)
    assert abs(drift) < 1e-14


def test_a_softened_modulus_passes_the_real_collisions_heat(tmp_path):
    # E 100x softer: a 2.5x wider spot for a 6.3x longer contact; the heat is the real one's
    q_cold, q_hot, _, _, drift, _ = _collide(tmp_path, "collision", real_youngs=YOUNGS)
    expected = _sun_chen()
    print(f"\n  softened 100x: DEM {q_cold:.6e} J, Sun & Chen (real modulus) {expected:.6e} J, "
          f"ratio {q_cold / expected:.4f}")
    assert q_cold == pytest.approx(expected, rel=TOLERANCE)
    assert abs(drift) < 1e-14


def test_the_default_is_the_steady_spot_law_unchanged(tmp_path):
    q_default, _, t_default, names, drift, _ = _collide(tmp_path)
    assert "collision_conduction" not in names
    _, _, t_steady, names_steady, _, _ = _collide(tmp_path, "steady")
    assert "collision_conduction" not in names_steady
    np.testing.assert_array_equal(t_default, t_steady)          # bit for bit
    # the spot law 2 k a over the elastic Hertz collision: int a dt = 0.7541 a_max t_c
    a_max, t_c = hertz_collision()
    steady = 2.0 * K * (T_HOT - T_COLD) * beta(0.6, 0.5) / beta(0.4, 0.5) * a_max * t_c
    collision = _sun_chen()
    fourier = K / (DENSITY * C) * t_c / a_max ** 2
    print(f"\n  steady law: DEM {q_default:.6e} J, 2 k dT int a dt {steady:.6e} J, ratio "
          f"{q_default / steady:.4f}; Sun & Chen / steady {collision / steady:.3f} "
          f"(0.9/sqrt(Fo) = {0.9 / math.sqrt(fourier):.3f})")
    assert q_default == pytest.approx(steady, rel=TOLERANCE)
    assert collision > 2.0 * steady
    assert abs(drift) < 1e-14


def test_a_bad_model_is_a_scene_error(tmp_path):
    text = _scene(tmp_path, "transient")
    with pytest.raises(taichi_dem.SceneError, match="contact_conduction_model"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")
    text = _scene(tmp_path, "collision").replace("conduction = true", "conduction = false")
    with pytest.raises(taichi_dem.SceneError, match="contact_conduction_model.*conduction is off"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64")


def _resting_scene(tmp_path, model):
    """A free steel sphere settling under gravity on a fixed one (softened 100x, restitution
    0.2): a slow collision, then an enduring contact."""
    rows = (("base", (0.0, 0.0, 0.0, R)), ("top", (0.0, 0.0, 2.0 * R + 1e-7, R)))
    for name, row in rows:
        (tmp_path / f"{name}.csv").write_text("x,y,z,radius\n" + ",".join(map(repr, row)) + "\n")
    key = f'contact_conduction_model = "{model}"\n'
    return f"""
[simulation]
end_time = 4e-3
dt = 2e-7
gravity = [0.0, 0.0, -9.81]
precision = "f64"
[domain]
min = [-0.01, -0.01, -0.01]
max = [0.01, 0.01, 0.01]
[materials.steel]
density = {DENSITY}
youngs_modulus = {YOUNGS / 100.0!r}
real_youngs_modulus = {YOUNGS!r}
poisson_ratio = {POISSON}
thermal_conductivity = {K}
heat_capacity = {C}
[[interactions]]
pair = ["steel", "steel"]
restitution = 0.2
friction = 0.0
[[particles]]
material = "steel"
fixed = true
temperature = {T_HOT}
file = "base.csv"
[[particles]]
material = "steel"
temperature = {T_COLD}
file = "top.csv"
[thermal]
conduction = true
{key}
[output]
interval = 1e-3
"""


def test_an_enduring_contact_keeps_the_spot_law(tmp_path):
    heats = {}
    for model in ("steady", "collision"):
        text = _resting_scene(tmp_path, model)
        with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
            sim.run(2e-3)
            t_early = np.asarray(sim.particles()["temperature"])
            sim.run()
            p = sim.particles()
            late = np.asarray(p["temperature"])[1]
            assert abs(np.asarray(p["velocity"])[1][2]) < 1e-4        # at rest on the base
        # the late heat per kelvin of difference (the early heats leave different differences)
        heats[model] = (t_early[1] - T_COLD, (late - t_early[1]) / (t_early[0] - t_early[1]))
    print(f"\n  first 2 ms: collision / steady {heats['collision'][0] / heats['steady'][0]:.6f}; "
          f"last 2 ms {heats['collision'][1] / heats['steady'][1]:.12f}")
    # the collisions (the drop and its bounces) conduct their real heat: here less than the
    # softened spot law's (its "static"-corrected spot 100^(1/5 - 1/3) = 0.54x the real one's
    # radius for 100^(2/5) = 6.3x the real contact time); once the sphere rests, the same spot
    # law, to round-off
    assert abs(heats["collision"][0] / heats["steady"][0] - 1.0) > 0.01
    assert heats["collision"][1] == pytest.approx(heats["steady"][1], rel=1e-8)


# --- a sphere bouncing off an isothermal wall (the wall variant) -------------------------------
#
# The same steel sphere hits a steel plate (a mesh body: its triangles) held at T_HOT head-on at
# 1 m/s, elastically. Hertz
# with R* = R, m* = m, E* = E / (2 (1 - nu^2)); the wall is a semi-infinite body at its
# temperature, Sun & Chen's own case, so the heat is the same formula with the wall's rho c k.
# Tolerance 2 % as for the pair (the same rectangle rule over ~600 steps of the collision).

def _wall_scene(tmp_path, model):
    x = R + GAP
    (tmp_path / "ball.csv").write_text("x,y,z,radius,vx,vy,vz\n" + ",".join(
        repr(float(c)) for c in (0.0, 0.0, x, R, 0.0, 0.0, -SPEED)) + "\n")
    # the pair's settings, materials and interaction; twice as long (the ball flies back)
    head = _scene(tmp_path, model).split("[[particles]]")[0]
    head = head.replace(f"end_time = {END!r}", f"end_time = {END * 2!r}")
    return head + f"""
[[bodies]]
name = "plate"
material = "steel"
temperature = {T_HOT}
mesh = {{ builder = "box", min = [-0.005, -0.005, -0.002], max = [0.005, 0.005, 0.0], normals = "outward" }}
[[particles]]
material = "steel"
temperature = {T_COLD}
file = "ball.csv"
[thermal]
conduction = true
wall_conduction = true
contact_conduction_model = "{model}"
[output]
interval = {END / 2!r}
"""


def test_a_bounce_off_a_hot_wall_passes_sun_and_chens_heat(tmp_path):
    mass = DENSITY * 4.0 / 3.0 * math.pi * R ** 3
    e_eff = YOUNGS / (2.0 * (1.0 - POISSON ** 2))
    d_max = (15.0 * mass * SPEED ** 2 / (16.0 * e_eff * math.sqrt(R))) ** 0.4
    a_max, t_c = math.sqrt(R * d_max), 0.8 * beta(0.4, 0.5) * d_max / SPEED
    expected = sun_chen_heat(T_HOT - T_COLD, a_max, t_c, DENSITY, C, K, DENSITY, C, K)
    steady = 2.0 * K * (T_HOT - T_COLD) * beta(0.6, 0.5) / beta(0.4, 0.5) * a_max * t_c
    heats = {}
    for model in ("steady", "collision"):
        with taichi_dem.Simulation.from_text(_wall_scene(tmp_path, model), base_dir=str(tmp_path),
                                             precision="f64") as sim:
            names = [e.name for e in sim.effects]
            sim.run()
            p = sim.particles()
            into_wall = float(np.asarray(sim.series["thermal/wall_heat"])[-1])
        assert ("wall_collision_conduction" in names) == (model == "collision")
        assert np.asarray(p["velocity"])[0][2] == pytest.approx(SPEED, rel=1e-3)  # bounced
        heats[model] = (float(np.asarray(p["temperature"])[0]) - T_COLD) * mass * C
        # energy: the plate's tally (the time integral of its heat flow, which a body records
        # over every step) is what the sphere gained, to round-off (the heat is ~1e-7 of the
        # sphere's m c T)
        assert -into_wall == pytest.approx(heats[model], rel=1e-6)
    print(f"\n  wall: a_max {a_max:.4e} m, t_c {t_c:.4e} s: collision {heats['collision']:.6e} J, "
          f"Sun & Chen {expected:.6e} J ({heats['collision'] / expected:.4f}); steady "
          f"{heats['steady']:.6e} J, 2 k dT int a dt {steady:.6e} J "
          f"({heats['steady'] / steady:.4f})")
    assert heats["collision"] == pytest.approx(expected, rel=TOLERANCE)
    assert heats["steady"] == pytest.approx(steady, rel=TOLERANCE)
