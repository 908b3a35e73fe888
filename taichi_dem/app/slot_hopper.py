"""Seed 000's rectangular slot hopper: discharge mass flow with [mobility] on and off, and the
speed-up on the settled bed and on the discharge (``taichi-dem demo slot_hopper``).

The poster's case: glass beads d = 2.24 mm, rho = 2500 kg/m^3, restitution 0.94 between beads
and 0.9 on the walls, friction 0.2; a flat bottom 56 d wide with a central slot 11.2 d wide;
periodic depth. Its Table 2: 92.40 g/s without the algorithm and 92.41 g/s with it (the mean
of 7 runs, standard deviation 0.25 and 0.33 g/s). Its depth and bed height are not on the
poster; here the depth is 4 d (periodic, two pair cut-offs and more) and the bed about 30 d high,
so the flow (per unit depth) is what compares, not the poster's g/s.

Three phases, all from the same settled bed:
1. fill and settle (the demo's scene, demos/slot_hopper.toml: a closed floor, the plane z = 0);
2. the settled bed stepped with mobility on and off, interleaved (the "settled" speed-up);
3. the slot opened (the floor becomes two plates, particles below z = -20 mm leave and are
   counted), discharged with mobility on and off: mass flow over 15 - 60 % of the bed out, and
   the wall time of each run (the "discharge" speed-up).
E is softened to 5 MPa (the step is set by it; discharge through an opening is set by gravity,
friction and restitution, tests/regression/test_hopper_beverloo.py).
"""
import math
import time
from pathlib import Path

import numpy as np

D = 2.24e-3                  # m, bead diameter
RHO = 2500.0                 # kg/m^3


def geometry(width_d=56.0, slot_d=11.2, depth_d=4.0):
    """Half width, half slot, depth (m)."""
    return 0.5 * width_d * D, 0.5 * slot_d * D, depth_d * D


def scene_text(*, phase="fill", count=7700, width_d=56.0, slot_d=11.2, depth_d=4.0,
               end_time=0.45, mobility=True, particles_file=None, interval=0.01, h5=None,
               threshold="auto", seed=1):
    """The TOML text of one phase: "fill" (closed floor, a fill region above it) or
    "discharge" (the slot open; ``particles_file`` a CSV of the settled bed)."""
    half, half_slot, depth = geometry(width_d, slot_d, depth_d)
    volume = count * math.pi / 6 * D ** 3
    fill_height = volume / (0.40 * 2 * half * depth) + 2 * D
    top = fill_height + 4 * D
    # discharge: the empty cells under the floor keep the cells over it mobile ("touching an
    # empty cell"): that is what wakes a frozen bed when its slot opens. (With the domain ending
    # at the floor there are none, and the bed over the opened slot stays frozen in the air.)
    bottom = -1e-3 if phase == "fill" else -20e-3
    lines = [
        f"# Seed 000's slot hopper ({phase}): {count} glass beads of 2.24 mm, floor 56 d with a "
        f"slot of 11.2 d, periodic depth {depth_d:g} d",
        "[simulation]", f"end_time = {end_time}", "gravity = [0.0, 0.0, -9.81]",
        'precision = "f32"', f"seed = {seed}", "",
        "[domain]", f"min = [{-half:.6g}, 0.0, {bottom:.6g}]",
        f"max = [{half:.6g}, {depth:.6g}, {top:.6g}]", 'periodic = ["y"]', "",
        "[materials.glass]", f"density = {RHO}", "youngs_modulus = 5.0e6", "poisson_ratio = 0.25", "",
        "[materials.steel]", "density = 7800.0", "youngs_modulus = 2.0e11", "poisson_ratio = 0.3", "",
        "[[interactions]]", 'pair = ["glass", "glass"]', "restitution = 0.94", "friction = 0.2", "",
        "[[interactions]]", 'pair = ["glass", "steel"]', "restitution = 0.9", "friction = 0.2", "",
        "[[walls]]", 'name = "left"', f"plane = {{ point = [{-half:.6g}, 0, 0], normal = [1, 0, 0] }}",
        'material = "steel"', "",
        "[[walls]]", 'name = "right"', f"plane = {{ point = [{half:.6g}, 0, 0], normal = [-1, 0, 0] }}",
        'material = "steel"', ""]
    if phase == "fill":
        lines += ["[[walls]]", 'name = "floor"', "plane = { point = [0, 0, 0], normal = [0, 0, 1] }",
                  'material = "steel"', ""]
    else:
        for name, x0, x1 in (("floor_left", -half, -half_slot), ("floor_right", half_slot, half)):
            lines += ["[[bodies]]", f'name = "{name}"', 'material = "steel"',
                      f'mesh = {{ builder = "box", min = [{x0:.6g}, 0.0, -0.003], '
                      f'max = [{x1:.6g}, {depth:.6g}, 0.0], normals = "outward" }}', ""]
    if particles_file is None:
        lines += ["[[particles]]", 'material = "glass"', f"radius = {D / 2}", f"count = {count}",
                  f"region = {{ box = {{ min = [{-half + 0.6 * D:.6g}, 0.0, {0.6 * D:.6g}], "
                  f"max = [{half - 0.6 * D:.6g}, {depth:.6g}, {fill_height:.6g}] }} }}", ""]
    else:
        lines += ["[[particles]]", 'material = "glass"', f'file = "{particles_file}"', ""]
    if mobility:
        value = f'"{threshold}"' if isinstance(threshold, str) else f"{threshold:g}"
        lines += ["[mobility]", "enabled = true", f"granular_temperature_threshold = {value}",
                  "solid_fraction_threshold = 0.4", ""]
    lines += ["[output]", f"interval = {interval}"] + ([f'h5 = "{h5}"'] if h5 else []) + [""]
    return "\n".join(lines)


