"""The wall heat law of coarse-grained particles (issue 10 item 6; thermal/coarse_grained.py).

A particle of a material with ``coarse_grained = { represented_diameter = d, ... }`` takes heat
from a wall as the bed of d-sized particles it stands for: G = w A_p h(t), h(t) = alpha_WS
erfcx(alpha_WS sqrt(t / e)), t the (thermal) time since it came to rest against the wall.

Checks against closed forms:
- h(t) in the kernel against math.erfc (Numerical Recipes' fit, 1.2e-7) and the limits
  alpha_WS (t -> 0) and sqrt(e / (pi t)) (t -> inf), and alpha_WS against Schlünder's formula
  (correlations.py, itself checked against the sphere-plane gas integral);
- one particle resting on a hot plane from t = 0, with a real heat capacity: its temperature
  follows T_w - T = (T_w - T_0) exp(-A_p/(m c) integral_0^t h), the integral in closed form
  (Carslaw & Jaeger 2.7), over 5 s. The explicit update (h at the middle of each step) errs
  in proportion to the thermal step: dt G_0/(m c) = 3.6e-5 at dt = 1e-4 s (measured 4e-5
  relative on T - T_w; asserted 1e-4); f64;
- the same thermal history with time_scale = 10 (a tenth of the simulated time, a thermal step
  ten times longer: dt G_0/(m c) = 3.6e-4, measured 3.4e-4, asserted 1e-3);
- a particle standing off the wall: the weight 1 - gap/(reach R); beyond the reach nothing;
- the contact-spot and gas-gap laws of the big sphere are off for these particles (the flow is
  the law's alone, while another material's particle beside it keeps them).
"""
import math

import numpy as np
import pytest

import taichi_dem
from taichi_dem.errors import SceneError
from taichi_dem.thermal import coarse_grained as cg
from taichi_dem.thermal import correlations

R = 0.01
RHO, C, K_S, K_G = 870.0, 800.0, 0.3, 0.04
D_REAL, POROSITY = 100e-6, 0.45
T_0, T_W = 700.0, 300.0
LENS = 0.2


def _scene(tmp_path, rows, *, end=0.5, dt=1e-4, time_scale=1.0, heat_capacity=C,
           other=None, coarse=True, body=False):
    lines = ["x,y,z,radius"] + [",".join(repr(float(c)) for c in (*p, R)) for p in rows]
    (tmp_path / "p.csv").write_text("\n".join(lines) + "\n")
    coarse_key = (f'coarse_grained = {{ represented_diameter = "{D_REAL * 1e6:g} um", '
                  f'bed_porosity = {POROSITY} }}') if coarse else ""
    other_fill = ""
    if other is not None:
        (tmp_path / "q.csv").write_text(f"x,y,z,radius\n{other[0]!r},{other[1]!r},{other[2]!r},{R!r}\n")
        other_fill = f"""[[particles]]
material = "glass"
fixed = true
temperature = {T_0}
file = "q.csv"
"""
    scale = f"time_scale = {time_scale}" if time_scale != 1.0 else ""
    return f"""
[simulation]
end_time = {end}
dt = {dt}
gravity = [0.0, 0.0, 0.0]
precision = "f64"
[domain]
min = [-0.1, -0.1, -0.05]
max = [0.1, 0.1, 0.1]
[materials.ash]
density = {RHO}
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = {K_S}
heat_capacity = {heat_capacity}
{coarse_key}
[materials.glass]
density = {RHO}
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = {K_S}
heat_capacity = 1e12
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = 45.0
heat_capacity = 480.0
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["ash", "steel"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["ash", "glass"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
{PLATE_BODY if body else PLATE_WALL}
[[particles]]
material = "ash"
fixed = {"false" if body else "true"}
temperature = {T_0}
file = "p.csv"
{other_fill}
[thermal]
conduction = false
wall_conduction = true
gas_gap = true
gap_gas_conductivity = {K_G}
gas_gap_lens = {LENS}
{scale}
[output]
interval = 0.05
"""


PLATE_WALL = f"""[[walls]]
name = "plate"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "steel"
temperature = {T_W}"""

# mesh contacts are for moving particles: a free one at rest without gravity stays put
PLATE_BODY = f"""[[bodies]]
name = "plate"
material = "steel"
temperature = {T_W}
mesh = {{ builder = "box", min = [-0.08, -0.08, -0.02], max = [0.08, 0.08, 0.0], normals = "outward" }}"""


