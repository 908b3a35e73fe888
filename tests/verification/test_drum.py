"""A rotating drum: the torque on the shell balances the bed, and the bed stays inside (issue 3).

1. Torque balance. The drum's axial torque is summed from the contact forces (never
   reconstructed from accelerations). The bed's angular momentum about the axis changes by the
   drum's torque on it plus gravity's: over a window T, mean(T_drum_on_bed) + mean(T_gravity)
   = dL/T. The recorded series is the torque *on the drum* (= -T_drum_on_bed), the mean over
   all steps of each output interval. So mean(series) = mean(T_gravity) - dL/T, with the
   gravity torque sum_i m_i ((x_i - p) x g) . axis sampled every 10 ms and L = sum_i m_i
   ((x_i - p) x v_i) . axis + I_i w_i,x from the particle states at both ends. Asserted within
   2 % of the gravity torque: the sampled mean of a smooth series (the bed's centre of mass
   moves slowly in the rolling regime) against the all-steps mean.
2. No particle leaves the drum at any speed up to centrifuging (Froude number w^2 R / g from
   0.02 and 2): none is lost, none is outside the shell radius, and at Fr = 2 the bed
   centrifuges (Fr > 1: the wall holds the particles all the way round): particles ride over
   the top of the drum (z > 0.5 R), which no particle reaches in the rolling regime at Fr = 0.02.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

GLASS = dict(density=2500.0, youngs_modulus=5.0e6, poisson_ratio=0.25)
STEEL = dict(density=7800.0, youngs_modulus=2.0e11, poisson_ratio=0.3)
RADIUS, LENGTH, R_P = 0.1, 0.05, 0.004
G = 9.81


def _scene(tmp_path, rpm, count=500, precision="f64"):
    text = (h.header(gravity=(0, 0, -G), lo=(-0.01, -0.11, -0.11), hi=(0.06, 0.11, 0.11),
                     output_interval=0.01).replace('precision = "f64"', f'precision = "{precision}"')
            + h.material("glass", **GLASS) + h.material("steel", **STEEL)
            + h.interaction("glass", "glass", 0.5, 0.5, 0.02)
            + h.interaction("glass", "steel", 0.5, 0.5, 0.02)
            + "[[bodies]]\nname = \"drum\"\nmaterial = \"steel\"\n"
            + f"mesh = {{ builder = \"drum\", radius = {RADIUS}, length = {LENGTH}, end_walls = true }}\n"
            + "motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], "
            + f"speed = \"{rpm} rpm\" }} }}\n\n"
            + "[[particles]]\nmaterial = \"glass\"\n"
            + f"radius = {R_P}\ncount = {count}\n"
            + "region = { cylinder = { axis_point = [0.001, 0, 0], axis_direction = [1, 0, 0], "
            + f"radius = {RADIUS - 0.01}, length = {LENGTH - 0.002} }} }}\n\n")
    return taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision=precision)


def _angular_momentum(p):
    r, v = p["position"], p["velocity"]
    m = p["mass"]
    inertia = 0.4 * m * p["radius"] ** 2
    return float(np.sum(m * (r[:, 1] * v[:, 2] - r[:, 2] * v[:, 1]) + inertia * p["angular_velocity"][:, 0]))


def _gravity_torque(p):
    r, m = p["position"], p["mass"]
    return float(np.sum(m * (r[:, 1] * -G)))           # ((x - 0) x g) . e_x = y g_z


def test_drum_torque_balances_the_bed(tmp_path):
    with _scene(tmp_path, 15) as sim:
        sim.run(1.0)                        # settle into the rolling regime
        t0 = sim.time
        p = sim.particles()
        l0 = _angular_momentum(p)
        first = len(sim.series["time"])
        gravity = []
        while sim.time < t0 + 1.0 - 1e-9:
            sim.step(sim.output_every)
            gravity.append(_gravity_torque(sim.particles()))
        p = sim.particles()
        l1 = _angular_momentum(p)
        window = sim.time - t0
        torque = sim.series["bodies/drum/axial_torque"][first:]
    expected = np.mean(gravity) - (l1 - l0) / window
    print(f"\n  drum torque {np.mean(torque):.5f} N m; gravity torque of the bed {np.mean(gravity):.5f} "
          f"N m; dL/T {(l1 - l0) / window:.2e} N m")
    assert len(torque) == len(gravity)
    assert np.mean(torque) == pytest.approx(expected, rel=0.02)
    assert np.mean(gravity) < 0         # the bed leans up the rising side and pulls back


@pytest.mark.parametrize("froude", [0.02, 2.0])
def test_no_particle_leaves_and_the_bed_centrifuges(tmp_path, froude):
    omega = math.sqrt(froude * G / RADIUS)
    rpm = omega * 60 / (2 * math.pi)
    with _scene(tmp_path, rpm, precision="f32") as sim:
        top = 0.0
        outside = -math.inf
        turns = max(min(1.5 * 2 * math.pi / omega, 1.2), 0.8)    # 1.5 turns, 0.8 to 1.2 s
        while sim.time < turns:
            sim.step(sim.output_every * 5)
            p = sim.particles()
            x = p["position"]
            r = np.hypot(x[:, 1], x[:, 2])
            outside = max(outside, float(np.max(r) - RADIUS))
            if sim.time > 0.5 * turns:
                top = max(top, float(np.max(x[:, 2])))
        lost = sim.series["particles/lost"][-1]
    print(f"\n  Fr = {froude}: {rpm:.1f} rpm, lost {lost:.0f}, largest centre radius - R = "
          f"{outside:.2e} m, highest centre in the second half {top / RADIUS:.2f} R")
    assert lost == 0
    assert outside < 0.0                # every centre stays inside the shell
    if froude > 1.0:
        assert top > 0.5 * RADIUS
    if froude < 0.1:
        assert top < 0.5 * RADIUS
