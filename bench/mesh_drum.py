#!/usr/bin/env python3
"""Meshes benchmark: a drum with lifting flights and a counter-rotating paddle shaft inside.

Reports particle-steps per second with the mesh bodies, and the share of the step spent on
mesh contacts (Taichi's kernel profiler: the per-particle gather kernel, which holds the
mesh contacts, against the same kernel of a run with the bodies replaced by nothing-touching
far planes is not possible - particles would fall out - so we report the mesh-only kernels
(triangle binning, candidate search, frames) and the gather kernel separately).

    python bench/mesh_drum.py --particles 20000 --steps 1000 --repeats 3
    python bench/mesh_drum.py ... --thermal [--gas fixed|plug_flow|none] [--radiation] [--moisture]
"""
import argparse
import statistics
import sys
import time


THERMAL = """
[thermal]
conduction = true
wall_conduction = true
"""
FIXED_GAS = """[thermal.gas]
model = "fixed"
temperature = 400.0
"""
# hot gas counter-current to a drum fed at x = 0: enters at x = 0.5, 20 cells
PLUG_FLOW_GAS = """[thermal.gas]
model = "axial_plug_flow"
axis_point = [0.0, 0.0, 0.0]
axis_direction = [1, 0, 0]
length = 0.5
cells = 20
radius = 0.3
mass_flow = "0.05 kg/s"
inlet_temperature = "600 C"
flow = "against_axis"
density = 0.4
"""
# the burner end: particles in the last 0.1 m see an enclosure at 1200 C
RADIATION = """radiation = true
radiation_to = "1200 C"
radiation_region = { box = { min = [0.4, -0.3, -0.3], max = [0.5, 0.3, 0.3] } }
"""


def scene_text(particles: int, precision: str = "f32", thermal: bool = False,
               gas: str = "fixed", radiation: bool = False, moisture: bool = False,
               gas_gap: str = "off") -> str:
    """``gas_gap``: "off", "walls" (gas gap to the shell only) or "all" (and between
    particles: near pairs listed within the fluid lens)."""
    text = _scene_text(particles, precision)
    if not thermal:
        return text
    if radiation:
        text = text.replace("poisson_ratio = 0.25\n", "poisson_ratio = 0.25\nemissivity = 0.9\n", 1)
    if moisture:
        text = text.replace("count = ", "moisture = 0.05\ncount = ")
    # heat: hot gravel, a water-cooled shell, particle-particle conduction, convection to air
    text = text.replace("poisson_ratio = 0.25\n", "poisson_ratio = 0.25\nthermal_conductivity = 1.5\n"
                        "heat_capacity = 800.0\nreal_youngs_modulus = 5.0e10\n", 1)
    text = text.replace("poisson_ratio = 0.3\n", "poisson_ratio = 0.3\nthermal_conductivity = 45.0\n"
                        "heat_capacity = 480.0\n", 1)
    text = text.replace('name = "drum"\nmaterial = "steel"\n', 'name = "drum"\nmaterial = "steel"\ntemperature = 300.0\n')
    text = text.replace("count = ", "temperature = 450.0\ncount = ")
    gap = {"off": "", "walls": "gas_gap = true\ngas_gap_pairs = false\n",
           "all": "gas_gap = true\n"}[gas_gap]
    return (text + THERMAL + gap + (RADIATION if radiation else "")
            + {"fixed": FIXED_GAS, "plug_flow": PLUG_FLOW_GAS, "none": ""}[gas])


def _scene_text(particles: int, precision: str = "f32") -> str:
    return f"""
[simulation]
end_time = 10.0
gravity = [0.0, 0.0, -9.81]
precision = "{precision}"

[domain]
min = [-0.02, -0.32, -0.32]
max = [0.52, 0.32, 0.32]

[materials.gravel]
density = 2600.0
youngs_modulus = 5.0e6
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3

[[interactions]]
pair = ["gravel", "gravel"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.05

[[interactions]]
pair = ["gravel", "steel"]
restitution = 0.5
friction = 0.5
rolling_friction = 0.05

[[bodies]]
name = "drum"
material = "steel"
mesh = {{ builder = "drum", radius = 0.3, length = 0.5, end_walls = true, flights = 8, flight_height = 0.05 }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "8 rpm" }} }}

[[bodies]]
name = "shaft"
material = "steel"
mesh = {{ builder = "paddle_shaft", length = 0.5, shaft_radius = 0.03, rows = 5, paddles_per_row = 4, paddle_length = 0.15, paddle_width = 0.05, paddle_pitch_deg = 30 }}
motion = {{ rotate = {{ axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = "-20 rpm" }} }}

[[particles]]
material = "gravel"
radius = 0.005
count = {particles}
region = {{ cylinder = {{ axis_point = [0.01, 0, 0], axis_direction = [1, 0, 0], radius = 0.27, length = 0.48 }} }}

[output]
interval = 0.05
"""


