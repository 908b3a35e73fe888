"""Heat that f32 cannot hold (issue 10 item 7).

At process temperatures the f32 spacing is large: 6.1e-5 K at 723 K. A cooler's per-step
temperature changes are ~1e-6..1e-5 K, so a plain f32 update T += dt Q/(m c) rounds them
away (round to nearest: below half a spacing, nothing changes) and heat is lost or made.
Temperatures in f32 scenes therefore carry an f64 residual (compensated summation): T is the
f32 value plus the residual, the fluxes use the f32 value (at most half a spacing off, i.e.
3e-5 K against temperature differences of kelvins) and the increments accumulate in f64.

1. Two fixed, touching ash spheres at 723.15 and 724.15 K (k = 0.3 W/(m K), c = 800 J/(kg K),
   30 mm) with per-step changes of 1.7e-8 K, far below the spacing: after 10 s the hot one has
   cooled by the analytic 0.5 (1 - exp(-lambda t)) K to 1e-3 (explicit Euler: relative error
   lambda dt / 2 ~ 2e-8; the f32 increments themselves ~1e-7 relative).
2. Hot ash on a water-cooled plane wall (303.15 K), f32, per-step changes of 2e-5 K (below half
   the spacing): the heat the particles lose equals the heat into the wall integrated over the
   run, to 1e-3 (trapezoid of 0.05 s samples of a flow that changes by ~1e-4 over the run:
   error ~1e-9; the f64 energy sums themselves to 1e-12).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem

R = 0.015
RHO, C, K = 870.0, 800.0, 0.3


def _header(dt, end_time, interval):
    return f"""
[simulation]
end_time = {end_time}
dt = {dt}
gravity = [0.0, 0.0, 0.0]
precision = "f32"
[domain]
min = [-0.2, -0.2, -0.05]
max = [0.2, 0.2, 0.2]
[materials.ash]
density = {RHO}
youngs_modulus = 1e7
poisson_ratio = 0.25
thermal_conductivity = {K}
heat_capacity = {C}
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
thermal_conductivity = 45.0
heat_capacity = 480.0
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["ash", "steel"]
restitution = 0.5
friction = 0.5
[output]
interval = {interval}
"""


def _fill(tmp_path, name, rows, temperature):
    lines = ["x,y,z,radius"] + [",".join(repr(float(c)) for c in (*p, R)) for p in rows]
    (tmp_path / name).write_text("\n".join(lines) + "\n")
    return (f"[[particles]]\nmaterial = \"ash\"\nfixed = true\ntemperature = {temperature}\n"
            f"file = \"{name}\"\n\n")


def _mc():
    return 4.0 / 3.0 * math.pi * R ** 3 * RHO * C


def test_small_changes_at_process_temperature_accumulate(tmp_path):
    overlap = 1e-5
    dt = 1e-3
    text = (_header(dt, 10.0, 1.0)
            + _fill(tmp_path, "a.csv", [(0.0, 0.0, 0.05)], 723.15)
            + _fill(tmp_path, "b.csv", [(2 * R - overlap, 0.0, 0.05)], 724.15)
            + "[thermal]\nconduction = true\n")
    h_c = 4 * K * K / (2 * K) * math.sqrt(R / 2 * overlap)
    rate = 2 * h_c / _mc()
    per_step = dt * h_c * 1.0 / _mc()
    assert per_step < 1e-7          # far below the f32 spacing at 723 K (6.1e-5 K)
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f32") as sim:
        e0 = sim.thermal_energy()
        sim.run()
        t = sim.time
        temps = sim.particles()["temperature"]
        e1 = sim.thermal_energy()
    cooled = 724.15 - temps[1]
    warmed = temps[0] - 723.15
    expected = 0.5 * (1.0 - math.exp(-rate * t))
    print(f"\nf32 at 723 K: per step {per_step:.2e} K; hot sphere cooled {cooled:.6e} K, "
          f"cold warmed {warmed:.6e} K, analytic {expected:.6e} K; energy drift "
          f"{(e1 - e0) / (_mc() * 1.0):.2e} of m c x 1 K")
    assert cooled == pytest.approx(expected, rel=1e-3)
    assert warmed == pytest.approx(expected, rel=1e-3)
    # the flows are antisymmetric: the sum m c T holds to the f64 sums' round-off
    assert abs(e1 - e0) < 1e-6 * _mc()


def test_heat_lost_by_hot_ash_is_the_heat_into_a_cold_wall(tmp_path):
    overlap = 1e-5
    dt = 1e-3
    rows = [(-0.15 + 0.035 * i, -0.15 + 0.035 * j, R - overlap) for i in range(9) for j in range(9)]
    text = (_header(dt, 5.0, 0.05)
            + "[[walls]]\nname = \"shell\"\nplane = { point = [0, 0, 0], normal = [0, 0, 1] }\n"
              "material = \"steel\"\ntemperature = 303.15\n\n"
            + _fill(tmp_path, "bed.csv", rows, 723.15)
            + "[thermal]\nwall_conduction = true\n")
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f32") as sim:
        # the wall's heat flow is recorded at the samples after the first step: start there
        sim.step(sim.output_every)
        e0 = sim.thermal_energy()
        sim.run()
        e1 = sim.thermal_energy()
        s = sim.series
        temps = sim.particles()["temperature"]
    q = s["walls/shell/heat_flow"][1:]          # W into the wall, at each sample
    time = s["time"][1:]
    into_wall = float(np.sum(0.5 * (q[1:] + q[:-1]) * np.diff(time)))
    lost = e0 - e1
    per_step = dt * q[0] / len(rows) / _mc()
    print(f"\nf32 cold wall: per-step change {per_step:.2e} K; particles lost {lost:.6f} J, "
          f"wall received {into_wall:.6f} J; mean T {temps.mean():.6f} K")
    assert 1e-6 < per_step < 3.0e-5         # below half the f32 spacing at 723 K
    assert q[0] > 0.0
    assert lost == pytest.approx(into_wall, rel=1e-3)