def _bed(heat_capacity=C):
    """alpha_WS and e of the represented bed, at the law's reference temperature."""
    class _Coarse:
        represented_diameter, bed_porosity, surface_coverage, roughness = D_REAL, POROSITY, 0.8, 0.0

    class _Material:
        density, thermal_conductivity = RHO, K_S
    _Material.heat_capacity = heat_capacity

    return cg.represented_bed(_Material, _Coarse, K_G, 0.5 * (T_0 + T_W))


class _Owner:
    """Stands for a simulation on the shared runtime (engine/backend.py: the one ti.init)."""

    def _mark_stale(self, reason):
        pass


def test_bed_coefficient_and_its_limits():
    import taichi as ti
    from taichi_dem.engine import backend
    owner = _Owner()
    backend.acquire(owner, "cpu", "f64")
    ages = np.array([0.0, 1e-6, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e6])
    out = ti.field(ti.f64, len(ages))
    a, e = 3000.0, 870.0 * 0.55 * 800.0 * 0.12

    @ti.kernel
    def fill(age: ti.types.ndarray()):
        for k in range(age.shape[0]):
            out[k] = cg.bed_coefficient(a, e, age[k])

    fill(ages)
    got = out.to_numpy()
    want = np.array([cg.bed_coefficient_reference(a, e, t) for t in ages])
    np.testing.assert_allclose(got, want, rtol=3e-7)
    assert got[0] == pytest.approx(a, rel=1e-7)                           # alpha_WS at t = 0
    assert got[-1] == pytest.approx(math.sqrt(e / (math.pi * 1e6)), rel=1e-4)   # the bed's own
    # the integral's closed form against a fine quadrature of the reference
    t = np.linspace(0.0, 2.0, 200_001)
    h = np.array([cg.bed_coefficient_reference(a, e, x) for x in t[1:]])
    mid = 0.5 * (np.concatenate([[a], h[:-1]]) + h)
    assert np.sum(mid * np.diff(t)) == pytest.approx(cg.bed_heat_reference(a, e, 2.0), rel=1e-4)


def test_represented_bed_is_schlunders_first_layer_and_zbs():
    bed = _bed()
    ws = correlations.wall_contact_coefficient(D_REAL, K_G, 0.5 * (T_0 + T_W))
    assert bed["alpha_ws"] == pytest.approx(ws["alpha_ws"], rel=1e-12)
    assert bed["bed_density"] == pytest.approx(RHO * (1 - POROSITY))
    assert bed["bed_conductivity"] == pytest.approx(correlations.zehner_schlunder(K_S, K_G, POROSITY))
    # a 100 um particle: a first-layer coefficient of thousands, a bed coefficient of hundreds
    assert 1000.0 < bed["alpha_ws"] < 10000.0


def _expected_temperature(time):
    bed = _bed()
    mass = RHO * 4.0 / 3.0 * math.pi * R ** 3
    area = cg.wall_area_per_particle(R, 0.8)
    heat = cg.bed_heat_reference(bed["alpha_ws"], bed["effusivity_sq"], time)
    return T_W + (T_0 - T_W) * math.exp(-area * heat / (mass * C))


@pytest.mark.parametrize("time_scale, tolerance", [(1.0, 1e-4), (10.0, 1e-3)])
def test_particle_resting_on_a_hot_plane_follows_the_closed_form(tmp_path, time_scale,
                                                                 tolerance):
    thermal_end = 5.0
    text = _scene(tmp_path, [(0.0, 0.0, R * (1 - 1e-4))], end=thermal_end / time_scale,
                  time_scale=time_scale)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        names = {e.name for e in sim.effects}
        assert {"coarse_grained_wall", "wall_contact_age"} <= names
        sim.run()
        temperature = sim.particles()["temperature"][0]
    expected = _expected_temperature(thermal_end)
    print(f"\n  S = {time_scale:g}: T = {temperature:.6f} K, closed form {expected:.6f} K "
          f"(fed {T_0}, wall {T_W})")
    assert (T_0 - expected) > 20.0                   # it does cool, by tens of kelvin
    assert (temperature - T_W) == pytest.approx(expected - T_W, rel=tolerance)


@pytest.mark.parametrize("gap_over_r, body", [(0.1, False), (0.3, False), (0.05, True),
                                              (0.25, True)])
