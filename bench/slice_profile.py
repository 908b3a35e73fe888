#!/usr/bin/env python3
"""Where a mesh-heavy step's time goes, against a plain bed of the same spheres (issue 45 item 3).

The seed's cooler slice (demos/cooler_slice.toml: a periodic paddle row, the shell and the
paddle shaft as meshes, heat on, 15 mm calibrated ash, f32) filled to ``--holdup`` kg/m, and a
plain periodic bed of the same spheres, count, material, heat and time step lying on a floor
(plane walls, no mesh): each settled ``--settle`` s, then ``--steps`` steps timed ``--repeats``
times, the two alternated in one process; with ``--profile`` Taichi's kernel profiler sums the
time of each kernel over the timed steps (the stages: ``pair_forces`` the particle pairs,
``gather`` the mesh contacts and the integration, ``drift``, ``update_frames`` the bodies'
poses, the rest the neighbour-list and triangle-list rebuilds and the surface survey).

    python bench/slice_profile.py [--holdup 60] [--steps 500] [--repeats 3] [--profile]
    python bench/slice_profile.py --scene demos/dryers/dryer_slice.toml --holdup 75

``--scene`` takes another periodic slice whose first body is its shell (the flighted dryer
drum above); the bed then keeps that scene's materials, gas and heat.

Prints each case's particle-steps per second (median), ns per particle-step, their ratio, and
with ``--profile`` the per-kernel breakdown per particle-step of both.
"""
from __future__ import annotations

import argparse
import re
import statistics
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SLICE = ROOT / "demos" / "cooler_slice.toml"


def slice_text(holdup: float, path: Path = SLICE) -> tuple[str, int]:
    """The slice's scene (``path``, the cooler slice by default) filled to ``holdup`` kg/m,
    and its sphere count."""
    from taichi_dem.app import slice_map as sm
    from taichi_dem.app.overrides import apply, to_text
    from taichi_dem.scene.loader import parse_scene
    base = path.read_text()
    scene = parse_scene(base, source=str(path), base_dir=str(path.parent))
    count, _, _ = sm.holdup_count(scene, sm.slice_geometry(scene), ("kg/m", holdup))
    return to_text(apply(tomllib.loads(base), {"particles.0.count": count}, str(path))), count


