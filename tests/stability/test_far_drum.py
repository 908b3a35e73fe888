"""The same small drum in f32 at the origin and 6 m away from it (issue 11, item 3, case 5).

Scene: 200 glass spheres of r = 4 mm (E softened to 5 MPa, mu 0.5, mu_r 0.02) in a drum of
R = 60 mm, L = 24 mm with end walls (no flights), f32, dt = 8e-5 s (the automatic step, 4.2e-5 s,
is sized for a fall across the whole domain at 1.8 m/s; this one resolves a contact at the
rolling bed's 0.5 m/s in 14-16 steps, at the fill's 1.5 m/s landing in 11-13, above the 8 the
loader demands, and halves the run time). The fill falls and rests with the drum still until
0.6 s, then the drum turns at 20 rpm (Froude 0.027: a rolling bed). Both drums start from the
same bed (the loader's placement at the origin, moved by the offset, through a CSV file). The
far drum's axis is at (0, 4.243, 4.243): 6 m from the origin, both transverse coordinates in
[4, 8), where f32 spacing is q = 2^-21 = 4.77e-7 m (at the origin drum's 0.05 m: 3.7e-9 m).

What f32 allows at 6 m. Positions are stored to q = 4.8e-7 m. Against the overlaps of this bed
(static: ~3.5e-5 m under five layers, E* = 2.7 MPa; ~5e-4 m in impacts) that is 1.4 % of a
resting contact's overlap, i.e. a force noise of ~2 % per contact, random in sign, averaged
over ~300 contacts and 10^4 steps in the torque: < 0.1 % on a mean torque, nothing on the bed's
centre of mass. Per step a particle moving at v moves v dt: 8e-6 m (17 q) at 0.1 m/s, rounded
by up to q/2 (3 %), unbiased; but a particle slower than q / (2 dt) = 3.0 mm/s does not move at
all until its velocity has grown past that, so a resting bed cannot settle closer than one
position step to its equilibrium: it jitters, at rms speeds up to ~q / dt = 6 mm/s, a kinetic
energy of at most 0.5 M (q/dt)^2 = 2.4e-6 J (M = 0.134 kg), against ~1e-10 J at the origin
(q/dt there: 4.7e-5 m/s).

The torque is checked sharply on its own: in each drum the drum's axial torque, summed from
the contacts with lever arms from the (f32, 6 m out) positions, must balance gravity's torque on
the bed, -g sum m y, within 2 % (measured: 0.0 % near, 0.2 % far; a lever arm off by 1 mm would
be 5 %).

The rolling bed is a chaotic flow: the two drums leave the same start but differ by 1e-15 m
(f64) or 1e-7 m (f32) after a step, and their beds are different packings within a second (in
f64, near, 1 um and 1 mm away, and 6 m away: centre-of-mass trajectories agree to 1e-12 m at
0.3 s and differ by millimetres from 1.1 s on; in f32 the far bed has already settled into a
different packing, 1 mm from the near one's, at 0.58 s). So the near and far runs can agree
only as well as two independent runs do: their window averages (1.0-1.8 s) scatter, measured
over 9 runs (f32 seeds 1-6 and f64 seeds 1-3, at the origin and at 6 m alike), by sd 1.7 % in
torque, 0.25 mm in the centre of mass's distance from the axis, 1.1 deg in its angle, 1.5 deg
in the dynamic angle of repose and 8 % in kinetic energy. The tolerance on a near - far
difference is 3 sqrt(2) sd: 7 % in torque, 1.1 mm, 4.7 deg, 6.3 deg and 34 %. Measured (seed
1): torque -0.02589 / -0.02629 N m (1.5 %), centre of mass 0.16 mm and 0.95 deg, angle of
repose 39.7 / 41.0 deg, kinetic energy +14 % (f64 near and far differ by 3.4 % in torque and
1.4 deg: the scatter, not f32). Over f32 seeds 1-6 the far drum's mean torque was -0.02642 N m
against -0.02629 N m at the origin (sd 0.0002 and 0.0004): no f32 effect on the rolling bed is
measurable. These tolerances are wide - they cannot see the far drum turning at 23 instead
of 20 rpm (torque +3 %, kinetic energy +20 %: passes) - but they do see a different bed: a
rolling friction of 0.1 instead of 0.02 in the far drum (torque +11 %, centre of mass +6.6 deg)
fails them (checked by hand).

Found (issue 11), fixed (issue 31 item 6): the far bed did not come to rest. With the drum
still, the bed at the origin reaches a kinetic energy of 3e-11 J (minimum over the samples
0.4-0.58 s) while the one at 6 m kept jittering: minimum 3.5e-7 J, mean 8.5e-7 J (v_rms 2.6
mm/s), 10^4 times more, as q/dt predicts; a shorter step made it worse. Now an f32 scene whose
domain reaches beyond 1 m splits its positions (engine/precision.py): each carries an f32
residual, the drift adds v dt to the pair in f64, and the contacts add the residuals to the
(exact) differences of near coordinates, and take mesh triangles relative to the body's
pivot. Measured: the far bed rests at 1.45e-11 J against 6.5e-12 J at the origin (the near
bed's own figure varies 3e-12 - 3e-11 J between builds); asserted within 10x the near one's.

Also bounded (both drums): finite, no particle lost or outside the shell, overlaps sampled at
every output (0.02 s) below 1.1 x the elastic Hertz overlap of a sphere falling across the
drum (2 R) onto another (m*/2, r/2: 13 % of r), kinetic energy below the potential energy of
the fill falling across the drum plus the drum's surface speed.
"""
from __future__ import annotations

