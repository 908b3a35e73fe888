"""[mobility] in a deep rotating drum (issue 12 items 3 and 5): error against time saved.

A periodic slice (4 d along the axis) of a bare drum of R = 0.25 m, 62 particle diameters
across, a third full of 8 mm glass beads (about 4,900), turning at 6 rpm (Froude number
w^2 R / g = 0.010: a rolling bed), gravity tilted 3 degrees along the axis so that the
cascading layer also conveys the bed axially, as in an inclined rotary drum or cooler. The
bed is about 19 d (six mobility cells of 3 d) deep: the passive region turning with the shell
is several cells thick, which the 9 d drum of bench/mobility_drum.py never was.

One fill and settle with mobility off (``--settle`` s, default 3 s: the fall, then about a
quarter turn of rolling) is captured in memory (run/checkpoint.capture: positions, velocities
and the contact history); from that one state each variant continues for ``--window`` s, the
variants stepped in alternating chunks of one output interval in the same process, so the
machine's noise falls on all of them alike. Per variant:

  axial torque       mean of /series/bodies/drum/axial_torque over the window     N m
  axial speed        the bed's mean axial velocity over the window, from the mass    m/s
                     crossing the mid-slice plane at every step (the conveying
                     speed: a drum of length L holds its material L / speed, the
                     mean residence time)
  dynamic angle      the free surface's slope (analysis.bed_surface)                deg
  inactive           mean fraction of particles inactive at the output samples
  stepping wall      seconds spent in sim.step over the window

    .venv/bin/python bench/mobility_deep_drum.py [--settle 3] [--window 4] [--variants off,body_frame]
"""
import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import taichi_dem  # noqa: E402
from taichi_dem.app import analysis  # noqa: E402
from taichi_dem.run import checkpoint  # noqa: E402

R, R_P, RPM, FILL, TILT_DEG, G = 0.25, 0.004, 6.0, 0.33, 3.0, 9.81
SLICE = 8 * R_P                      # 4 diameters along the axis, periodic
PACKING = 0.6                        # random close packing, for the particle count


def particle_count() -> int:
    """Beads for a bed filling FILL of the drum's cross-section at solid fraction PACKING."""
    volume = FILL * math.pi * R ** 2 * SLICE * PACKING
    return int(volume / (4.0 / 3.0 * math.pi * R_P ** 3))


def variant_text(name: str) -> str:
    """The [mobility] section of a variant: "off" (none), "at_rest", "body_frame" (defaults), or
    "body_frame:K[:C]" with the granular temperature threshold K g d (K = 1e-5 is the default)
    and mobility cells of C diameters (default 3)."""
    if name == "off":
        return ""
    if name == "at_rest":
        return "\n[mobility]\n"
    mode, *knobs = name.split(":")
    if mode != "body_frame":
        raise SystemExit(f"unknown variant {name!r}")
    text = '\n[mobility]\nmode = "body_frame"\nbody = "drum"\n'
    if knobs and knobs[0]:
        text += f"granular_temperature_threshold = {float(knobs[0]) * G * 2 * R_P:.4e}\n"
    if len(knobs) > 1:
        text += f"cell_size = {float(knobs[1]) * 2 * R_P:.4e}\n"
    return text


def scene(end_time: float, seed: int = 1, interval: float = 0.1) -> str:
    """The drum slice as scene TOML."""
    tilt = math.radians(TILT_DEG)
    gx, gz = G * math.sin(tilt), -G * math.cos(tilt)
    return f"""
[simulation]
end_time = {end_time}
gravity = [{gx:.6f}, 0.0, {gz:.6f}]
precision = "f32"
seed = {seed}

[domain]
min = [0.0, -{R + 0.01}, -{R + 0.01}]
max = [{SLICE}, {R + 0.01}, {R + 0.01}]
periodic = ["x"]

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
mesh = {{ builder = "drum", radius = {R}, length = {SLICE}, end_walls = false }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "{RPM} rpm" }} }}

[[particles]]
material = "glass"
radius = {R_P}
count = {particle_count()}
region = {{ cylinder = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], radius = {R - 0.006}, length = {SLICE} }} }}

[[sensors]]
kind = "mass_flow"          # the bed's axial throughput, counted at every step
name = "axial"
plane = {{ point = [{SLICE / 2}, 0, 0], normal = [1, 0, 0] }}

[output]
interval = {interval}
"""


