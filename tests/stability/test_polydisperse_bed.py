"""A polydisperse bed with a 10:1 radius ratio settling on a floor (issue 11, item 3, case 2).

Scene (f64, automatic time step): in a 32 mm square box of plane walls on a steel floor, 120
small glass spheres of r = 0.5 mm on the floor, a layer of 3 x 3 large spheres of r = 5 mm
0.3 mm above them, 150 more small spheres in the gaps above that layer and 2 x 2 large ones
above those, in its hollows: the large spheres land on small ones lying on the floor (a small
sphere pinched between a sphere 1000 times heavier and a steel floor) or on the lower large
layer, the upper small ones trickle through the 5 mm holes of the large layer onto the floor.
Glass softened to E = 2e8 Pa (real glass would need 0.2 x 3.6e-8 s steps: 1.4 million for these
50 ms). The automatic step is 1.42e-6 s: the Hertz contact of a small sphere on the steel floor
at the 0.79 m/s of a fall across the domain in 20 steps (below 0.2 x the small spheres' Rayleigh
time, 1.9e-6 s). 50 ms, every second step checked (stability_helpers.Monitor); by then every
large sphere has landed and 124 small ones lie on the floor.

Bounds:
* finite state, nothing lost, no centre behind a wall, every small sphere's centre at least
  half its radius above the floor at every 5 ms sample (measured: 0.97 r);
* the overlap of each pair, as a fraction of its smaller radius (the Hertz overlap is set by
  the smaller sphere, R* -> r_small), at most 1.1 x the elastic Hertz maximum of the worst
  impact the scene can give a small sphere: a large one's whole mass (m* -> m_large, the small
  sphere backed by the floor) at R* of the pair (0.45 mm) and the speed of a fall from the
  highest large sphere's start down to the floor (0.44 m/s): (15 m* v^2 / (16 E* sqrt(R*)))^0.4
  = 22.5 % of 0.5 mm. Measured: 8.2 % (41 um), what an upper large sphere landing at 0.2 m/s on a
  small one lying on the lower layer gives (m* ~ m_large / 2: 8 % elastic);
* with a wall or the floor (every sphere, as a fraction of its radius): the same bound (a
  pinched small sphere's other contact, stiffer: glass on steel). Measured: 5.0 %;
* the mechanical energy KE + PE never above its start by more than 1e-3 of the potential energy
  the bed can lose (7e-4 J; the contacts only dissipate; a rise is made by the integrator).
  Measured: 2e-19 J.

Checked to fail (by hand, not part of the suite): the automatic step x 4 (about what a step
sized for a bed of mean-sized spheres would be): pair overlaps 9.4 r_s, energy gain 39 J,
55 spheres lost, one behind a wall; x 10 (a step sized for the large spheres): the divergence
check stops the run (overlap 5.6 r_s).
"""
from __future__ import annotations

import math
import time

import numpy as np

import taichi_dem as td
import stability_helpers as sh

R_L, R_S = 0.005, 0.0005
E, NU, RHO = 2e8, 0.25, 2500.0
G = 9.81
HALF = 0.016                  # half width of the box
END = 0.05
Z_SMALL_TOP = 0.0011          # top of the floor layer's region
Z_L1 = Z_SMALL_TOP + 0.0003 + R_L
S_L = 0.0106                  # large-layer spacing
Z_L2 = Z_L1 + math.sqrt(4 * R_L ** 2 - S_L ** 2 / 2) + 0.002