def mesh_cost(sim, calls: int = 200):
    """Time the per-particle kernel (walls, mesh contacts, kick) with the current mesh lists and
    with them emptied, and the particle-pair kernel, on the same state. dt = 0 so the state
    does not move; the difference is what the mesh contacts cost per step."""
    import taichi as ti
    e = sim.engine
    n = e.count

    def timed(fn):
        fn()
        ti.sync()
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        ti.sync()
        return (time.perf_counter() - t0) / calls

    pair = timed(lambda: e._pair_forces(n, 0.0))
    with_mesh = timed(lambda: e._gather(n, 0.0, 0, 0))
    saved = e.mesh.mesh_count.to_numpy()
    touching = int((saved[:n] > 0).sum())
    e.mesh.mesh_count.fill(0)
    without = timed(lambda: e._gather(n, 0.0, 0, 0))
    e.mesh.mesh_count.from_numpy(saved)
    print(f"per step: particle pairs {pair * 1e3:.3f} ms; mesh contacts {(with_mesh - without) * 1e3:.3f} ms "
          f"({(with_mesh - without) / pair:.0%} of the pairs; {touching} particles have candidate "
          f"triangles)")


def gas_cost(sim, calls: int = 200):
    """Time the plug-flow gas's own kernel (per-particle conductance, per-cell sums with atomic
    adds on a few addresses, the serial march) against the particle-pair kernel."""
    import taichi as ti
    e = sim.engine
    n = e.count

    def timed(fn):
        fn()
        ti.sync()
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        ti.sync()
        return (time.perf_counter() - t0) / calls

    pair = timed(lambda: e._pair_forces(n, 0.0))
    gas = timed(lambda: e.model.effect("plug_flow_convection").stream.exchange(n, 0.0))
    print(f"per step: particle pairs {pair * 1e3:.3f} ms; plug-flow gas exchange {gas * 1e3:.3f} ms "
          f"({gas / pair:.1%} of the pairs)")


VARIANTS = {      # name -> scene_text keyword arguments
    "off": dict(thermal=False),
    "fixed": dict(thermal=True, gas="fixed"),
    "plug_flow": dict(thermal=True, gas="plug_flow"),
    "plug_flow+radiation": dict(thermal=True, gas="plug_flow", radiation=True),
    "plug_flow+radiation+moisture": dict(thermal=True, gas="plug_flow", radiation=True, moisture=True),
}
GAS_GAP_VARIANTS = {  # --compare-gas-gap: what conduction through the gas near contacts costs
    "off": dict(thermal=False),
    "fixed": dict(thermal=True, gas="fixed"),
    "fixed+gas_gap_walls": dict(thermal=True, gas="fixed", gas_gap="walls"),
    "fixed+gas_gap": dict(thermal=True, gas="fixed", gas_gap="all"),
}


def kernel_costs(sims, rounds: int, calls: int = 30):
    """The step's kernels (pairs, plug-flow gas, per-particle gather) of each variant on its
    settled state with dt = 0 (nothing moves), round-robin; median and least time per step.
    The least is the run least disturbed by other processes on a shared machine."""
    import taichi as ti
    times = {name: [] for name in sims}
    for _ in range(rounds):
        for name, sim in sims.items():
            e = sim.engine
            n = e.count

            def step():
                e._pair_forces(n, 0.0)
                for c in e.model.cell_effects:
                    c.after_pairs(e.context, n, 0.0)
                e._gather(n, 0.0, 0, 0, e.time)
            step()
            ti.sync()
            t0 = time.perf_counter()
            for _ in range(calls):
                step()
            ti.sync()
            times[name].append((time.perf_counter() - t0) / calls)
    base_med, base_min = statistics.median(times["off"]), min(times["off"])
    print("| variant | pair+gas+gather ms (median) | ratio | least ms | ratio |\n|---|---|---|---|---|")
    for name, v in times.items():
        print(f"| {name} | {statistics.median(v) * 1e3:.3f} | {statistics.median(v) / base_med:.2f} "
              f"| {min(v) * 1e3:.3f} | {min(v) / base_min:.2f} |")


