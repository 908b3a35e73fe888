"""Chung & Ooi (2011) benchmark tests 1-4 for DEM codes at the particle-impact level.

Source: Chung Y.C., Ooi J.Y., "Benchmark tests for verifying discrete element modelling codes
at particle impact level", Granular Matter 13:643-656 (2011); digitised test-4 curves in
/work/shared/reference (as published with the Kratos DEM suite).

Test 1  two identical glass spheres, head-on at 20 m/s relative speed, elastic: maximum overlap,
        peak force and contact duration against Hertz theory (closed form, dem_helpers) and the
        published 274.1 um, 10.70 kN, 40.35 us.
Test 2  aluminium-alloy sphere (R 0.1 m) on a rigid wall at 0.2 m/s, elastic: the same three
        quantities against Hertz, the force read from the wall-force series.
Test 3  achieved restitution = target for e = 0.1 ... 1.0 at 0.1, 1 and 10 m/s (glass and
        aluminium-alloy spheres on a rigid wall; 60 particles in one simulation).
Test 4  oblique impact of an aluminium-oxide sphere on a rigid wall at 3.9 m/s, mu 0.092,
        e 0.98: tangential restitution and rebound spin against rigid-body theory in gross
        sliding, and all three quantities against the digitised published curves.

Tolerances (derived, not fitted):
* The contacts are resolved with N = 200 steps per Hertz contact time t_c (dt = t_c / N).
  Velocity Verlet is second order: the overlap, force and duration errors scale as (1/N)^2
  (measured while writing this test: 9.1e-5 at N = 100, 5.7e-6 at N = 400 for the overlap,
  a ratio of 16). Reading a maximum from samples spaced dt apart adds at most
  (1/2) |d''| (dt/2)^2 ~ (pi/N)^2 / 8 relative. We assert (pi/N)^2 = 2.5e-4 against exact
  Hertz: a bound on both terms, ~10x the measured error, not a fit to it.
* The contact duration is taken where the linearly interpolated overlap changes sign; the
  interpolation error is O(dt^2) and bounded by the same (pi/N)^2.
* Published test-1 values carry 4 significant figures (rounding up to 4.7e-4 relative for
  10.70 kN) and the published 40.35 us itself lies 2.7e-4 above exact Hertz (40.339 us);
  they are asserted at 1e-3 relative.
* Restitution: the damping ratio comes from a one-off integration of the clamped Hertz ODE
  (restitution.py, < 1e-4 in e). Velocity Verlet knows the velocity at the half step only;
  the normal damping uses the predicted full-step velocity v + a dt/2 (hertz_mindlin.py).
  Before that prediction the error was first order, e - target = -C(e)/N with C up to 0.23
  (12 % relative at e = 0.1 with N = 20). With it, a convergence study (glass and aluminium
  on the rigid wall, e = 0.1 ... 1.0 at 0.1, 1 and 10 m/s) gave max |e - target| = 6.5e-3,
  1.9e-3, 5.5e-4 and 1.4e-4 at N = 20, 40, 80, 200 (order ~1.7). We assert (a) at N = 20,
  the coarsest resolution the automatic time step allows (timestep.py), |e - target| <= 0.01
  at every e and speed: one point of restitution, what a user can tell apart in a bulk
  result; (b) |e - target| <= 0.5/N_case at N = 200 and 400 (a first-order bound, which the
  prediction beats by ~8x; N_case is the number of steps per Hertz contact at that case's
  speed, 200 to 790 here) and (c) the Richardson extrapolation 2 e(2N) - e(N) equals the
  target within 2e-4 (restitution.py's 1e-4 plus the remainder): the limit dt -> 0 is the
  target, at every speed.
* Test 4 gross sliding (tan theta > 3.5 mu (1+e), theta > 32.5 deg): every step's tangential
  force sits on the Coulomb cone, so the tangential impulse is exactly mu times the normal
  impulse; with the achieved normal restitution e_n in the formula, e_t = 1 - mu (1+e_n)/tan
  theta holds to round-off (asserted at 1e-10 relative). The spin: the engine applies the
  tangential force at the overlap centre, R - d/2 from the centre (PHYSICS.md), so the spin
  is lower than rigid-body theory by the impulse-weighted mean of d/(2R), which for a Hertz
  impact is B(7/5,1/2)/B(1,1/2) = 0.8176 of d_max/(2R) (<= 1.1e-3 here). After that
  correction we assert 5e-5 relative (left over: O((d/R)^2) and the e = 0.98 damping's
  change to the overlap history; measured <= 9.3e-6), and without it the bound d_max/(2R).
* Test 4 digitised curves: see test_test4_digitised_curves.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

REF = Path("/work/shared/reference")
STEPS_PER_CONTACT = 200
HERTZ_TOL = (math.pi / STEPS_PER_CONTACT) ** 2          # 2.5e-4, see the docstring

GLASS = dict(density=2800.0, youngs_modulus=48e9, poisson_ratio=0.2)
ALUMINIUM = dict(density=2699.0, youngs_modulus=70e9, poisson_ratio=0.33)
ALUMINA = dict(density=4000.0, youngs_modulus=380e9, poisson_ratio=0.23)
RIGID = dict(density=7800.0, youngs_modulus=h.RIGID_E, poisson_ratio=0.0)


def _contact_interval(t, overlap):
    """Start and end of the (single) contact from sampled overlaps, interpolating the sign
    changes linearly."""
    inside = np.nonzero(overlap > 0.0)[0]
    a, b = inside[0], inside[-1]
    assert a > 0 and b + 1 < len(overlap), "the contact must start and end inside the record"
    t_in = t[a - 1] + (t[a] - t[a - 1]) * (0.0 - overlap[a - 1]) / (overlap[a] - overlap[a - 1])
    t_out = t[b] + (t[b + 1] - t[b]) * (0.0 - overlap[b]) / (overlap[b + 1] - overlap[b])
    return t_in, t_out


def _in_id_order(sim, *names):
    """The named fields of the particles in id order: what sim.particles() returns for them
    here (f64, no particle leaves, no process ids), read after every step without the eight
    other fields that sim.particles() reads and sorts (each read a kernel launch: most of the
    stepping loops' time)."""
    s, n = sim.engine.state, sim.engine.count
    assert not s.process and n == sim.particle_count
    order = np.argsort(s.particle_id.to_numpy()[:n], kind="stable")
    return [getattr(s, name).to_numpy()[:n][order] for name in names]


# ------------------------------------------------------------------------------------ test 1
@pytest.fixture(scope="module")
def test1(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("co1")
    r, v = 0.01, 10.0
    m = h.sphere_mass(r, GLASS["density"])
    ref = h.hertz_impact(m / 2, r / 2, h.youngs_eff(GLASS["youngs_modulus"], GLASS["poisson_ratio"]), 2 * v)
    dt = ref["time"] / STEPS_PER_CONTACT
    gap = 2.5 * 2 * v * dt                    # the contact begins during the third step
    text = (h.header(dt=dt, lo=(-0.1, -0.1, -0.1), hi=(0.1, 0.1, 0.1))
            + h.material("glass", **GLASS) + h.interaction("glass", "glass", 1.0, 0.0)
            + h.csv_fill(tmp, "t1.csv", "glass", [[-r - gap / 2, 0, 0], [r + gap / 2, 0, 0]], r,
                         [[v, 0, 0], [-v, 0, 0]]))
    t, overlap, vel = [], [], []
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        assert sim.dt == pytest.approx(dt, rel=1e-12)
        for _ in range(int(1.3 * STEPS_PER_CONTACT)):
            sim.step(1)
            x, v_now = _in_id_order(sim, "position", "velocity")
            t.append(sim.time)
            overlap.append(2 * r - (x[1, 0] - x[0, 0]))
            vel.append(v_now[0, 0])
        final = sim.particles()["velocity"]
    t, overlap, vel = map(np.array, (t, overlap, vel))
    # force on sphere 0 from its velocity change per step (the mean of the forces at the two
    # ends of the step in velocity Verlet)
    force = -m * np.diff(vel) / dt
    t_in, t_out = _contact_interval(t, overlap)
    return dict(ref=ref, overlap=overlap.max(), force=force.max(), time=t_out - t_in,
                rebound=(final[1, 0] - final[0, 0]) / (2 * v))


def test_test1_against_hertz(test1):
    ref = test1["ref"]
    for key in ("overlap", "force", "time"):
        print(f"test 1 {key}: {test1[key]:.6g} vs Hertz {ref[key]:.6g} "
              f"({test1[key] / ref[key] - 1:+.2e})")
        assert test1[key] == pytest.approx(ref[key], rel=HERTZ_TOL)
    # elastic and frictionless: the spheres separate at the impact speed (Verlet is symplectic;
    # the energy error after a contact at N = 200 is far below the Hertz tolerance)
    assert test1["rebound"] == pytest.approx(1.0, abs=HERTZ_TOL)


def test_test1_against_published(test1):
    published = {"overlap": 274.1e-6, "force": 10.70e3, "time": 40.35e-6}
    for key, value in published.items():
        assert test1[key] == pytest.approx(value, rel=1e-3), key


# ------------------------------------------------------------------------------------ test 2
@pytest.fixture(scope="module")
def test2(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("co2")
    r, v = 0.1, 0.2
    m = h.sphere_mass(r, ALUMINIUM["density"])
    e_eff = h.youngs_eff(ALUMINIUM["youngs_modulus"], ALUMINIUM["poisson_ratio"],
                         RIGID["youngs_modulus"], RIGID["poisson_ratio"])
    ref = h.hertz_impact(m, r, e_eff, v)
    dt = ref["time"] / STEPS_PER_CONTACT
    gap = 2.5 * v * dt
    text = (h.header(dt=dt, lo=(-0.5, -0.5, -0.5), hi=(0.5, 0.5, 0.5), output_interval=dt)
            + h.material("al", **ALUMINIUM) + h.material("rigid", **RIGID)
            + h.all_interactions(["al"]) + h.interaction("al", "rigid", 1.0, 0.0)
            + h.wall("floor", (0, 0, 0), (0, 0, 1), "rigid")
            + h.csv_fill(tmp, "t2.csv", "al", [[0, 0, r + gap]], r, [[0, 0, -v]]))
    t, overlap = [], []
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        assert sim.output_every == 1
        for _ in range(int(1.3 * STEPS_PER_CONTACT)):
            sim.step(1)
            t.append(sim.time)
            overlap.append(r - _in_id_order(sim, "position")[0][0, 2])
        series = sim.series
        final = sim.particles()["velocity"][0]
    t, overlap = np.array(t), np.array(overlap)
    force = series["walls/floor/force"]
    assert np.allclose(series["time"][1:], t, rtol=0, atol=1e-3 * dt)
    t_in, t_out = _contact_interval(t, overlap)
    return dict(ref=ref, overlap=overlap.max(), force=-force[:, 2].min(), time=t_out - t_in,
                lateral=np.abs(force[:, :2]).max(), rebound=final[2] / v)


def test_test2_against_hertz(test2):
    ref = test2["ref"]
    for key in ("overlap", "force", "time"):
        print(f"test 2 {key}: {test2[key]:.6g} vs Hertz {ref[key]:.6g} "
              f"({test2[key] / ref[key] - 1:+.2e})")
        assert test2[key] == pytest.approx(ref[key], rel=HERTZ_TOL)
    # the wall is pushed down (force on the wall from the particle is -z), nothing sideways
    assert test2["lateral"] == 0.0
    assert test2["rebound"] == pytest.approx(1.0, abs=HERTZ_TOL)


# ------------------------------------------------------------------------------------ test 3
RESTITUTIONS = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
SPEEDS = [0.1, 1.0, 10.0]
FIRST_ORDER_BOUND = 0.5     # |e - target| <= 0.5 / N (N steps per Hertz contact time); see docstring
TABLE_TOL = 2e-4            # restitution.py: 1e-4 from its ODE table, plus O(1/N^2) left over


def _restitution_run(tmp, steps_per_contact):
    """60 spheres (glass and aluminium alloy, R 10 mm; one material per target e), each falling
    on a rigid wall at 0.1, 1 or 10 m/s. Returns the cases, the achieved e and, per case, the
    number of steps per elastic Hertz contact time."""
    r = 0.01
    bases = {"glass": GLASS, "al": ALUMINIUM}

    def contact_time(mat, speed):
        return h.hertz_impact(h.sphere_mass(r, mat["density"]), r,
                              h.youngs_eff(mat["youngs_modulus"], mat["poisson_ratio"],
                                           RIGID["youngs_modulus"], 0.0), speed)["time"]

    # the shortest contact (stiffest material, highest speed) sets dt
    t_short = min(contact_time(mat, max(SPEEDS)) for mat in bases.values())
    t_long = max(contact_time(mat, min(SPEEDS)) for mat in bases.values())
    dt = t_short / steps_per_contact
    spacing = 0.05
    mats, inter, fills, names, cases, steps = "", "", "", [], [], []
    row = 0
    for base, props in bases.items():
        for e in RESTITUTIONS:
            name = f"{base}_e{int(round(e * 100)):03d}"
            names.append(name)
            mats += h.material(name, **props)
            inter += h.interaction(name, "rigid", e, 0.0)
            pos = [[row * spacing, k * spacing, r + 2.5 * v * dt] for k, v in enumerate(SPEEDS)]
            vel = [[0.0, 0.0, -v] for v in SPEEDS]
            fills += h.csv_fill(tmp, f"{name}_{steps_per_contact}.csv", name, pos, r, vel)
            cases += [(base, e, v) for v in SPEEDS]
            steps += [contact_time(props, v) / dt for v in SPEEDS]
            row += 1
    text = (h.header(dt=dt, lo=(-spacing,) * 3, hi=(row * spacing, len(SPEEDS) * spacing, 0.2))
            + mats + h.material("rigid", **RIGID) + h.all_interactions(names) + inter
            + h.wall("floor", (0, 0, 0), (0, 0, 1), "rigid") + fills)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        # a damped contact ends with the force at zero while some overlap remains; the sphere
        # then drifts off at its rebound speed. Step until every sphere has cleared the wall.
        sim.step(int(1.2 * t_long / dt))
        for _ in range(100):
            p = sim.particles()
            if np.all(p["position"][:, 2] > r):
                break
            sim.step(steps_per_contact)
        assert np.all(p["position"][:, 2] > r), "every sphere has left the wall"
        vz = p["velocity"][:, 2]
    achieved = np.array([vz[k] / v for k, (_, _, v) in enumerate(cases)])
    return cases, achieved, np.array(steps)


@pytest.fixture(scope="module")
def test3(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("co3")
    coarse = _restitution_run(tmp, STEPS_PER_CONTACT)
    fine = _restitution_run(tmp, 2 * STEPS_PER_CONTACT)
    return coarse, fine


def test_test3_restitution_at_the_coarsest_automatic_step(tmp_path):
    cases, achieved, steps = _restitution_run(tmp_path, 20)
    target = np.array([c[1] for c in cases])
    print(f"\ntest 3 at N = 20: max |e - target| = {np.abs(achieved - target).max():.2e}")
    assert np.all(np.abs(achieved - target) <= 0.01), list(zip(cases, achieved - target))


def test_test3_restitution_equals_target(test3):
    (cases, e_n, steps), (_, e_2n, _) = test3
    target = np.array([c[1] for c in cases])
    extrapolated = 2.0 * e_2n - e_n          # Richardson, first order
    print("\ntest 3: achieved e - target at N = 200 (glass 0.1, 1, 10 m/s | al 0.1, 1, 10 m/s), "
          "and Richardson-extrapolated")
    for e in RESTITUTIONS:
        sel = target == e
        print(f"  e = {e:.1f}: " + " ".join(f"{x:+.1e}" for x in e_n[sel] - e) + "   extrap: "
              + " ".join(f"{x:+.1e}" for x in extrapolated[sel] - e))
    print(f"  max |e - target|: N = {STEPS_PER_CONTACT}: {np.abs(e_n - target).max():.2e}, "
          f"2N: {np.abs(e_2n - target).max():.2e}, extrapolated: "
          f"{np.abs(extrapolated - target).max():.2e}")
    # first-order convergence to the target, and the limit is the target
    assert np.all(np.abs(e_n - target) <= FIRST_ORDER_BOUND / steps), cases
    assert np.all(np.abs(e_2n - target) <= FIRST_ORDER_BOUND / (2 * steps)), cases
    assert np.all(np.abs(extrapolated - target) <= TABLE_TOL), cases


# ------------------------------------------------------------------------------------ test 4
MU, E4, V4, R4 = 0.092, 0.98, 3.9, 0.0025


def _digitised(name):
    d = np.loadtxt(REF / f"chung_ooi_test4_{name}.csv", delimiter=",", skiprows=1)
    return d[:, 0], d[:, 1]


@pytest.fixture(scope="module")
def test4(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("co4")
    angles = set(np.round(np.arange(2.0, 89.0, 2.0), 6))
    for name in ("tangential_restitution", "angular_velocity", "rebound_angle"):
        angles |= set(np.round(_digitised(name)[0], 6))
    angles = np.array(sorted(angles))
    m = h.sphere_mass(R4, ALUMINA["density"])
    e_eff = h.youngs_eff(ALUMINA["youngs_modulus"], ALUMINA["poisson_ratio"], RIGID["youngs_modulus"], 0.0)
    t_fast = h.hertz_impact(m, R4, e_eff, V4)["time"]
    t_slow = h.hertz_impact(m, R4, e_eff, V4 * math.cos(math.radians(angles.max())))["time"]
    dt = t_fast / STEPS_PER_CONTACT
    spacing = 4 * R4
    th = np.radians(angles)
    vel = np.stack([V4 * np.sin(th), np.zeros_like(th), -V4 * np.cos(th)], axis=1)
    # each sphere starts 2.5 steps of its normal speed above the wall
    pos = np.stack([np.zeros_like(th), spacing * np.arange(len(th)), R4 + 2.5 * dt * V4 * np.cos(th)], axis=1)
    text = (h.header(dt=dt, lo=(-0.01, -spacing, -0.01), hi=(0.01, spacing * len(th), 0.02))
            + h.material("alumina", **ALUMINA) + h.material("rigid", **RIGID)
            + h.all_interactions(["alumina"]) + h.interaction("alumina", "rigid", E4, MU)
            + h.wall("floor", (0, 0, 0), (0, 0, 1), "rigid")
            + h.csv_fill(tmp, "t4.csv", "alumina", pos, R4, vel))
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        sim.step(int(1.2 * t_slow / dt) + 10)
        p = sim.particles()
        assert np.all(p["position"][:, 2] > R4), "every sphere has left the wall"
    v, w = p["velocity"], p["angular_velocity"]
    # velocity of the contact point (at -R n below the centre, n = +z): v + w x (-R z)
    v_contact_x = v[:, 0] - R4 * w[:, 1]
    # tangential restitution of the centre velocity, v_x'/v_x: this is what the digitised curve
    # and the rigid-body formula of chung_ooi_test4.md describe (at 50 deg: 0.845 digitised,
    # 1 - mu (1+e)/tan = 0.847 for the centre, 0.465 for the contact point), although the
    # note calls it "at the contact point". The rebound angle is the contact point's.
    e_t = v[:, 0] / vel[:, 0]
    # published sign convention: negative spin for a sphere sliding in +x (our w_y > 0)
    spin = -w[:, 1]
    rebound_angle = np.degrees(np.arctan2(v_contact_x, v[:, 2]))
    normal_e = v[:, 2] / -vel[:, 2]
    return dict(angles=angles, e_t=e_t, spin=spin, rebound_angle=rebound_angle,
                normal_e=normal_e, lateral=np.abs(v[:, 1]).max() + np.abs(w[:, [0, 2]]).max())


# the impulse-weighted mean overlap over an elastic Hertz impact, as a fraction of d_max:
# int d F dt / (d_max int F dt) = B(7/5, 1/2) / B(1, 1/2) (substitute x = (4/5) u^(5/2))
MEAN_OVERLAP_FRACTION = (math.gamma(1.4) * math.gamma(0.5) / math.gamma(1.9)) / 2.0   # 0.81756


def test_test4_gross_sliding_rigid_body(test4):
    a = test4["angles"]
    th = np.radians(a)
    e_n = test4["normal_e"]                                  # achieved normal restitution
    e_t_theory = 1.0 - MU * (1 + e_n) / np.tan(th)
    spin_rigid = -5.0 * MU * (1 + e_n) * V4 * np.cos(th) / (2 * R4)
    # the engine applies the tangential force at the overlap centre, R - d/2 from the sphere
    # centre (PHYSICS.md), so the spin is smaller than rigid-body theory by the impulse-weighted
    # mean of d / (2R)
    m = h.sphere_mass(R4, ALUMINA["density"])
    e_eff = h.youngs_eff(ALUMINA["youngs_modulus"], ALUMINA["poisson_ratio"], RIGID["youngs_modulus"], 0.0)
    d_max = np.array([h.hertz_impact(m, R4, e_eff, V4 * math.cos(t))["overlap"] for t in th])
    spin_theory = spin_rigid * (1.0 - MEAN_OVERLAP_FRACTION * d_max / (2 * R4))
    sliding = np.tan(th) > 3.5 * MU * (1 + E4)
    print("\ntest 4, gross sliding: angle, e_t, rigid-body, rel err | spin, rigid-body, rel err, "
          "rel err after the lever-arm correction")
    for k in np.nonzero(sliding)[0]:
        print(f"  {a[k]:6.2f}  {test4['e_t'][k]:.6f} {e_t_theory[k]:.6f} "
              f"{test4['e_t'][k] / e_t_theory[k] - 1:+.1e} | {test4['spin'][k]:9.3f} "
              f"{spin_rigid[k]:9.3f} {test4['spin'][k] / spin_rigid[k] - 1:+.1e} "
              f"{test4['spin'][k] / spin_theory[k] - 1:+.1e}")
    assert test4["lateral"] < 1e-9
    steps = STEPS_PER_CONTACT * (1.0 / np.cos(th)) ** 0.2     # steps per contact at each angle
    assert np.all(np.abs(e_n - E4) <= FIRST_ORDER_BOUND / steps)
    # sliding throughout: the tangential impulse is exactly mu times the normal impulse, so
    # e_t is exact up to round-off once the achieved e_n (with its O(dt) error) is used
    assert np.allclose(test4["e_t"][sliding], e_t_theory[sliding], rtol=1e-10, atol=0)
    # the lever-arm correction is itself first order in d/R: what is left is O((d/R)^2) ~ 1e-6
    # and the damping's change of the overlap history at e = 0.98 (~1e-5 relative)
    assert np.allclose(test4["spin"][sliding], spin_theory[sliding], rtol=5e-5, atol=0)
    # and the uncorrected comparison, bounded by d_max / (2R) < 1.6e-3
    assert np.all(np.abs(test4["spin"][sliding] / spin_rigid[sliding] - 1) <= d_max[sliding] / (2 * R4))


KRATOS_TOL = {"tangential_restitution": 1.6e-2, "angular_velocity": 2.2e-2, "rebound_angle": 2.5e-2}


def _l1_error(got, ref):
    """The Kratos suite's measure: sum |DEM - reference| / sum |reference|."""
    return float(np.abs(got - ref).sum() / np.abs(ref).sum())


def test_test4_digitised_curves(test4):
    """Against the digitised curves. The digitisation's own error shows where the curves can be
    checked against exact theory (gross sliding, tan(theta) > 3.5 mu (1+e)): there the digitised
    points differ from rigid-body theory by up to 0.003 in e_t, 3 % (3.7 rad/s) in the spin and
    0.35 deg in the rebound angle, i.e. by as much as our results do. Pointwise tolerances at the
    Kratos levels would therefore test the digitiser, not the engine; we assert the Kratos
    suite's own aggregate measure (L1 error normalised by the L1 norm of the reference) at its
    thresholds 1.6 %, 2.2 % and 2.5 %, and print every point."""
    a = test4["angles"]
    th = np.radians(a)
    rigid = {"tangential_restitution": 1.0 - MU * (1 + E4) / np.tan(th),
             "angular_velocity": -5.0 * MU * (1 + E4) * V4 * np.cos(th) / (2 * R4)}
    for name, key in (("tangential_restitution", "e_t"), ("angular_velocity", "spin"),
                      ("rebound_angle", "rebound_angle")):
        ang, ref = _digitised(name)
        idx = np.searchsorted(a, np.round(ang, 6))
        assert np.allclose(a[idx], np.round(ang, 6))
        got = test4[key][idx]
        err = _l1_error(got, ref)
        print(f"\ntest 4 {name}: angle, digitised, measured, abs diff, rel diff"
              + (", digitised - rigid-body (sliding)" if name in rigid else ""))
        for k, (x, rf, g) in enumerate(zip(ang, ref, got)):
            line = f"  {x:6.2f}  {rf:10.4f} {g:10.4f} {g - rf:+9.4f} {(g - rf) / abs(rf):+7.2%}"
            if name in rigid and math.tan(math.radians(x)) > 3.5 * MU * (1 + E4):
                line += f"   {rf - rigid[name][idx[k]]:+9.4f}"
            print(line)
        print(f"  Kratos L1 error {err:.2%} (Kratos asserts {KRATOS_TOL[name]:.1%})")
        assert err <= KRATOS_TOL[name], name