import math
import time

import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.app import analysis

R, L, R_P = 0.06, 0.024, 0.004
COUNT = 200
RPM = 20.0
SETTLE = 0.6                 # s at rest before the drum starts
REST = (0.4, 0.58)           # s: the bed at rest (samples before the drum starts)
END = 1.8
WINDOW = (1.0, END)          # s: rolling-bed averages over this window
DT = 8e-5
G = 9.81
FAR = 6.0 / math.sqrt(2.0)   # the far drum's axis at (0, FAR, FAR): 6 m from the origin


FILL = f"""[[particles]]
material = "glass"
radius = {R_P}
count = {COUNT}
region = {{ cylinder = {{ axis_point = [0.001, 0, 0], axis_direction = [1, 0, 0], radius = {R - 0.004}, length = {L - 0.002} }} }}
"""


def write_fill(tmp_path, offset, seed=1):
    """The fill the loader places in the drum at the origin, moved by ``offset``: both drums
    start from the same bed (to f64 rounding; f32 rounds the far one's positions by up to
    2.4e-7 m when they are uploaded)."""
    from taichi_dem.scene.loader import parse_scene
    from taichi_dem.setup.placement import place_fills
    near = parse_scene(scene((0.0, 0.0, 0.0), seed, fill=FILL))
    x = place_fills(near, np.random.default_rng(seed)).position + np.asarray(offset, float)
    lines = ["x,y,z,radius,vx,vy,vz,wx,wy,wz"]
    lines += [",".join(repr(float(c)) for c in (*p, R_P, 0, 0, 0, 0, 0, 0)) for p in x]
    (tmp_path / "drum_fill.csv").write_text("\n".join(lines) + "\n")
    return '[[particles]]\nmaterial = "glass"\nfile = "drum_fill.csv"\n'


def scene(offset, seed=1, precision="f32", fill=""):
    ox, oy, oz = offset
    return f"""
[simulation]
end_time = {END}
gravity = [0.0, 0.0, -{G}]
precision = "{precision}"
seed = {seed}
dt = {DT}

[domain]
min = [{ox - 0.01}, {oy - R - 0.01}, {oz - R - 0.01}]
max = [{ox + L + 0.01}, {oy + R + 0.01}, {oz + R + 0.01}]

[materials.glass]
density = 2500.0
youngs_modulus = 5e6
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.02

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.02

[[bodies]]
name = "drum"
material = "steel"
mesh = {{ builder = "drum", radius = {R}, length = {L}, end_walls = true, origin = [{ox}, {oy}, {oz}] }}
motion = {{ rotate = {{ axis_point = [{ox}, {oy}, {oz}], axis_direction = [1, 0, 0], speed = [[0.0, "0 rpm"], [{SETTLE}, "{RPM} rpm"]] }} }}

{fill}

[output]
interval = 0.02
"""


def q_far() -> float:
    """f32 spacing at the far drum's coordinates, m."""
    return float(np.spacing(np.float32(FAR)))


