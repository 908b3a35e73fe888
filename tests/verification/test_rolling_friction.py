"""Rolling friction on a plane wall: stopping distance, rest without chatter, spin-up and stop.

Models (PHYSICS.md "Rolling friction"): the constant directional torque (CDT, EDEM type A)
tau = -mu_r F_n R w_rel/|w_rel|, limited so it cannot reverse the spin within a step; and EPSD
(Ai, Chen, Rotter & Ooi 2011), a rolling spring capped at the same mu_r F_n R.

Checks, all in one simulation (independent spheres 5 cm apart on one floor, gravity -z):
1. Rolling without slip (v0, w0 = v0/R) under a constant resisting torque mu_r m g R stops
   after s = 7 v0^2 / (10 mu_r g) (rigid-body mechanics: m dv/dt = F, I dw/dt = -F R - tau,
   dv/dt = R dw/dt with I = 2/5 m R^2 give dv/dt = -5/7 mu_r g). Three speeds with CDT, one with
   EPSD (once rolling, its spring is saturated at the same cap, so the same s holds).
2. A sphere resting on the floor with a tiny initial spin (1e-3 rad/s) settles and then stays
   at rest: |w| and the drift stay at round-off level over 10^4 steps. Without the limiter the
   torque would flip the spin every step with amplitude mu_r g dt / (0.4 R) ~ 1e-2 rad/s.
3. A sphere on an incline with tan(a) = mu_r / 2 must be held at rest by the rolling
   resistance: EPSD holds it (its spring gives a static torque; its viscous part, Ai et al.
   2011 model C, damps the rocking on that spring). The constant-torque model creeps downhill
   for ever (a known limit of the model; xfail, strict, so a fix shows up).
4. A sphere set spinning (w0, v = 0) on the floor slides (friction mu), reaches rolling and
   then stops under rolling friction: CDT and EPSD. Analytic: during sliding
   dv/dt = mu g, dw/dt = -(mu + mu_r) g / (0.4 R) (the rolling torque acts too), rolling starts
   at t1 where v = R w, then the rolling phase covers v1^2 / (2 * 5/7 mu_r g).

Tolerances (derived): Velocity Verlet integrates a constant deceleration exactly, so the time
error is only where the motion changes regime (start, slip-to-roll, stop), each at most one step
of travel, v dt ~ 6e-5 m, i.e. <= 3e-4 of s (s >= 0.2 m here). The engine applies the contact
force at the overlap centre, R - d/2 from the sphere centre: the rolling deceleration becomes
5/7 mu_r g (1 + 0.43 d/(2R)), relative ~1e-4 here (d/R = 3.6e-4). The spheres start at the
static Hertz overlap, so no normal oscillation takes energy. We assert 1e-3 relative on s, about
3x the sum of these bounds. Phase 3 also has the tangential spring's stick transient at the
slip-to-roll transition (the spring load F/S_t ~ 2e-7 m) - negligible - and is asserted at 2e-3.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

R = 0.01
BALL = dict(density=2500.0, youngs_modulus=1e8, poisson_ratio=0.25)
FLOOR = dict(density=7800.0, youngs_modulus=2e11, poisson_ratio=0.3)
G = 9.81
MU_R = 0.1
MU = 0.5
ROLL_SPEEDS = [0.2, 0.4, 0.6]
EPSD_ROLL_SPEED = 0.4
SPIN0 = 60.0          # rad/s for the spin-up spheres
TOL = 1e-4
SPIN_UP_TOL = 1e-3


def _static_overlap():
    m = h.sphere_mass(R, BALL["density"])
    e_eff = h.youngs_eff(BALL["youngs_modulus"], BALL["poisson_ratio"], FLOOR["youngs_modulus"],
                         FLOOR["poisson_ratio"])
    return (m * G / (4.0 / 3.0 * e_eff * math.sqrt(R))) ** (2.0 / 3.0)


def _spin_up_distance(w0, mu, mu_r):
    """Distance travelled by a sphere started with spin w0 (rolling direction +x), no velocity."""
    a = mu * G                                   # dv/dt while sliding
    alpha = (mu + mu_r) * G / (0.4 * R)          # -dw/dt while sliding
    t1 = R * w0 / (a + R * alpha)                # v = R w
    v1 = a * t1
    return 0.5 * a * t1 ** 2 + v1 ** 2 / (2.0 * 5.0 / 7.0 * mu_r * G)


@pytest.fixture(scope="module")
def rolling(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rolling")
    d0 = _static_overlap()
    z0 = R - d0
    spacing = 0.05
    # CDT spheres: rolling at three speeds, one at rest (tiny spin), one spun up
    cdt_pos = [[0.0, k * spacing, z0] for k in range(5)]
    cdt_vel = [[v, 0, 0] for v in ROLL_SPEEDS] + [[0, 0, 0], [0, 0, 0]]
    cdt_ang = [[0, v / R, 0] for v in ROLL_SPEEDS] + [[0, 1e-3, 0], [0, SPIN0, 0]]
    # EPSD spheres: one rolling, one spun up
    epsd_pos = [[0.0, (5 + k) * spacing, z0] for k in range(2)]
    epsd_vel = [[EPSD_ROLL_SPEED, 0, 0], [0, 0, 0]]
    epsd_ang = [[0, EPSD_ROLL_SPEED / R, 0], [0, SPIN0, 0]]
    t_stop = max(max(7 * v / (5 * MU_R * G) for v in ROLL_SPEEDS + [EPSD_ROLL_SPEED]),
                 1.0)
    text = (h.header(gravity=(0, 0, -G), lo=(-0.05, -0.05, -0.01), hi=(1.0, 8 * spacing, 0.05),
                     rayleigh_fraction=0.2)
            + h.material("ball", **BALL) + h.material("ball_epsd", **BALL)
            + h.material("floor", **FLOOR)
            + h.interaction("ball", "floor", 0.5, MU, MU_R)
            + h.interaction("ball_epsd", "floor", 0.5, MU, MU_R, model="epsd")
            + h.all_interactions(["ball", "ball_epsd"], 0.5, MU)
            + h.wall("floor", (0, 0, 0), (0, 0, 1), "floor")
            + h.csv_fill(tmp, "cdt.csv", "ball", cdt_pos, R, cdt_vel, cdt_ang)
            + h.csv_fill(tmp, "epsd.csv", "ball_epsd", epsd_pos, R, epsd_vel, epsd_ang))
    rest_w, rest_x = [], []
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        dt = sim.dt
        x0 = sim.particles()["position"].copy()
        # settle the resting sphere, then watch it for 10^4 steps while the others roll
        chunk = 500
        n_total = int(math.ceil(1.15 * t_stop / dt))
        done = 0
        while done < n_total:
            sim.step(chunk)
            done += chunk
            p = sim.particles()
            rest_w.append(p["angular_velocity"][3].copy())
            rest_x.append(p["position"][3].copy())
        final = sim.particles()
    return dict(dt=dt, d0=d0, x0=x0, final=final, rest_w=np.array(rest_w), rest_x=np.array(rest_x),
                chunk=chunk)


def _elastic_rolling_length(d0):
    """EPSD: the rolling spring k_r = 2.25 S_n mu_r^2 R^2 holds the cap mu_r R F_n at a rotation
    F_n / (2.25 S_n mu_r R); with F_n / S_n = 2 d / 3 (Hertz) the sphere rolls back by
    R times that, 0.296 d / mu_r, when it stops and the loaded spring relaxes (m)."""
    return 2.0 / 3.0 * d0 / (2.25 * MU_R)


def test_rolling_stop_distance(rolling):
    x0, p, d0 = rolling["x0"], rolling["final"], rolling["d0"]
    travelled = p["position"][:, 0] - x0[:, 0]
    # lever-arm correction: the contact force acts R - d/2 from the centre; rolling then needs
    # v = (R - d/2) w, so w0 = v0/R is resolved by the tangential spring into a rolling speed
    # lower by 0.286 d/(2R), and the deceleration is higher by 0.43 d/(2R): s(1 - d/(2R))
    arm = 1.0 - d0 / (2 * R)
    rows = [(f"CDT v0 = {v}", k, 7 * v ** 2 / (10 * MU_R * G), 0.0) for k, v in enumerate(ROLL_SPEEDS)]
    rows.append((f"EPSD v0 = {EPSD_ROLL_SPEED}", 5, 7 * EPSD_ROLL_SPEED ** 2 / (10 * MU_R * G),
                 2 * _elastic_rolling_length(d0)))
    print(f"\nrolling friction (dt = {rolling['dt']:.3g} s, d0/(2R) = {d0 / (2 * R):.2e})")
    for name, k, s, extra in rows:
        print(f"  {name}: s = {travelled[k]:.6f} m, 7 v0^2/(10 mu_r g) = {s:.6f} m "
              f"({travelled[k] / s - 1:+.2e}; after the lever-arm correction "
              f"{travelled[k] / (s * arm) - 1:+.2e}), final |v| {np.linalg.norm(p['velocity'][k]):.1e} "
              f"m/s, |w| {np.linalg.norm(p['angular_velocity'][k]):.1e} rad/s")
    for name, k, s, extra in rows:
        assert travelled[k] == pytest.approx(s * arm, rel=TOL, abs=extra), name
        # uncorrected, within the first-order lever-arm bound
        assert abs(travelled[k] / s - 1) <= d0 / R + TOL + extra / s, name
    assert np.abs(p["position"][:, 1] - x0[:, 1]).max() < 1e-12


def test_cdt_comes_to_rest(rolling):
    p = rolling["final"]
    step_dv = 5 / 7 * MU_R * G * rolling["dt"]       # one step of the rolling deceleration
    for k in (0, 1, 2, 4):
        assert np.linalg.norm(p["velocity"][k]) < 1e-6 * step_dv, k
        assert np.linalg.norm(p["angular_velocity"][k]) * R < 1e-6 * step_dv, k


def test_epsd_comes_to_rest(rolling):
    p = rolling["final"]
    step_dv = 5 / 7 * MU_R * G * rolling["dt"]
    for k in (5, 6):
        print(f"  EPSD sphere {k}: final |v| {np.linalg.norm(p['velocity'][k]):.1e} m/s, "
              f"|w| {np.linalg.norm(p['angular_velocity'][k]):.1e} rad/s")
    for k in (5, 6):
        assert np.linalg.norm(p["velocity"][k]) < 1e-2 * step_dv, k


def test_spin_up_then_stop(rolling):
    x0, p, d0 = rolling["x0"], rolling["final"], rolling["d0"]
    s = _spin_up_distance(SPIN0, MU, MU_R)
    for name, k, extra in (("CDT", 4, 0.0), ("EPSD", 6, 2 * _elastic_rolling_length(d0))):
        travelled = p["position"][k, 0] - x0[k, 0]
        print(f"  spin-up {name}: s = {travelled:.6f} m, theory {s:.6f} m ({travelled / s - 1:+.2e})")
        assert travelled == pytest.approx(s, rel=SPIN_UP_TOL, abs=extra), name


def test_resting_sphere_no_chatter(rolling):
    w = rolling["rest_w"]
    x = rolling["rest_x"]
    dt = rolling["dt"]
    chatter = MU_R * G * dt / (0.4 * R)       # the per-step spin flip without the limiter
    # the initial 1e-3 rad/s is gone within the first chunk; after that nothing moves
    settled = slice(1, None)
    print(f"  resting sphere: max |w| after settling {np.abs(w[settled]).max():.1e} rad/s "
          f"(chatter scale {chatter:.1e}), drift {np.abs(x[settled] - x[1]).max():.1e} m over "
          f"{(len(x) - 1) * rolling['chunk']} steps")
    assert np.abs(w[settled]).max() < 1e-6 * chatter
    assert np.abs(x[settled] - x[1]).max() < 1e-12


@pytest.mark.parametrize("model", [
    pytest.param("constant_torque", marks=pytest.mark.xfail(
        strict=True, reason="a known limit of the constant-torque model (README): it cannot hold "
        "a static torque; the spin limiter acts like a viscous term I/dt, so the sphere creeps "
        "downhill at w ~ g sin(a) dt / (0.4 R) for ever. Use EPSD for static piles.")),
    "epsd"])
def test_sphere_held_on_gentle_incline(tmp_path, model):
    """A sphere on an incline with tan(a) = mu_r / 2 (the rolling resistance mu_r F_n R exceeds
    the downhill torque ~ m g sin(a) R) must come to rest and stay: its centre moves less than
    1e-9 m over the last 10^4 steps (a thousandth of the static overlap; a creep at the
    limiter's scale, w = g sin(a) dt / (0.4 R), moves 1.4e-5 m in that time)."""
    a = math.atan(0.5 * MU_R)
    n = (0.0, math.sin(a), math.cos(a))
    text = (h.header(gravity=(0, 0, -G), lo=(-0.05,) * 3, hi=(0.05,) * 3)
            + h.material("ball", **BALL) + h.material("floor", **FLOOR)
            + h.interaction("ball", "floor", 0.5, MU, MU_R, model)
            + h.all_interactions(["ball"], 0.5, MU)
            + h.wall("slope", (0, 0, 0), n, "floor")
            + h.csv_fill(tmp_path, "slope.csv", "ball", [[R * c for c in n]], R))
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), arch="cpu", precision="f64") as sim:
        sim.step(10000)
        x1 = sim.particles()["position"][0]
        sim.step(10000)
        p = sim.particles()
        creep = np.linalg.norm(p["position"][0] - x1)
        print(f"\n  incline tan(a) = {math.tan(a):.3f}: moved {creep:.2e} m over 10^4 steps, "
              f"|w| = {np.linalg.norm(p['angular_velocity'][0]):.2e} rad/s "
              f"(limiter scale g sin(a) dt / (0.4 R) = {G * math.sin(a) * sim.dt / (0.4 * R):.2e})")
    assert creep < 1e-9
