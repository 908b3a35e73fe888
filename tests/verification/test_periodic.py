"""Periodic faces keep contacts and their history; non-periodic faces remove and count.

1. An oblique, frictional, damped collision (e 0.5, mu 0.5, tangential slip and spins, so the
   outcome depends on the tangential spring's history) between two spheres drifting at 2 m/s
   along a periodic x axis, timed so that the pair straddles the periodic face x = 0.1 / 0 at
   the start and the second sphere wraps in mid-contact, with several neighbour rebuilds during
   the contact (skin 0.5 mm: a rebuild every 0.125 ms of drift, contact ~1 ms). References:
   (b) the same pair shifted by half the box in the same simulation, which never crosses the
   face, and (c) the same collision without the drift in a second simulation with a skin so
   large that no rebuild happens during the contact (Galilean invariance). All three must give
   the same relative velocity, spins and relative position. The scenes differ only in the
   rounding of positions (~1e-17 m against overlaps of ~1e-4 m) and of the drift velocity, so
   the results agree to round-off in f64: we assert 1e-9 relative (1e6 x double epsilon,
   ample for the ~10^3 steps of accumulation). Any lost or mis-carried history (spring reset at
   a rebuild or a wrap, a partner's image taken wrongly) changes the result at O(1).
2. A sphere leaving through a non-periodic face is removed: the particle count drops by one and
   the `particles/lost` series counts it; the spheres crossing the periodic face are not lost.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

SOFT = dict(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.25)
R = 0.005
SIDE = 0.1
U = 2.0                   # m/s drift along x
V_APPROACH = 0.5          # m/s each, along the line of centres
V_SLIP = 0.3              # m/s each, along z (tangential)
GAP = 1e-3
N = np.array([math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0])
W_A = np.array([0.0, 0.0, 50.0])
W_B = np.array([10.0, 0.0, 0.0])
TOL = 1e-9


def _pair(centre, drift):
    a = centre + (R + GAP / 2) * N
    b = centre - (R + GAP / 2) * N
    va = drift - V_APPROACH * N + np.array([0, 0, V_SLIP])
    vb = drift + V_APPROACH * N - np.array([0, 0, V_SLIP])
    return [a, b], [va, vb], [W_A, W_B]


def _scene(tmp, name, positions, velocities, spins, skin, lo, hi, periodic, dt):
    return (h.header(dt=dt, lo=lo, hi=hi, periodic=periodic, skin=skin, output_interval=1e-4)
            + h.material("ball", **SOFT) + h.interaction("ball", "ball", 0.5, 0.5)
            + h.csv_fill(tmp, name, "ball", positions, R, velocities, spins))


def _min_image_x(d):
    d = d.copy()
    d[..., 0] -= SIDE * np.round(d[..., 0] / SIDE)
    return d


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("periodic")
    m = h.sphere_mass(R, SOFT["density"])
    e_eff = h.youngs_eff(SOFT["youngs_modulus"], SOFT["poisson_ratio"])
    t_c = h.hertz_impact(m / 2, R / 2, e_eff, 2 * V_APPROACH)["time"]
    dt = t_c / 100
    t_touch = GAP / (2 * V_APPROACH)
    t_mid = t_touch + t_c / 2
    # sphere b reaches the face x = SIDE at mid-contact; sphere a starts already wrapped
    b_x0 = SIDE - (U + V_APPROACH * N[0]) * t_mid
    centre = np.array([b_x0 + (R + GAP / 2) * N[0], 0.0, 0.0])
    (a, b), vel, spin = _pair(centre, np.array([U, 0, 0]))
    assert a[0] > SIDE > b[0]
    a_wrapped = a - np.array([SIDE, 0, 0])
    crossing = [a_wrapped, b]
    shifted = [a - np.array([SIDE / 2, 0, 0]), b - np.array([SIDE / 2, 0, 0])]
    shifted[0][1] += 0.05
    shifted[1][1] += 0.05
    # a lone sphere leaving through the non-periodic +y face
    leaver = np.array([0.05, 0.085, 0.02])
    positions = crossing + shifted + [leaver]
    velocities = vel + vel + [np.array([0.0, 5.0, 0.0])]
    spins = spin + spin + [np.zeros(3)]
    steps = int(round(3 * t_mid / dt))
    text = _scene(tmp, "cross.csv", positions, velocities, spins, 5e-4, (0, -0.02, -0.02),
                  (SIDE, 0.1, 0.04), ("x",), dt)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        rebuilds0 = getattr(getattr(sim.engine, "broadphase", None), "rebuilds", None)
        sim.step(steps)
        p1 = sim.particles()
        series1 = sim.series
        rebuilds = getattr(getattr(sim.engine, "broadphase", None), "rebuilds", None)
        count1 = sim.particle_count
    # (c) no drift, no rebuild during the contact
    (a0, b0), vel0, spin0 = _pair(np.array([0.05, 0.0, 0.0]), np.zeros(3))
    text = _scene(tmp, "still.csv", [a0, b0], vel0, spin0, 5e-3, (0, -0.02, -0.02),
                  (SIDE, 0.1, 0.04), (), dt)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp), arch="cpu", precision="f64") as sim:
        sim.step(steps)
        p2 = sim.particles()
    return dict(p1=p1, p2=p2, series=series1, count=count1, steps=steps, dt=dt, t_c=t_c,
                rebuilds=(rebuilds - rebuilds0) if rebuilds is not None else None, vel=vel)


def _relative(p, i, j, drift):
    dv = p["velocity"][i] - p["velocity"][j]
    dx = _min_image_x(p["position"][i] - p["position"][j])
    return dict(dv=dv, dx=dx, wa=p["angular_velocity"][i], wb=p["angular_velocity"][j],
                va=p["velocity"][i] - drift)


def test_contact_across_periodic_face_keeps_history(runs):
    p1, p2 = runs["p1"], runs["p2"]
    drift = np.array([U, 0, 0])
    ids = list(p1["id"])
    crossing = _relative(p1, ids.index(0), ids.index(1), drift)
    shifted = _relative(p1, ids.index(2), ids.index(3), drift)
    still = _relative(p2, 0, 1, np.zeros(3))
    dv_in = runs["vel"][0] - runs["vel"][1]
    print(f"\nperiodic: {runs['steps']} steps, contact {runs['t_c'] / runs['dt']:.0f} steps, "
          f"rebuilds {runs['rebuilds']}")
    for name, r in (("crossing", crossing), ("shifted", shifted), ("no drift", still)):
        print(f"  {name:9s} dv = {np.array2string(r['dv'], precision=9)}  "
              f"w_a = {np.array2string(r['wa'], precision=6)}  w_b = {np.array2string(r['wb'], precision=6)}")
    diff = max(np.abs(crossing[k] - other[k]).max() / max(np.abs(still[k]).max(), 1.0)
               for k in ("dv", "va", "wa", "wb") for other in (shifted, still))
    print(f"  largest relative difference between the three: {diff:.1e}")
    # the collision happened and did something history-dependent
    assert np.linalg.norm(crossing["dv"] - dv_in) > 0.5
    assert np.linalg.norm(crossing["wa"] - W_A) > 1.0
    for key in ("dv", "va", "wa", "wb"):
        scale = max(np.abs(still[key]).max(), 1.0)
        assert np.abs(crossing[key] - shifted[key]).max() < TOL * scale, key
        assert np.abs(crossing[key] - still[key]).max() < TOL * scale, key
    assert np.abs(crossing["dx"] - shifted["dx"]).max() < TOL * 2 * R
    assert np.abs(crossing["dx"] - still["dx"]).max() < TOL * 2 * R
    if runs["rebuilds"] is not None:
        assert runs["rebuilds"] >= 5


def test_leaving_a_non_periodic_face_is_counted(runs):
    s = runs["series"]
    assert runs["count"] == 4
    assert list(runs["p1"]["id"]) == [0, 1, 2, 3]
    assert s["particles/lost"][0] == 0 and s["particles/lost"][-1] == 1
    assert s["particles/count"][0] == 5 and s["particles/count"][-1] == 4
    # the sphere crossing the periodic face is wrapped, not lost
    x = runs["p1"]["position"][:, 0]
    assert np.all((x >= 0) & (x < SIDE))