def write_bed(sim, path):
    """The particles of ``sim`` as a CSV the loader reads (x,y,z,radius,vx..wz)."""
    p = sim.particles()
    data = np.column_stack([p["position"], p["radius"], p["velocity"], p["angular_velocity"]])
    np.savetxt(path, data, delimiter=",", header="x,y,z,radius,vx,vy,vz,wx,wy,wz", comments="")


def _stepping_time(sim, steps):
    t0 = time.perf_counter()
    sim.step(steps)
    return time.perf_counter() - t0


def settled_speedup(bed_csv, *, steps=400, repeats=3, **kw):
    """Wall time (s) of ``steps`` steps of the settled bed with mobility off and on, interleaved
    ``repeats`` times in one process; returns (median off, median on, inactive fraction)."""
    from ..run.simulation import Simulation
    base = Path(bed_csv).parent
    sims = {m: Simulation.from_text(scene_text(phase="fill", particles_file=Path(bed_csv).name,
                                               mobility=m, **kw), base_dir=str(base))
            for m in (False, True)}
    try:
        for s in sims.values():
            s.step(20)                                        # compile, first rebuild
        times = {False: [], True: []}
        for _ in range(repeats):
            for m in (False, True):
                times[m].append(_stepping_time(sims[m], steps))
        st = sims[True].engine.model.effect("mobility").statistics()
        frac = st["inactive_particles"] / max(sims[True].particle_count, 1)
        return float(np.median(times[False])), float(np.median(times[True])), frac
    finally:
        for s in sims.values():
            s.close()


def discharge(bed_csv, *, mobility, end_time, **kw):
    """Open the slot under the settled bed and discharge; returns (mass flow kg/s, wall time
    s, total mass kg, fit window); ``discharge.inactive`` then lists the inactive particles
    at each output sample (mobility on)."""
    from ..run.simulation import Simulation
    from . import analysis
    base = Path(bed_csv).parent
    text = scene_text(phase="discharge", particles_file=Path(bed_csv).name, mobility=mobility,
                      end_time=end_time, interval=0.005, **kw)
    inactive = []

    def count_inactive(sim, values):
        if sim.engine.model.effect("mobility") is not None:
            inactive.append(sim.engine.model.effect("mobility").statistics()["inactive_particles"])
    with Simulation.from_text(text, base_dir=str(base)) as sim:
        sim.add_observer(count_inactive)
        sim.step(1)
        t0 = time.perf_counter()
        sim.run()
        wall = time.perf_counter() - t0
        discharge.inactive = inactive          # inactive particles at each output sample
        t, out = analysis.discharged_mass(sim)
        total = float(analysis.initial_masses(sim).sum())
        t0_, t1_ = analysis.steady_window(t, out, total)
        return analysis.linear_rate(t, out, t0_, t1_), wall, total, (t0_, t1_)


def report(sim, *, discharge_time=1.2, settled_steps=400, **kw):
    """The summary of ``taichi-dem demo slot_hopper``: from the settled bed of ``sim``, the
    settled-bed speed-up and the discharge with mobility on and off."""
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "bed.csv"
        write_bed(sim, csv)
        n = sim.particle_count
        off, on, frac = settled_speedup(csv, steps=settled_steps, count=n, **kw)
        print(f"summary: {n} glass beads of 2.24 mm settled in the slot hopper (seed 000)")
        print(f"  settled bed: {settled_steps} steps take {off:.3g} s with mobility off, {on:.3g} s "
              f"with it on ({frac:.0%} of the particles inactive): speed-up {off / on:.2f}x "
              f"(medians of 3, interleaved)")
        rate_off, wall_off, total, w_off = discharge(csv, mobility=False, end_time=discharge_time,
                                                     count=n, **kw)
        rate_on, wall_on, _, w_on = discharge(csv, mobility=True, end_time=discharge_time,
                                              count=n, **kw)
        inactive = discharge.inactive
        depth = geometry(**{k: v for k, v in kw.items() if k in ("width_d", "slot_d", "depth_d")})[2]
        print(f"  discharge ({discharge_time:g} s, fit while 15 - 60 % of the {total * 1e3:.1f} g "
              f"bed left): {rate_off * 1e3:.2f} g/s without mobility, {rate_on * 1e3:.2f} g/s with "
              f"it ({(rate_on / rate_off - 1):+.2%}); per metre of depth {rate_off / depth:.4g} "
              f"and {rate_on / depth:.4g} kg/(m s) (poster: 92.40 vs 92.41 g/s, +0.01 %)")
        print(f"  discharge wall time: {wall_off:.3g} s off, {wall_on:.3g} s on: speed-up "
              f"{wall_off / wall_on:.2f}x (inactive while discharging: "
              f"{np.mean(inactive) / n:.0%} on average, {max(inactive) / n:.0%} at most)")
        return dict(settled_off=off, settled_on=on, inactive_fraction=frac, rate_off=rate_off,
                    rate_on=rate_on, wall_off=wall_off, wall_on=wall_on)
