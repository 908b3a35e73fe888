"""Energy bookkeeping: an elastic gas conserves energy; a poured, dissipative bed comes to rest
on the floor, which then carries its weight.

1. Elastic gas. 343 spheres (R 5 mm) in a box periodic on all three axes, e = 1, friction 0,
   no gravity, random velocities of 1 m/s. With e = 1 the damping ratio is 0 and with mu = 0
   the tangential force is capped at 0, so only the Hertz normal force acts: a conservative
   system. We check the total energy K + U, with U = sum over overlapping pairs of the Hertz
   potential 8/15 E* sqrt(R*) d^(5/2) (computed here from positions, minimum image), every 15
   steps over 1e4 steps and several thousand collisions.
   Tolerance: velocity Verlet is symplectic, but the Hertz potential is not smooth at first
   touch, so each collision leaves an energy error that does not average out exactly; it
   grows with the impact speed (fewer steps per contact: t_c ~ v^(-1/5)). The worst case is
   every collision erring, in the same sign, by the relative error of the worst collision:
       bound = eps_worst x sum over collisions of 1/2 m* v_n^2 / E_0,
   with eps_worst measured here by a head-on two-sphere collision at the same dt and
   V_WORST = 4 m/s (the test checks that no impact in the gas is faster), and each collision's
   normal impact speed v_n taken from the velocities at the sample before it began (sampling
   every 15 steps, under half the shortest contact of 40 steps, sees every contact).
   The momentum must stay zero to round-off (pair forces are equal and opposite).
2. Poured bed. 500 spheres (R 5 mm, E 1e7 Pa softened, e 0.5, mu 0.5, mu_r 0.05) fall onto a
   floor in a box periodic in x and y. After 1 s the bed is at rest and the floor force equals
   the weight. "At rest" is defined on physical scales, not fitted: K < 1e-3 m g R (a
   thousandth of the energy of lifting one grain by its radius), and a centre-of-mass
   acceleration |dP/dt| / (M g) < 1e-4, measured from the total vertical momentum one step
   either side of the last sample. The vertical momentum balance F_floor - W = dP/dt (exact
   in velocity Verlet for the two-step average of F) then gives |F_floor / W - 1| < 1e-4,
   asserted for the last sample and for the mean of the samples over the last 0.3 s.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

SOFT = dict(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.25)
V_WORST = 4.0                # m/s, above every relative normal impact speed in the gas
STEPS_PER_CONTACT = 40       # steps per Hertz contact at V_WORST
REST_FRACTION_OF_GRAIN = 1e-3    # at rest: K < 1e-3 x the energy m g R of lifting one grain by R
REST_ACCELERATION = 1e-4         # at rest: |dP/dt| < 1e-4 W (centre-of-mass acceleration 1e-4 g)


class _PairScanner:
    """All pairs i < j of n identical spheres in a periodic box: overlaps (minimum image) and
    the Hertz potential 8/15 E* sqrt(R*) d^(5/2) of the overlapping ones."""

    def __init__(self, n, radius, e_eff, span):
        self.i, self.j = np.triu_indices(n, 1)
        self.radius, self.span = radius, span
        self.k = 8.0 / 15.0 * e_eff * math.sqrt(radius / 2)

    def scan(self, pos):
        d = pos[self.i] - pos[self.j]
        d -= self.span * np.round(d / self.span)
        dist = np.sqrt((d * d).sum(-1))
        touching = np.nonzero(dist < 2 * self.radius)[0]
        overlap = 2 * self.radius - dist[touching]
        normal = d[touching] / dist[touching, None]
        return float((self.k * overlap ** 2.5).sum()), touching, normal


@pytest.fixture(scope="module")
def gas(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("gas")
    r, side, n_side, speed = 0.005, 0.1, 7, 1.0
    m = h.sphere_mass(r, SOFT["density"])
    e_eff = h.youngs_eff(SOFT["youngs_modulus"], SOFT["poisson_ratio"])
    t_c = h.hertz_impact(m / 2, r / 2, e_eff, V_WORST)["time"]
    dt = t_c / STEPS_PER_CONTACT
    rng = np.random.default_rng(7)
    g = (np.arange(n_side) + 0.5) * side / n_side
    pos = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    pos += rng.uniform(-1e-3, 1e-3, pos.shape)
    vel = rng.normal(size=pos.shape)
    vel /= np.linalg.norm(vel, axis=1)[:, None]
    vel *= speed
    vel -= vel.mean(axis=0)
    text = (h.header(dt=dt, lo=(0, 0, 0), hi=(side,) * 3, periodic=("x", "y", "z"))
            + h.material("glass", **SOFT) + h.interaction("glass", "glass", 1.0, 0.0)
            + h.csv_fill(tmp, "gas.csv", "glass", pos, r, vel))
    sample_every = 15            # < STEPS_PER_CONTACT / 2: every contact is seen at least once
    n_samples = 667
    scanner = _PairScanner(len(pos), r, e_eff, side)
    energy, kinetic = [], []
    collisions, collision_energy, fastest = 0, 0.0, 0.0
    before = np.empty(0, dtype=np.int64)
    prev_vel = vel
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        for k in range(n_samples + 1):
            if k:
                sim.step(sample_every)
            p = sim.particles()
            u, now, normal = scanner.scan(p["position"])
            new = ~np.isin(now, before)
            # impact normal speed of each new contact, from the velocities one sample earlier
            # (before the contact began)
            ii, jj = scanner.i[now[new]], scanner.j[now[new]]
            vn = np.abs(((prev_vel[ii] - prev_vel[jj]) * normal[new]).sum(1))
            collisions += int(new.sum())
            collision_energy += float((0.5 * (m / 2) * vn ** 2).sum())
            fastest = max(fastest, float(vn.max(initial=0.0)))
            before, prev_vel = now, p["velocity"]
            kin = 0.5 * float((p["mass"] * (p["velocity"] ** 2).sum(1)).sum())
            kinetic.append(kin)
            energy.append(kin + u)
            assert np.abs(p["angular_velocity"]).max() == 0.0      # mu = 0: no torque at all
        assert sim.kinetic_energy() == pytest.approx(kinetic[-1], rel=1e-12)
        steps = sim.step_count
        momentum = (p["mass"][:, None] * p["velocity"]).sum(0)

    # the worst single collision at the same dt: head on at V_WORST, the fewest steps per contact
    text2 = (h.header(dt=dt, lo=(-0.05,) * 3, hi=(0.05,) * 3)
             + h.material("glass", **SOFT) + h.interaction("glass", "glass", 1.0, 0.0)
             + h.csv_fill(tmp, "pair.csv", "glass", [[-r - 1e-5, 0, 0], [r + 1e-5, 0, 0]], r,
                          [[V_WORST / 2, 0, 0], [-V_WORST / 2, 0, 0]]))
    with taichi_dem.Simulation.from_text(text2, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        k0 = sim.kinetic_energy()
        sim.step(3 * STEPS_PER_CONTACT)
        worst = abs(sim.kinetic_energy() / k0 - 1)
        assert sim.particles()["velocity"][0, 0] < 0
    return dict(energy=np.array(energy), kinetic=np.array(kinetic), collisions=collisions,
                collision_energy=collision_energy, fastest=fastest, steps=steps, worst=worst,
                n=len(pos), momentum=momentum, m=m)


def test_elastic_gas_conserves_energy(gas):
    e = gas["energy"]
    drift = np.abs(e / e[0] - 1).max()
    # worst case: every collision errs by the worst collision's relative error, in the same sign
    bound = gas["worst"] * gas["collision_energy"] / e[0]
    print(f"\nelastic gas: {gas['n']} spheres, {gas['steps']} steps, {gas['collisions']} collisions "
          f"(fastest normal impact {gas['fastest']:.2f} m/s, collision energy "
          f"{gas['collision_energy'] / e[0]:.2f} x E0); max |E/E0 - 1| = {drift:.2e}, end "
          f"{e[-1] / e[0] - 1:+.2e}; worst single collision {gas['worst']:.2e}, bound {bound:.2e}; "
          f"K dips by up to {1 - gas['kinetic'].min() / e[0]:.2e} (energy held in contacts)")
    assert gas["collisions"] > 1000
    assert gas["fastest"] < V_WORST
    assert drift <= bound
    # total momentum stays zero (pairwise forces are equal and opposite)
    assert np.abs(gas["momentum"]).max() < 1e-12 * gas["m"] * gas["n"]


# ------------------------------------------------------------------------------- poured bed
@pytest.fixture(scope="module")
def bed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bed")
    r, side, g = 0.005, 0.1, 9.81
    text = (h.header(gravity=(0, 0, -g), lo=(0, 0, 0), hi=(side, side, 0.15), periodic=("x", "y"),
                     output_interval=0.01)
            + h.material("ball", **SOFT) + h.material("floor", density=7800.0, youngs_modulus=2e11,
                                                     poisson_ratio=0.3)
            + h.interaction("ball", "ball", 0.5, 0.5, 0.05)
            + h.interaction("ball", "floor", 0.5, 0.5, 0.05)
            + h.wall("floor", (0, 0, 0), (0, 0, 1), "floor")
            + "[[particles]]\nmaterial = \"ball\"\nradius = 0.005\ncount = 500\n"
            + "region = { box = { min = [0.0, 0.0, 0.0], max = [0.1, 0.1, 0.14] } }\n\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        p0 = sim.particles()
        m = p0["mass"]
        weight = float(m.sum()) * g
        z0 = p0["position"][:, 2].copy()
        # stop one step before an output step (n), then read the momentum at n-1, n, n+1; the
        # series' last wall force is the one of step n
        n_out = int(round(1.0 / sim.dt / sim.output_every)) * sim.output_every
        sim.step(n_out - 1)
        pa = sim.particles()
        sim.step(1)
        pb = sim.particles()
        series = sim.series
        sim.step(1)
        pc = sim.particles()
        dt = sim.dt
        kin = sim.kinetic_energy()
        count = sim.particle_count
    released = float((m * g * (z0 - pc["position"][:, 2])).sum())
    pz = [float((m * p["velocity"][:, 2]).sum()) for p in (pa, pb, pc)]
    assert series["time"][-1] == pytest.approx(n_out * dt, rel=1e-12)
    return dict(weight=weight, released=released, kinetic=kin, series=series, dt=dt, pz=pz,
                n=len(z0), count=count, grain=float(m[0]) * g * r)


def test_poured_bed_comes_to_rest(bed):
    ke = bed["series"]["particles/kinetic_energy"]
    t = bed["series"]["time"]
    print(f"\npoured bed: {bed['n']} spheres, released {bed['released']:.4e} J, K(1 s) = "
          f"{bed['kinetic']:.3e} J = {bed['kinetic'] / bed['released']:.2e} of it "
          f"= {bed['kinetic'] / bed['grain']:.2e} m g R; K(0.3 s) = {ke[np.searchsorted(t, 0.3)]:.2e} J")
    assert bed["count"] == bed["n"]
    assert bed["released"] > 0
    assert bed["kinetic"] < REST_FRACTION_OF_GRAIN * bed["grain"]


def test_floor_carries_the_weight(bed):
    f = bed["series"]["walls/floor/force"]
    pz, dt, w = bed["pz"], bed["dt"], bed["weight"]
    floor = -f[-1, 2]
    # velocity Verlet: P(n+1) - P(n-1) = dt/2 (F(n-1) + 2 F(n) + F(n+1)) - 2 W dt
    dpdt = (pz[2] - pz[0]) / (2 * dt)
    print(f"  floor force {floor:.7f} N, weight {w:.7f} N ({floor / w - 1:+.2e}); "
          f"dP/dt = {dpdt / w:+.2e} W; F - W - dP/dt = {(floor - w - dpdt) / w:+.2e} W")
    # at rest the vertical momentum no longer changes (centre-of-mass acceleration < 1e-4 g)...
    assert abs(dpdt) < REST_ACCELERATION * w
    # ... so by the momentum balance F - W = dP/dt the floor carries the weight; F(n) differs
    # from the two-step average in that balance only by the bed's contact vibration (printed)
    assert floor == pytest.approx(w, rel=REST_ACCELERATION)
    # the same for the mean over the samples of the last 0.3 s (the time average of dP/dt is
    # the momentum change over 0.3 s: ~0 at rest)
    t = bed["series"]["time"]
    late = t >= 0.7
    assert -f[late, 2].mean() == pytest.approx(w, rel=REST_ACCELERATION)


@pytest.mark.xfail(reason="a known limit of the constant-torque rolling model (README): in a "
                          "static bed the floor's lateral force alternates sign every step "
                          "(+-1e-3 W, period 2) although the bed does not move; EPSD does not",
                   strict=True)
def test_floor_lateral_force_vanishes_at_rest(bed):
    f = bed["series"]["walls/floor/force"]
    t = bed["series"]["time"]
    late = t >= 0.7
    print(f"  floor lateral force over the last 0.3 s: up to {np.abs(f[late, :2]).max() / bed['weight']:.2e} W")
    # at rest the horizontal momentum does not change, so the floor's net friction is zero
    assert np.abs(f[late, :2]).max() < REST_ACCELERATION * bed["weight"]