def run(tmp_path, offset, seed=1, precision="f32"):
    t0 = time.perf_counter()
    ox, oy, oz = offset
    rec = {"t": [], "com": [], "gravity": [], "theta": [], "ke": [], "shell": [], "pair": [],
           "outside": []}
    text = scene(offset, seed, precision, write_fill(tmp_path, offset, seed))
    with td.Simulation.from_text(text, base_dir=str(tmp_path)) as sim:
        def watch(sim, values):
            p = sim.particles()
            y = p["position"][:, 1] - oy
            z = p["position"][:, 2] - oz
            x = p["position"][:, 0] - ox
            r, m = p["radius"], p["mass"]
            rec["t"].append(sim.time)
            rec["com"].append((np.sum(m * y) / m.sum(), np.sum(m * z) / m.sum()))
            # the drum's axial torque balances gravity's on the bed, -g sum m y, less dL/dt
            rec["gravity"].append(-G * float(np.sum(m * y)))
            rec["ke"].append(values.get("particles/kinetic_energy", np.nan))
            rho = np.hypot(y, z)
            rec["shell"].append(float(np.max((rho + r - R) / r)))
            rec["outside"].append(int(np.sum((rho > R) | (x < 0) | (x > L))))
            rel = np.stack([x, y, z], axis=1)
            d = np.linalg.norm(rel[:, None] - rel[None], axis=2)
            np.fill_diagonal(d, np.inf)
            rec["pair"].append(float(np.max((r[:, None] + r[None] - d) / np.minimum(r[:, None], r[None]))))
            if sim.time > SETTLE + 0.2:
                rec["theta"].append(analysis.bed_surface(y, z, r, 2 * R_P)[0])
            else:
                rec["theta"].append(np.nan)
        sim.add_observer(watch)
        sim.run(REST[1])
        p = sim.particles()
        rested = p["position"] - np.array(offset)
        sim.run(END)
        s = sim.series
        out = dict(dt=sim.dt, n=sim.particle_count, mass=float(sim.particles()["mass"].sum()))
    t = np.array(rec["t"])
    torque = s["bodies/drum/axial_torque"]
    w = (t > WINDOW[0] + 1e-9) & (t <= WINDOW[1] + 1e-9)
    rest = (t > REST[0] + 1e-9) & (t <= REST[1] + 1e-9)
    com = np.array(rec["com"])
    out.update(
        rested=rested,
        torque=float(np.mean(torque[w])), torque_sd=float(np.std(torque[w])),
        torque_rest=float(np.mean(torque[rest])),
        gravity_torque=float(np.mean(np.array(rec["gravity"])[w])),
        com_y=float(np.mean(com[w, 0])), com_z=float(np.mean(com[w, 1])),
        com_angle=float(np.degrees(np.mean(np.arctan2(com[w, 0], -com[w, 1])))),
        theta=float(np.degrees(np.nanmean(np.array(rec["theta"])[w]))),
        ke=float(np.mean(np.array(rec["ke"])[w])), ke_rest=float(np.min(np.array(rec["ke"])[rest])),
        ke_max=float(np.nanmax(rec["ke"])),
        shell=float(np.max(rec["shell"])), pair=float(np.max(rec["pair"])),
        outside=int(np.max(rec["outside"])), finite=bool(np.all(np.isfinite(s["particles/kinetic_energy"]))),
        wall_s=time.perf_counter() - t0)
    return out


@pytest.fixture(scope="module")
def drums(tmp_path_factory):
    near = run(tmp_path_factory.mktemp("near"), (0.0, 0.0, 0.0))
    far = run(tmp_path_factory.mktemp("far"), (0.0, FAR, FAR))
    return near, far


def _bounds():
    m = 4 / 3 * math.pi * R_P ** 3 * 2500.0
    e_eff = 1.0 / (2 * (1 - 0.25 ** 2) / 5e6)
    v = math.sqrt(2 * G * 2 * R)
    pair = 1.1 * (15 * (m / 2) * v ** 2 / (16 * e_eff * math.sqrt(R_P / 2))) ** 0.4 / R_P
    speed = 2 * math.pi * RPM / 60 * R
    return pair, COUNT * m * (G * 2 * R + 0.5 * speed ** 2)


def test_both_drums_stay_bounded(drums):
    pair, ke = _bounds()
    for m in drums:
        assert m["finite"] and m["n"] == COUNT and m["outside"] == 0, m
        assert m["pair"] < pair and m["shell"] < pair, (m, pair)
        assert m["ke_max"] < ke, (m, ke)