def test_weight_falls_with_the_gap_and_ends_at_the_reach(tmp_path, gap_over_r, body):
    # a huge heat capacity keeps T constant: the wall's heat flow is then G(t) (T_0 - T_W)
    # (it also makes the represented bed's e = rho_b c k_bed huge: h stays near alpha_WS)
    text = _scene(tmp_path, [(0.01, 0.02, R * (1 + gap_over_r))], end=0.1, heat_capacity=1e12,
                  body=body)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run()
        key = "bodies/plate/heat_flow" if body else "walls/plate/heat_flow"
        q = np.asarray(sim.series[key][1:])
        times = np.asarray(sim.series["time"][1:])
    bed = _bed(1e12)
    weight = max(0.0, 1.0 - gap_over_r / LENS)
    dt = 1e-4

    def law(age):
        return (weight * cg.wall_area_per_particle(R, 0.8) * (T_0 - T_W)
                * cg.bed_coefficient_reference(bed["alpha_ws"], bed["effusivity_sq"], age))
    if body:
        # a body's series is the mean over the output interval (sensors/loads.py): of the
        # steps k = 1..500 ending in it, each with h at its middle, (k - 1/2) dt
        want = np.array([np.mean([law((k - 0.5) * dt) for k in range(
            int(round((t - 0.05) / dt)) + 1, int(round(t / dt)) + 1)]) for t in times])
    else:
        # a plane wall's is the step that ends at t: h at its middle, t - dt/2
        want = np.array([law(t - 0.5 * dt) for t in times])
    print(f"\n  gap {gap_over_r} R: wall heat flow {q[-1]:.6e} W, law {want[-1]:.6e} W")
    if weight == 0.0:
        assert np.all(q == 0.0)
    else:
        np.testing.assert_allclose(-q if q[-1] < 0 else q, want, rtol=1e-6)


def test_the_big_spheres_own_wall_laws_stay_off_for_coarse_particles_only(tmp_path):
    # an ash particle (coarse-grained) and a glass one (not), both touching the plate far
    # apart: the plate's heat flow is the coarse law for the ash plus spot + gas gap for glass
    def run(coarse):
        text = _scene(tmp_path, [(0.0, 0.0, R * (1 - 1e-4))], end=0.05, heat_capacity=1e12,
                      other=(0.05, 0.05, R * (1 - 1e-4)), coarse=coarse)
        with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
            names = {e.name for e in sim.effects}
            held = hasattr(sim.engine.state, "wall_contact_steps")
            # without the key nothing of the law is compiled or allocated (the contact age is
            # the default "schlunder" gas-gap wall law's too, and counted once)
            assert ("coarse_grained_wall" in names) == coarse
            assert held and sum(e.name == "wall_contact_age" for e in sim.effects) == 1
            assert ("coarse_alpha_ws" in sim.engine.table) == coarse
            sim.run()
            return abs(sim.series["walls/plate/heat_flow"][-1])
    both_plain = run(False)          # two big spheres, spot + gas gap each
    mixed = run(True)
    bed = _bed(1e12)
    law = cg.wall_area_per_particle(R, 0.8) * cg.bed_coefficient_reference(
        bed["alpha_ws"], bed["effusivity_sq"], 0.05 - 0.5e-4) * (T_0 - T_W)
    # by symmetry each plain sphere carried half of both_plain
    assert mixed == pytest.approx(0.5 * both_plain + law, rel=1e-6)
    assert law > 10.0 * 0.5 * both_plain         # the represented bed conducts far better


@pytest.mark.parametrize("change, message", [
    ("bed_porosity = 0.95", "bed_porosity"),
    ("surface_coverage = 1.5", "surface_coverage"),
    ("colour = 1", "colour"),
])
def test_bad_coarse_grained_keys_are_named(tmp_path, change, message):
    text = _scene(tmp_path, [(0.0, 0.0, R)]).replace(
        "bed_porosity = 0.45 }", f"bed_porosity = 0.45, {change} }}" if "bed" not in change
        else f"{change} }}")
    with pytest.raises(SceneError, match=message):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path))


def test_coarse_grained_without_a_hot_wall_is_refused(tmp_path):
    text = _scene(tmp_path, [(0.0, 0.0, R)]).replace(f"temperature = {T_W}\n", "", 1)
    text = "\n".join(x for x in text.splitlines() if not x.startswith(("gas_gap", "gap_gas")))
    with pytest.raises(SceneError, match="coarse_grained"):
        taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path))