def scene(tmp_path, seed=1):
    rng = np.random.default_rng(seed)
    large = [((i - 1) * S_L, (j - 1) * S_L, Z_L1) for i in range(3) for j in range(3)]
    large += [((i - 0.5) * S_L, (j - 0.5) * S_L, Z_L2) for i in range(2) for j in range(2)]
    large = np.array(large)
    large[:, :2] += rng.uniform(-1e-4, 1e-4, (len(large), 2))
    lines = ["x,y,z,radius,vx,vy,vz,wx,wy,wz"]
    lines += [",".join(repr(float(c)) for c in (*x, R_L, 0, 0, 0, 0, 0, 0)) for x in large]
    (tmp_path / "large.csv").write_text("\n".join(lines) + "\n")
    walls = ""
    for name, point, normal in (("floor", (0, 0, 0), (0, 0, 1)),
                                ("xlo", (-HALF, 0, 0), (1, 0, 0)), ("xhi", (HALF, 0, 0), (-1, 0, 0)),
                                ("ylo", (0, -HALF, 0), (0, 1, 0)), ("yhi", (0, HALF, 0), (0, -1, 0))):
        walls += (f"[[walls]]\nname = \"{name}\"\nplane = {{ point = {list(map(float, point))}, "
                  f"normal = {list(map(float, normal))} }}\nmaterial = \"steel\"\n\n")
    h = HALF - 1e-5
    return f"""
[simulation]
end_time = {END}
gravity = [0.0, 0.0, -{G}]
precision = "f64"
seed = {seed}

[domain]
min = [{-HALF - 0.002}, {-HALF - 0.002}, -0.002]
max = [{HALF + 0.002}, {HALF + 0.002}, 0.03]

[materials.glass]
density = {RHO}
youngs_modulus = {E}
poisson_ratio = {NU}

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
friction = 0.5

{walls}
[[particles]]
material = "glass"
file = "large.csv"

[[particles]]
material = "glass"
radius = {R_S}
count = 120
region = {{ box = {{ min = [{-h}, {-h}, 0.0], max = [{h}, {h}, {Z_SMALL_TOP}] }} }}

[[particles]]
material = "glass"
radius = {R_S}
count = 150
region = {{ box = {{ min = [{-h}, {-h}, {Z_L1 + 0.002}], max = [{h}, {h}, {Z_L2 + 0.001}] }} }}

[output]
interval = 0.005
"""


def overlap_bound():
    """1.1 x the elastic Hertz overlap of a large sphere's whole mass falling from the highest
    start onto a small sphere on the floor, as a fraction of the small radius."""
    m_l = 4 / 3 * math.pi * R_L ** 3 * RHO
    r_eff = R_L * R_S / (R_L + R_S)
    v = math.sqrt(2 * G * (Z_L2 - R_L))
    return 1.1 * sh.hertz_overlap(m_l, r_eff, sh.youngs_eff(E, NU), v) / R_S, v


def run(tmp_path, seed=1, every=2):
    t0 = time.perf_counter()
    sim = td.Simulation.from_text(scene(tmp_path, seed), base_dir=str(tmp_path))
    mon = sh.Monitor(sim)
    small_low = math.inf
    try:
        n0 = sim.particle_count
        p = sim.particles()
        small = p["radius"] < 2 * R_S
        pe_avail = float(np.sum(p["mass"] * G * (p["position"][:, 2] - p["radius"])))
        while sim.time < END - 0.5 * sim.dt:
            mon.advance(0, every=every, until=min(sim.time + 0.005, END))
            p = sim.particles()
            small_low = min(small_low, float(np.min(p["position"][p["radius"] < 2 * R_S, 2])))
        out = mon.result()
        p = sim.particles()
        out.update(n_small=int(small.sum()), lost=n0 - sim.particle_count, dt=sim.dt,
                   limited_by=sim.timestep.limited_by, pe_avail=pe_avail,
                   small_low=small_low / R_S, ke_end=sim.kinetic_energy(),
                   small_on_floor=int(np.sum((p["radius"] < 2 * R_S) & (p["position"][:, 2] < 1.5 * R_S))),
                   wall_s=time.perf_counter() - t0)
    finally:
        mon.close()
        sim.close()
    return out


def test_polydisperse_bed_settles_within_bounds(tmp_path):
    m = run(tmp_path)
    bound, v = overlap_bound()
    print(f"\n  {m['n_small']} small + {13} large, dt {m['dt']:.3g} s ({m['limited_by']}); max pair "
          f"overlap {m['pair']:.4f} of the smaller r, wall {m['wall']:.4f} r, bound {bound:.3f} "
          f"(v {v:.2f} m/s); lowest small centre {m['small_low']:.3f} r_s; {m['small_on_floor']} "
          f"small on the floor at the end; energy gain {m['energy_gain']:.3g} J of {m['pe_avail']:.3g} J "
          f"available; KE end {m['ke_end']:.3g} J; {m['wall_s']:.1f} s")
    assert m["non_finite"] == 0 and m["lost"] == 0 and m["through"] == 0
    assert m["small_low"] > 0.5, m
    assert m["pair"] < bound, m
    assert m["wall"] < bound, m
    assert m["energy_gain"] < 1e-3 * m["pe_avail"], m


if __name__ == "__main__":
    import pathlib
    import sys
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        for seed in (int(s) for s in (sys.argv[1] if len(sys.argv) > 1 else "1").split(",")):
            print(seed, run(pathlib.Path(d), seed), overlap_bound())
