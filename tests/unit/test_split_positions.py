"""Split positions (engine/precision.py): an f32 scene reaching beyond 1 m keeps a residual per
position, so a slow particle far from the origin moves as it would at the origin."""
import numpy as np
import pytest

import taichi_dem as td

SCENE = """
[simulation]
end_time = 0.1
gravity = [0.0, 0.0, 0.0]
precision = "f32"
dt = 1e-4

[domain]
min = [{lo}, -0.05, -0.05]
max = [{hi}, 0.05, 0.05]
periodic = ["x"]

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5

[[particles]]
material = "glass"
radius = 0.004
count = 1
region = {{ box = {{ min = [{x0}, -0.0041, -0.0041], max = [{x1}, 0.0041, 0.0041] }} }}
velocity = [{v}, 0.0, 0.0]
"""


def _run(lo, hi, v, until=0.1):
    x0 = hi - 0.02
    text = SCENE.format(lo=lo, hi=hi, x0=x0 - 0.0041, x1=x0 + 0.0041, v=v)
    with td.Simulation.from_text(text, h5="") as sim:
        split = sim.engine.model.split_positions
        start = sim.particles()["position"][0].copy()
        sim.run(until)
        return split, start, sim.particles()["position"][0]


def test_a_slow_particle_6_m_out_moves_as_at_the_origin():
    """1e-4 m/s with dt = 1e-4 s: 1e-8 m per step, 1/48 of the f32 spacing at 6.5 m (4.8e-7
    m), which rounds every step away without the residual; with it the particle travels
    v t = 1e-5 m to within a few 1e-10 m (f64 accumulation of f32 steps)."""
    split, start, end = _run(6.0, 7.0, 1e-4)
    assert split
    assert end[0] - start[0] == pytest.approx(1e-5, abs=1e-9)
    assert np.all(np.abs(end[1:] - start[1:]) < 1e-9)


def test_the_residual_survives_the_periodic_wrap():
    """20 mm from the +x face at 0.5 m/s: it leaves through the face at 0.04 s and re-enters at
    the -x face; the wrapped position holds the travel to the same precision."""
    split, start, end = _run(6.0, 7.0, 0.5)
    expected = start[0] + 0.5 * 0.1 - 1.0
    assert end[0] == pytest.approx(expected, abs=2e-7)


def test_near_the_origin_positions_are_not_split():
    """Within 1 m nothing is split (and costs nothing); 3 cm out, 1e-6 m per step is 540 f32
    spacings: it moves as it should, but for the rounding of each step (up to half a spacing,
    2.4e-4 of the travel here)."""
    split, start, end = _run(-0.05, 0.05, 1e-2)
    assert not split
    assert end[0] - start[0] == pytest.approx(1e-3, rel=1e-3)   # (measured 2.4e-4: rounding)
