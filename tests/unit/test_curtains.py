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
    assert "airborne_mass_flow" not in out
    v[:, 0] = [5.0, 5.0, 5.0, 0.5, -1.0]                                 # along x: the bed fast
    along = curtains.curtain_figures(x, v, r, m, [plate], [pose], length=0.5, period_axis=None,
                                     axis_direction=(1.0, 0.0, 0.0), surface=False)
    assert along["airborne_mass_flow"] == pytest.approx((2 * 0.5 - 3 * 1.0) / 0.5)   # in flight only
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


# --- the surface the gas meets besides the curtains (curtains.exposed_fraction) -------------
# Each case has an exact fraction of the sphere; the Fibonacci lattice of N directions gives a
# cap's area to within ~1 / N (4,000 here: tolerance 0.002).

def test_a_lone_sphere_and_a_touching_pair():
    """A lone sphere is open all round. Of two touching equal spheres each hides the cap of
    the other whose normals pass within a radius of its centre 2 R away: the half-angle 30 deg,
    the cap (1 - cos 30 deg) / 2 = 0.067 of the sphere. Across a periodic face the same."""
    assert curtains.exposed_fraction(np.zeros((1, 3)), np.array([R])).tolist() == [1.0]
    expected = 1.0 - (1.0 - math.cos(math.radians(30.0))) / 2.0
    pair = np.array([[0.0, 0.0, 0.0], [2 * R, 0.0, 0.0]])
    got = curtains.exposed_fraction(pair, np.full(2, R), directions=4000)
    assert got == pytest.approx([expected, expected], abs=0.002)
    across = np.array([[0.5 * R, 0.3, 0.0], [0.1 - 1.5 * R, 0.3, 0.0]])     # L = 0.1
    wrapped = curtains.exposed_fraction(across, np.full(2, R), length=0.1, period_axis=0,
                                        directions=4000)
    assert wrapped == pytest.approx(got[::-1], abs=1e-12)     # the neighbour on the -x side
    apart = curtains.exposed_fraction(across, np.full(2, R), directions=4000)
    assert apart.tolist() == [1.0, 1.0]


def test_a_sphere_on_a_turned_plate():
    """A sphere resting on a plate (at a pose): a ray from its surface point R u leaving along
    u (u's component into the plate -s) stays off the plate over the reach l if
    R - (R + l) s >= 0, so the open fraction is (1 + R / (R + l)) / 2: 0.6 at l = 2
    diameters."""
    plate = trimesh.creation.box(extents=(1.0, 1.0, 0.02))          # top face at z = 0.01
    angle = math.radians(90.0)                                       # turned: face at y = -0.01
    rotation = np.array([[1, 0, 0], [0, math.cos(angle), -math.sin(angle)],
                         [0, math.sin(angle), math.cos(angle)]])
    shift = np.array([0.0, 0.0, 0.2])
    x = np.array([[0.0, -0.01 - R, 0.2]])
    reach = 4.0 * R
    got = curtains.exposed_fraction(x, np.array([R]), [plate], [(rotation, shift)],
                                    directions=4000)
    assert curtains.EXPOSURE_REACH_DIAMETERS * 2.0 * R == pytest.approx(reach)
    assert got[0] == pytest.approx((1.0 + R / (R + reach)) / 2.0, abs=0.002)
    # a plate farther than the reach hides nothing
    far = curtains.exposed_fraction(x + [0.0, -5.0 * R, 0.0], np.array([R]), [plate],
                                    [(rotation, shift)], directions=4000)
    assert far.tolist() == [1.0]


def test_inside_a_block_nothing_is_open():
    """A simple cubic block of touching spheres: two layers in, every ray meets a neighbour
    within the reach (one layer in, a few pass the square gaps of the face's layer, 0.41 R
    wide); on its faces a cap looks out."""
    n = 8
    grid = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1).reshape(-1, 3)
    x = grid * 2.0 * R
    got = curtains.exposed_fraction(x, np.full(len(x), R)).reshape(n, n, n)
    assert got[2:-2, 2:-2, 2:-2].max() == 0.0
    assert got[1:-1, 1:-1, 1:-1].max() < 0.15
    top = got[1:-1, 1:-1, -1]
    assert top.min() > 0.2 and top.max() < 0.5


def test_segments_cross_a_shell():
    """curtains._segments_cross against a faceted cylinder: a radial segment from inside
    crosses the shell where it reaches past the circumscribed radius, and not where it stops
    short of the inscribed one (the facets lie between)."""
    shell = trimesh.creation.cylinder(radius=0.5, height=0.4, sections=72)
    inscribed = 0.5 * math.cos(math.pi / 72)
    rng = np.random.default_rng(5)
    phi = rng.uniform(0, 2 * math.pi, 400)
    rho = rng.uniform(0.3, 0.49, 400)
    z = rng.uniform(-0.1, 0.1, 400)
    direction = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(400)])
    start = direction * rho[:, None] + np.column_stack([np.zeros((400, 2)), z])
    span = 0.08
    crosses = curtains._segments_cross([shell], [(np.eye(3), np.zeros(3))], start, direction,
                                       span)
    assert crosses[rho + span > 0.5].all()
    assert not crosses[rho + span < inscribed].any()
    assert (rho + span > 0.5).sum() > 50 and (rho + span < inscribed).sum() > 50


def test_the_surface_figures():
    """curtain_figures' surface: the bed's particles' open surface per metre and its
    area-weighted speed against the gas; the airborne ones are the curtains' alone."""
    plate = trimesh.creation.box(extents=(1.0, 1.0, 0.02))
    pose = (np.eye(3), np.zeros(3))
    x = np.array([[0.0, 0.0, 0.01 + R], [0.0, 0.0, 0.3]])          # on the plate; in flight
    v = np.array([[1.0, 0, 0], [0, 0, -3.0]])
    out = curtains.curtain_figures(x, v, np.full(2, R), np.ones(2), [plate], [pose], 0.5)
    open_fraction = curtains.exposed_fraction(x[:1], np.array([R]), [plate], [pose])[0]
    assert 0.5 < open_fraction < 0.7
    assert out["surface_area_per_metre"] == pytest.approx(4 * math.pi * R ** 2 * open_fraction / 0.5)
    assert out["surface_slip_speed"] == pytest.approx(1.0)
    assert "surface_area_per_metre" not in curtains.curtain_figures(
        x, v, np.full(2, R), np.ones(2), [plate], [pose], 0.5, surface=False)
