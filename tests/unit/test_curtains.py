"""The curtains' classification (app/curtains.py): a particle is airborne when it touches no
particle (across a periodic face too) and no body at its current pose."""
import math

import numpy as np
import pytest
import trimesh

from taichi_dem.app import curtains

R = 0.01


def test_pairs_touch_within_the_tolerance_and_across_a_periodic_face():
    x = np.array([[0.0, 0.0, 0.0], [2 * R * 1.01, 0.0, 0.0],       # touching (1 % gap)
                  [0.5, 0.0, 0.0],                                  # alone
                  [0.0, 0.3, 0.0], [0.0, 0.3 + 2 * R * 1.05, 0.0],  # 5 % apart: not touching
                  [0.002, 0.6, 0.0], [0.998, 0.6, 0.0]])            # across x's faces (L = 1)
    r = np.full(len(x), R)
    touching = curtains.touching_another(x, r, period_axis=0, period=1.0)
    assert touching.tolist() == [True, True, False, False, False, True, True]
    # without the period the last two are a metre apart
    assert curtains.touching_another(x, r).tolist()[5:] == [False, False]


def test_a_body_is_touched_at_its_pose():
    plate = trimesh.creation.box(extents=(1.0, 1.0, 0.02))          # top face at z = 0.01
    angle = math.radians(90.0)                                       # turned about x: top face at y = -0.01
    rotation = np.array([[1, 0, 0], [0, math.cos(angle), -math.sin(angle)],
                         [0, math.sin(angle), math.cos(angle)]])
    shift = np.array([0.0, 0.0, 0.2])
    x = np.array([[0.0, -0.01 - R, 0.2],            # resting on the turned face
                  [0.0, -0.01 - 3 * R, 0.2],        # a radius clear of it
                  [0.0, 0.3, 0.01 + R]])            # on the face at t = 0, 0.29 m from it now
    r = np.full(3, R)
    hit = curtains.touching_bodies(x, r, [plate], [(rotation, shift)])
    assert hit.tolist() == [True, False, False]


def test_the_curtain_figures():
    plate = trimesh.creation.box(extents=(1.0, 1.0, 0.02))
    pose = (np.eye(3), np.zeros(3))
    x = np.array([[0.0, 0.0, 0.01 + R],             # on the plate
                  [0.3, 0.0, 0.01 + R], [0.3 + 2 * R, 0.0, 0.01 + R],   # a pair on it
                  [0.0, 0.0, 0.3], [0.2, 0.1, 0.4]])                     # two in flight
    v = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, -3.0], [0, 0, -4.0]], float)
    r = np.full(5, R)
    m = np.array([1.0, 1.0, 1.0, 2.0, 3.0])
    out = curtains.curtain_figures(x, v, r, m, [plate], [pose], length=0.5, period_axis=None,
                                   gas_velocity=(0.0, 0.0, 1.0))
    assert out["airborne_fraction"] == pytest.approx(5.0 / 8.0)
    assert out["curtain_area_per_metre"] == pytest.approx(2 * 4 * math.pi * R ** 2 / 0.5)
    assert out["curtain_slip_speed"] == pytest.approx(4.5)           # (4 + 5) / 2 against the gas
    none = curtains.curtain_figures(x[:3], v[:3], r[:3], m[:3], [plate], [pose], 0.5)
    assert none["airborne_fraction"] == 0.0 and math.isnan(none["curtain_slip_speed"])


def test_the_narrowed_search_is_the_naive_one():
    """curtains._within narrows the triangles by their bounding spheres before measuring: on a
    flighted drum's mesh and points scattered through it, it agrees with trimesh's measure of
    every triangle."""
    from taichi_dem.geometry.registry import build
    drum = build("drum", {"radius": 0.5, "length": 0.24, "end_walls": False, "flights": 8,
                          "flight_height": 0.08, "flight_shape": "L", "flight_lip": 0.04})
    mesh = trimesh.Trimesh(drum.vertices, drum.faces, process=False)
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(0.0, 0.24, 3000), rng.uniform(-0.52, 0.52, 3000),
                              rng.uniform(-0.52, 0.52, 3000)])
    reach = rng.uniform(0.005, 0.03, 3000)
    _, distance, _ = trimesh.proximity.closest_point_naive(mesh, points)
    expected = distance <= reach
    assert expected.sum() > 100 and (~expected).sum() > 100
    assert (curtains._within(mesh, points, reach) == expected).all()