def compare(a, variants=None) -> int:
    """The heat variants in one process, timed round-robin (each round times every variant
    once, so load from other processes on a shared machine hits them alike); medians over the
    rounds and time ratios against thermal off."""
    import taichi_dem as td
    variants = variants or VARIANTS
    sims = {}
    for name, kw in variants.items():
        sim = td.Simulation.from_text(scene_text(a.particles, a.precision, **kw), h5="")
        sim.run(a.settle)
        sim.step(max(a.steps // 10, 1))       # warm: every kernel compiled (sampling included)
        sims[name] = sim
        print(f"{name}: {sim.particle_count} particles settled {a.settle} s", flush=True)
    rates = {name: [] for name in sims}
    for r in range(a.repeats):
        for name, sim in sims.items():
            t0 = time.perf_counter()
            sim.step(a.steps)
            sim.engine.flags.to_numpy()
            rates[name].append(sim.particle_count * a.steps / (time.perf_counter() - t0))
        print(f"round {r + 1}: " + ", ".join(f"{n} {v[-1] / 1e6:.2f}" for n, v in rates.items()), flush=True)
    base = statistics.median(rates["off"])
    print("| variant | M particle-steps/s (median) | time ratio vs thermal off |\n|---|---|---|")
    for name, v in rates.items():
        m = statistics.median(v)
        print(f"| {name} | {m / 1e6:.2f} | {base / m:.2f} |")
    kernel_costs(sims, a.repeats)
    if "plug_flow" in sims:
        gas_cost(sims["plug_flow"])
    for sim in sims.values():
        sim.close()
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--particles", type=int, default=20000)
    p.add_argument("--steps", type=int, default=1000)
    p.add_argument("--settle", type=float, default=0.6, help="simulated seconds before timing")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--profile", action="store_true", help="kernel profiler breakdown")
    p.add_argument("--precision", default="f32")
    p.add_argument("--thermal", action="store_true", help="with heat transfer (conduction, "
                   "a water-cooled shell, convection)")
    p.add_argument("--gas", choices=("fixed", "plug_flow", "none"), default="fixed",
                   help="with --thermal: the gas model (plug_flow: 20 cells, counter-current)")
    p.add_argument("--radiation", action="store_true", help="with --thermal: radiation at the "
                   "burner end (the last 0.1 m)")
    p.add_argument("--moisture", action="store_true", help="with --thermal: wet particles "
                   "(X = 0.05) that dry")
    p.add_argument("--compare", action="store_true", help="time thermal off, fixed gas, plug-flow "
                   "gas, + radiation, + moisture in one process, round-robin, as ratios")
    p.add_argument("--compare-gas-gap", action="store_true", help="time thermal off, fixed gas, "
                   "+ gas gap to the shell, + gas gap between particles, round-robin")
    a = p.parse_args(argv)
    if a.compare:
        return compare(a)
    if a.compare_gas_gap:
        return compare(a, GAS_GAP_VARIANTS)
    import taichi as ti
    if a.profile:
        orig = ti.init
        ti.init = lambda **kw: orig(**{**kw, "kernel_profiler": True})
    import taichi_dem as td
    sim = td.Simulation.from_text(scene_text(a.particles, a.precision, a.thermal, a.gas,
                                             a.radiation, a.moisture), h5="")
    print("effects: " + ", ".join(e.name for e in sim.effects))
    print(f"{sim.particle_count} particles, {sum(len(b.faces) for b in sim.scene.bodies)} triangles, "
          f"dt = {sim.dt:.3g} s; settling {a.settle} s", flush=True)
    sim.run(a.settle)
    rates = []
    for r in range(a.repeats):
        if a.profile:
            ti.profiler.clear_kernel_profiler_info()
        t0 = time.perf_counter()
        sim.step(a.steps)
        sim.engine.flags.to_numpy()
        seconds = time.perf_counter() - t0
        rates.append(sim.particle_count * a.steps / seconds)
        print(f"run {r + 1}: {rates[-1] / 1e6:.2f} M particle-steps/s", flush=True)
    print(f"median: {statistics.median(rates) / 1e6:.2f} M particle-steps/s with meshes "
          f"({sim.particle_count} particles)")
    if a.profile:
        ti.profiler.print_kernel_profiler_info("count")
    mesh_cost(sim)
    if sim.engine.model.effect("plug_flow_convection") is not None:
        gas_cost(sim)
    sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