# --- a rotating drum of coarse-grained glass beads against the real-size one --------------
#
# The experiment of tests/verification/drum_wall_heat.py (0.1 m drum slice, periodic, 15 % fill,
# a 72-sided shell at 100 C with 16 lifters half a bead high so that the bed rides with it, the
# bed switched to 20 C once it rolls, mechanics at 12 rpm with time_scale 2: the thermal contact
# time of 6 rpm), twice: with the real 2 mm beads (the default gas-gap law,
# test_drum_wall_heat.py) and with 4 mm beads that stand for them (coarse graining x2; 2 mm
# lifters). The wall-to-bed coefficient is compared over the wetted arc (the heat flow over the
# arc of the measured angle): the covered-triangle area under-reads for the coarse beads, which
# leave ~27 % of the triangles under the bed untouched at a sample.
#
# Measured (2026-12-04, docs/verification/first_layer.md): over the arc, coarse 140.2 and real
# 134.8 W/(m^2 K), 1.04 x (both ride at 0.95-0.96); Schlünder-Mollekopf 148-149 at the packed
# bed's porosity 0.407, so coarse 0.95 x, real 0.91 x; since 2026-12-05 the model is evaluated
# at the porosity the coarse run measures in its riding bed (drum_wall_heat.py): 143.0, coarse
# 0.98 x. Over the covered triangles: coarse 185.7 (1.46 x the real 126.8). Asserted: the
# arc figures within 10 % of each other (the tolerance for the coarse-grained law
# against the real-size drum) and the coarse one within 25 % of the model (the model's own
# uncertainty, test_drum_wall_heat.py).


@pytest.fixture(scope="module")
def coarse_and_real_drums():
    from drum_wall_heat import drum_wall_heat, models
    coarse = drum_wall_heat(rpm=6.0, time_scale=2.0, radius=0.002, length=0.016, fill=0.15,
                            settle=0.8, startup=1.2, measure=0.6, represented_diameter=0.002,
                            flights=16, flight_height=2e-3, model="schlunder")
    real = drum_wall_heat(rpm=6.0, time_scale=2.0, fill=0.15, length=0.005, settle=0.4,
                          startup=0.6, measure=0.3, dt=2.5e-5, output_interval=0.025,
                          threads=1, flights=16, flight_height=1e-3, model="schlunder",
                          skin=6e-4)      # (test_drum_wall_heat.py says why)
    for r in (coarse, real):
        r["kwargs"] = {"model": "schlunder"}
    model = models(coarse, radius=1e-3)["physical"]
    print(f"\n  coarse-grained drum, 6 rpm: {coarse['h']:.1f} (arc {coarse['h_arc']:.1f}) W/(m^2 K), "
          f"rides at {coarse['ride']:.2f}; real-size {real['h']:.1f} (arc {real['h_arc']:.1f}), "
          f"rides at {real['ride']:.2f}; model {model['alpha']:.1f}; "
          f"{coarse['wall_seconds'] + real['wall_seconds']:.0f} s wall")
    return coarse, real, model


@pytest.mark.slow
def test_coarse_grained_drum_against_the_real_size_one(coarse_and_real_drums):
    coarse, real, model = coarse_and_real_drums
    for r in (coarse, real):
        assert r["lost"] == 0 and r["froude_mech"] < 0.01 and r["ride"] > 0.85
    assert coarse["h_arc"] == pytest.approx(real["h_arc"], rel=0.10)
    assert coarse["h_arc"] == pytest.approx(model["alpha"], rel=0.25)


def test_an_inserted_particle_starts_with_no_wall_contact_age(tmp_path):
    # a factory reuses the slot of a removed particle: the wall-contact clock must start at 0,
    # not at what the slot held (else the new particle's first wall contact would count as old)
    text = _scene(tmp_path, [(0.0, 0.0, R * (1 - 1e-4))], end=0.1) + f"""
[[factories]]
name = "inlet"
material = "ash"
radius = {R}
region = {{ box = {{ min = [0.03, 0.03, 0.03], max = [0.07, 0.07, 0.07] }} }}
velocity = [0.0, 0.0, 0.0]
temperature = {T_0}
mass_rate = [[0.0, "0.01 t/h"]]
"""
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        engine = sim.engine
        s = engine.state
        n = engine.count
        steps, touch = s.wall_contact_steps.to_numpy(), s.wall_touch.to_numpy()
        steps[n], touch[n] = 12345, 1                   # left by a removed particle
        s.wall_contact_steps.from_numpy(steps)
        s.wall_touch.from_numpy(touch)
        mass = RHO * 4.0 / 3.0 * math.pi * R ** 3
        engine.insert({"position": np.array([[0.05, 0.05, 0.05]]), "velocity": np.zeros((1, 3)),
                       "radius": np.array([R]), "mass": np.array([mass]),
                       "material": np.array([0]), "key": np.array([n]), "serial": np.array([n]),
                       "origin": np.array([0]), "birth_time": np.array([0.0]),
                       "temperature": np.array([T_0]),
                       "inverse_thermal_mass": np.array([1.0 / (mass * C)])})
        assert s.wall_contact_steps.to_numpy()[n] == 0 and s.wall_touch.to_numpy()[n] == 0