def measure(sim, first: int, thetas, inactive) -> dict:
    """Window means: torque (N m), axial speed (m/s) from the throughput through the mid-slice
    plane (every crossing counted: u = mass flow x slice length / bed mass), dynamic angle
    (deg), inactive fraction."""
    torque = np.asarray(sim.series["bodies/drum/axial_torque"][first:], float)
    bed_mass = float(np.sum(sim.particles()["mass"]))
    flows = np.asarray(sim.series["sensors/axial/mass_flow"][first:], float)
    flows = flows[np.isfinite(flows)]
    flow = float(np.mean(flows))
    # standard errors of the window means from the samples' scatter (samples of 0.1 s taken
    # as independent: an estimate of the noise an error must exceed to be seen)
    se = dict(torque_se=float(np.std(torque, ddof=1) / np.sqrt(len(torque))),
              axial_se=float(np.std(flows, ddof=1) / np.sqrt(len(flows))) * SLICE / bed_mass)
    return dict(se, torque=float(np.mean(torque)), axial=flow * SLICE / bed_mass,
                theta=math.degrees(float(np.mean(thetas))),
                inactive=float(np.mean(inactive)) if inactive else 0.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--settle", type=float, default=3.0)
    ap.add_argument("--window", type=float, default=4.0)
    ap.add_argument("--interval", type=float, default=0.1)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--progress", action="store_true", help="a line per variant and chunk")
    ap.add_argument("--variants", default="off,body_frame,body_frame:1e-4,body_frame:1e-3")
    ap.add_argument("--state", help="continue from this saved settled state (HDF5 checkpoint) "
                    "instead of filling and settling")
    ap.add_argument("--save-state", help="write the settled state here")
    args = ap.parse_args(argv)
    names = args.variants.split(",")
    end = args.settle + args.window
    print(f"deep drum slice: {particle_count()} beads of {2 * R_P * 1e3:.0f} mm, R = {R} m, "
          f"{RPM} rpm, tilt {TILT_DEG} deg; settle {args.settle} s, window {args.window} s",
          flush=True)
    t0 = time.perf_counter()
    if args.state:
        snap = checkpoint.load(args.state)
        end = float(snap.attrs["time"]) + args.window
    else:
        with taichi_dem.Simulation.from_text(scene(end, args.seed, args.interval)) as sim:
            sim.run(args.settle)
            snap = checkpoint.capture(sim)
            print(f"settled in {time.perf_counter() - t0:.0f} s wall; dt {sim.dt:.3e} s", flush=True)
        if args.save_state:
            checkpoint.write(args.save_state, snap)
    for fields in snap.fields.values():         # judged afresh at the first rebuild
        for name in [k for k in fields if k.startswith("mobility_") or k == "particle_active"]:
            del fields[name]
    sims, state = {}, {}
    for v in names:
        s = taichi_dem.Simulation.from_text(scene(end + args.interval, args.seed, args.interval)
                                           + variant_text(v))
        checkpoint.restore(s, snap)
        s.step(1)                                   # compile and the first rebuild, untimed
        sims[v] = s
        state[v] = dict(first=len(s.series["time"]), wall=0.0, thetas=[], inactive=[])
    try:
        start = sims[names[0]].time
        chunks = int(round(args.window / args.interval))
        for k in range(chunks):
            for v in names:                          # alternating chunks of one output interval
                s, st = sims[v], state[v]
                t1 = time.perf_counter()
                s.run(start + (k + 1) * args.interval)
                st["wall"] += time.perf_counter() - t1
                p = s.particles()
                st["thetas"].append(analysis.bed_surface(p["position"][:, 1], p["position"][:, 2],
                                                         p["radius"], 2 * R_P)[0])
                if s.engine.model.effect("mobility") is not None:
                    st["inactive"].append(s.engine.model.effect("mobility").statistics()["inactive_particles"]
                                          / s.particle_count)
                if args.progress:
                    print(f"  {v:18s} t = {s.time:.3f} s  wall {st['wall']:.1f} s  inactive "
                          f"{st['inactive'][-1] if st['inactive'] else 0:.1%}  torque "
                          f"{s.series['bodies/drum/axial_torque'][-1]:.3f} N m", flush=True)
        results = {v: dict(measure(sims[v], state[v]["first"], state[v]["thetas"],
                                   state[v]["inactive"]), wall=state[v]["wall"])
                   for v in names}
    finally:
        for s in sims.values():
            s.close()
    ref = results[names[0]]
    print(f"{'variant':16s} {'torque N m':>11s} {'axial mm/s':>11s} {'angle deg':>9s} "
          f"{'inactive':>8s} {'wall s':>7s} {'speed-up':>8s} {'torque err':>10s} {'axial err':>9s}")
    for v, r in results.items():
        print(f"{v:16s} {r['torque']:11.4f} {r['axial'] * 1e3:11.3f} {r['theta']:9.2f} "
              f"{r['inactive']:8.1%} {r['wall']:7.1f} {ref['wall'] / r['wall']:8.2f} "
              f"{r['torque'] / ref['torque'] - 1:+10.2%} {r['axial'] / ref['axial'] - 1:+9.2%}")
    print(f"(standard errors of the reference's window means: torque {ref['torque_se']:.4f} N m "
          f"({ref['torque_se'] / abs(ref['torque']):.1%}), axial speed {ref['axial_se'] * 1e3:.3f} "
          f"mm/s ({ref['axial_se'] / abs(ref['axial']):.1%}); the same run's figures from another "
          f"state differ by about sqrt(2) of these)")
    return results


if __name__ == "__main__":
    main()