def bed_text(count: int, path: Path = SLICE) -> str:
    """A plain periodic bed: the slice's domain, materials, interactions, heat, gas and dt,
    its ``count`` spheres poured onto a floor between two side walls 10 mm inside the domain
    (plane walls of the shell's material, the floor at the shell's temperature; no mesh)."""
    doc = tomllib.loads(path.read_text())
    from taichi_dem.app.overrides import to_text
    shell = doc.pop("bodies")[0]
    lo, hi = doc["domain"]["min"], doc["domain"]["max"]
    doc["simulation"]["gravity"] = [0.0, 0.0, -9.81]
    floor = {"name": "floor", "plane": {"point": [0, 0, lo[2] + 0.01], "normal": [0, 0, 1]},
             "material": shell["material"]}
    if "temperature" in shell:
        floor["temperature"] = shell["temperature"]
    doc["walls"] = [
        floor,
        {"name": "left", "plane": {"point": [0, lo[1] + 0.01, 0], "normal": [0, 1, 0]},
         "material": shell["material"]},
        {"name": "right", "plane": {"point": [0, hi[1] - 0.01, 0], "normal": [0, -1, 0]},
         "material": shell["material"]},
    ]
    doc["particles"][0]["count"] = count
    doc["particles"][0]["region"] = {"box": {
        "min": [lo[0], lo[1] + 0.02, lo[2] + 0.02],
        "max": [hi[0], hi[1] - 0.02, lo[2] + 0.4 * (hi[2] - lo[2])]}}
    return to_text(doc)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--holdup", type=float, default=60.0, help="kg/m")
    p.add_argument("--scene", type=Path, default=SLICE, help="a periodic slice whose first "
                   "body is its shell (default: the seed's cooler slice)")
    p.add_argument("--settle", type=float, default=0.5, help="simulated seconds before timing")
    p.add_argument("--steps", type=int, default=500)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--profile", action="store_true", help="Taichi's kernel profiler breakdown")
    a = p.parse_args(argv)
    import taichi as ti
    if a.profile:
        orig = ti.init
        ti.init = lambda **kw: orig(**{**kw, "kernel_profiler": True})
    import taichi_dem as td
    text, count = slice_text(a.holdup, a.scene)
    cases = {"slice": text, "plain bed": bed_text(count, a.scene)}
    rates = {name: [] for name in cases}
    launches: dict = {name: {} for name in cases}      # case -> kernel -> [ms per launch]
    particle_steps = {name: 0 for name in cases}
    # both alive at once, each settled, then timed in alternation (a noisy host's drift
    # falls on both alike): round r times the slice, then the bed
    sims = {name: td.Simulation.from_text(scene, h5="") for name, scene in cases.items()}
    try:
        for sim in sims.values():
            sim.run(a.settle)
        for _ in range(a.repeats):
            for name, sim in sims.items():
                n = sim.particle_count
                if a.profile:
                    ti.profiler.clear_kernel_profiler_info()
                t0 = time.perf_counter()
                sim.step(a.steps)
                sim.engine.flags.to_numpy()
                rates[name].append(n * a.steps / (time.perf_counter() - t0))
                particle_steps[name] += n * a.steps
                if a.profile:
                    for kernel, times in profiler_launches().items():
                        launches[name].setdefault(kernel, []).extend(times)
    finally:
        for sim in sims.values():
            sim.close()
    for name, r in rates.items():
        print(f"{name}: {count} particles, median {statistics.median(r) / 1e6:.2f} M "
              f"particle-steps/s ({', '.join(f'{x / 1e6:.2f}' for x in r)})", flush=True)
    paired = [b / s for s, b in zip(rates["slice"], rates["plain bed"])]
    print(f"paired ratio per round (slice cost / bed cost): "
          f"{', '.join(f'{x:.2f}' for x in paired)}; median {statistics.median(paired):.2f}")
    ns = {k: 1e9 / statistics.median(v) for k, v in rates.items()}
    print(f"ns per particle-step: slice {ns['slice']:.0f}, bed {ns['plain bed']:.0f}, "
          f"ratio {ns['slice'] / ns['plain bed']:.2f}")
    if a.profile:
        def per_particle_step(case, kernel):
            return 1e6 * sum(launches[case].get(kernel, [])) / particle_steps[case]   # ns

        def per_step(case, kernel):
            return len(launches[case].get(kernel, [])) / (a.steps * a.repeats)

        names = sorted(set(launches["slice"]) | set(launches["plain bed"]),
                       key=lambda k: -per_particle_step("slice", k))
        print(f"{'kernel':40s} {'slice ns':>9s} {'bed ns':>9s}   (per particle-step)")
        for k in names:
            s, b = per_particle_step("slice", k), per_particle_step("plain bed", k)
            if s > 0.5 or b > 0.5:
                print(f"{k[:40]:40s} {s:9.1f} {b:9.1f}   launches per step "
                      f"{per_step('slice', k):.3f} / {per_step('plain bed', k):.3f}")
    return 0


def profiler_launches() -> dict:
    """kernel -> [ms of each launch] from Taichi's kernel profiler since it was last cleared
    (the runtime's records, as ti.profiler.print_kernel_profiler_info reads them). Taichi
    names a kernel's offloaded tasks <kernel>_c<n>_<k>_<kind>...: the compile number <n>,
    which differs between scenes and trees, is dropped, the task <k> kept."""
    from taichi.lang import impl
    prog = impl.get_runtime().prog
    prog.sync_kernel_profiler()
    prog.update_kernel_profiler()
    out: dict = {}
    for rec in prog.get_kernel_profiler_records():
        out.setdefault(re.sub(r"_c\d+_", "#", rec.name), []).append(rec.kernel_time)
    return out


if __name__ == "__main__":
    sys.exit(main())