def test_torque_balances_the_bed_in_both_drums(drums):
    """The drum's torque, summed from the contacts about its axis (lever arms from f32
    positions 6 m out in the far drum), balances gravity's torque on the bed (the bed's angular
    momentum changes little over the window): within 2 %, as tests/verification/test_drum.py
    asks at the origin in f64. Measured: 0.0 % and 0.2 %."""
    for m in drums:
        assert abs(m["torque"] / m["gravity_torque"] - 1) < 0.02, m


def test_far_drum_rolls_like_the_near_one(drums):
    near, far = drums
    d_radius = math.hypot(far["com_y"], far["com_z"]) - math.hypot(near["com_y"], near["com_z"])
    print(f"\n  torque near {near['torque']:.5f} far {far['torque']:.5f} N m; centre of mass "
          f"angle {near['com_angle']:.2f} / {far['com_angle']:.2f} deg, radius difference "
          f"{d_radius * 1e3:.3f} mm; dynamic angle of repose {near['theta']:.1f} / "
          f"{far['theta']:.1f} deg; KE {near['ke']:.4g} / {far['ke']:.4g} J; "
          f"{near['wall_s']:.1f} + {far['wall_s']:.1f} s")
    assert near["torque"] < 0 and far["torque"] < 0          # the bed leans up the rising side
    assert abs(far["torque"] / near["torque"] - 1) < 0.07
    assert abs(d_radius) < 1.1e-3
    assert abs(far["com_angle"] - near["com_angle"]) < 4.7
    assert abs(far["theta"] - near["theta"]) < 6.3
    assert abs(far["ke"] / near["ke"] - 1) < 0.34            # no energy gained far away


def test_far_bed_at_rest_jitters_only_as_f32_allows(drums):
    near, far = drums
    mass = near["mass"]
    allowed_far = 0.5 * mass * (q_far() / DT) ** 2
    print(f"\n  resting bed KE (minimum over {REST[0]}-{REST[1]} s): near {near['ke_rest']:.3g} J, "
          f"far {far['ke_rest']:.3g} J; f32 allows 0.5 M (q/dt)^2 = {allowed_far:.3g} J at 6 m")
    assert near["ke_rest"] < 1e-8                # at rest (measured 3e-11 J)
    assert far["ke_rest"] < allowed_far


def test_far_bed_comes_to_rest_like_the_near_one(drums):
    """Split positions (engine/precision.py): the far bed comes to rest, no longer jittering at
    the f32 floor. Without them the far bed stayed at 3.5e-7 J (its minimum over the window,
    0.15 of 0.5 M (q/dt)^2); with them it falls below 1.2e-7 J (0.05 of it, three times
    under). How far below depends on the packing the chaotic fill reaches by 0.58 s: over
    seeds 1-6 (2026-12-05, stop 33) the far bed's minimum was 9.8e-8, 3.7e-11, 2.2e-9,
    1.3e-8, 7.7e-8 and 5.4e-11 J (with gravity compiled in as a constant instead of read at
    run time, a different rounding path: 1.9e-10, 8e-11, 1e-9, 1.9e-8, 6.2e-8, 7.9e-11 J),
    the near one's 3-5e-11 J: "within 10x of the near bed", asserted before, held for seed 1
    by the rounding path alone and failed seeds 4 and 5 in either build."""
    near, far = drums
    allowed_far = 0.5 * near["mass"] * (q_far() / DT) ** 2
    assert far["ke_rest"] < 0.05 * allowed_far


if __name__ == "__main__":
    import sys
    seeds = [int(s) for s in (sys.argv[1] if len(sys.argv) > 1 else "1").split(",")]
    where = sys.argv[2] if len(sys.argv) > 2 else "near,far"
    prec = sys.argv[3] if len(sys.argv) > 3 else "f32"
    import pathlib
    import tempfile
    d = pathlib.Path(tempfile.mkdtemp())
    for seed in seeds:
        beds = {}
        for name in where.split(","):
            off = (0.0, 0.0, 0.0) if name == "near" else (0.0, FAR, FAR)
            m = run(d, off, seed, prec)
            beds[name] = m.pop("rested")
            print(seed, name, prec, {k: (float(f'{v:.5g}') if isinstance(v, float) else v) for k, v in m.items()},
                  flush=True)
        if len(beds) == 2:
            diff = np.linalg.norm(beds["far"] - beds["near"], axis=1)
            print("  rested bed far - near: max %.3g m, median %.3g m" % (diff.max(), np.median(diff)))
