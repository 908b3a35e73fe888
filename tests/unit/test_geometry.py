"""geometry/: TriMesh, the builders (checked against analytic areas and bounds), placement,
normals, import through trimesh, and the errors a user gets for bad input."""
import math

import numpy as np
import pytest

from taichi_dem import geometry
from taichi_dem.geometry import BUILDERS, GeometryError, TriMesh, build, build_mesh, load_mesh
from taichi_dem.geometry.builders import default_segments, helicoid_area


def polygon_perimeter(r, n):
    return 2.0 * n * r * math.sin(math.pi / n)


def radial(points):
    """Distance from the x axis."""
    return np.hypot(points[:, 1], points[:, 2])


def one_sided(mesh):
    keep = ~mesh.two_sided
    return TriMesh(mesh.vertices, mesh.faces[keep])


def two_sided(mesh):
    keep = mesh.two_sided
    return TriMesh(mesh.vertices, mesh.faces[keep], np.ones(int(keep.sum()), bool))


# ----------------------------------------------------------------------------------- TriMesh
def test_trimesh_arrays_are_typed_and_read_only():
    m = TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    assert m.vertices.dtype == np.float64 and m.faces.dtype == np.int64
    assert m.two_sided.tolist() == [False]
    with pytest.raises(ValueError):
        m.vertices[0, 0] = 5.0
    np.testing.assert_allclose(m.face_normals, [[0, 0, 1]])     # counter-clockwise seen from +z
    assert m.area == pytest.approx(0.5)


def test_merged_and_transformed():
    a = build("box", {"min": [0, 0, 0], "max": [1, 1, 1]})
    b = a.transformed(np.eye(3), [2.0, 0.0, 0.0])
    ab = a.merged(b)
    assert ab.n_faces == 24 and ab.connected_components() == 2
    np.testing.assert_allclose(ab.bounds, [[0, 0, 0], [3, 1, 1]])
    # a reflection keeps normals on the particle side by reversing the winding
    mirror = np.diag([-1.0, 1.0, 1.0])
    r = a.transformed(mirror)
    assert r.signed_volume == pytest.approx(a.signed_volume)
    assert r.is_closed


# ----------------------------------------------------------------------------------- validation
def test_degenerate_triangle_is_an_error():
    m = TriMesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], [[0, 1, 3], [0, 1, 2]])
    with pytest.raises(GeometryError, match="degenerate") as e:
        m.validate("bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh"
    repeated = TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2], [0, 0, 2]])
    with pytest.raises(GeometryError, match="degenerate"):
        repeated.validate()


def test_nan_vertex_bad_index_and_empty_are_errors():
    with pytest.raises(GeometryError, match="not finite"):
        TriMesh([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], [[0, 1, 2]]).validate()
    with pytest.raises(GeometryError, match="outside"):
        TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]]).validate()
    with pytest.raises(GeometryError, match="no triangles"):
        TriMesh.empty().validate()
    assert issubclass(GeometryError, ValueError)


def test_absurd_size_is_flagged_as_wrong_units():
    with pytest.raises(GeometryError, match="wrong units"):
        build("drum", {"radius": 433.0, "length": 6000.0}, key="bodies[0].mesh")
    with pytest.raises(GeometryError, match="wrong units"):
        TriMesh([[0, 0, 0], [1e-7, 0, 0], [0, 1e-7, 0]], [[0, 1, 2]]).validate()


# ----------------------------------------------------------------------------------- box
@pytest.mark.parametrize("normals, sign", [("inward", -1.0), ("outward", 1.0)])
def test_box(normals, sign):
    m = build("box", {"min": [0, -1, 2], "max": [1, 1, 5], "normals": normals})
    np.testing.assert_allclose(m.bounds, [[0, -1, 2], [1, 1, 5]])
    assert m.is_closed and m.n_faces == 12
    assert m.area == pytest.approx(2 * (1 * 2 + 2 * 3 + 3 * 1))
    assert m.signed_volume == pytest.approx(sign * 6.0)
    centre = np.array([0.5, 0.0, 3.5])
    towards_centre = np.einsum("ij,ij->i", m.face_normals, centre - m.face_centroids)
    assert np.all(-sign * towards_centre > 0)


def test_open_top_box():
    m = build("box", {"min": [0, 0, 0], "max": [1, 1, 1], "open_top": True})
    assert m.n_faces == 10 and not m.is_closed and m.open_edge_count() == 4
    assert m.face_normals[:, 2].max() <= 1e-12 + 1.0 and m.face_centroids[:, 2].max() < 1.0


# ----------------------------------------------------------------------------------- drum
def test_default_segments_meet_the_chord_error():
    n = default_segments()
    assert 1.0 - math.cos(math.pi / n) < 0.01
    assert 1.0 - math.cos(math.pi / (n - 4)) >= 0.01        # and no finer than needed
    assert default_segments(5) % 5 == 0


def test_drum_shell_area_bounds_and_inward_normals():
    R, L = 0.433, 6.0
    m = build("drum", {"radius": R, "length": L, "end_walls": False})
    n = default_segments()
    np.testing.assert_allclose(m.bounds, [[0, -R, -R], [L, R, R]], atol=1e-12)
    assert m.area == pytest.approx(polygon_perimeter(R, n) * L, rel=1e-12)
    assert m.area == pytest.approx(2 * math.pi * R * L, rel=(math.pi / n) ** 2 / 6 * 1.01)
    c = m.face_centroids
    outward = np.stack([np.zeros(len(c)), c[:, 1], c[:, 2]], axis=1)
    assert np.all(np.einsum("ij,ij->i", m.face_normals, outward) < 0)    # towards the axis
    assert np.allclose(m.face_normals[:, 0], 0.0, atol=1e-12)
    assert not m.is_closed and m.open_edge_count() == 2 * n
    assert not m.two_sided.any()


def test_drum_with_end_walls_is_a_closed_container():
    R, L = 1.0, 2.0
    m = build("drum", {"radius": R, "length": L})
    n = default_segments()
    assert m.is_closed
    polygon_area = 0.5 * n * R * R * math.sin(2 * math.pi / n)
    assert m.signed_volume == pytest.approx(-polygon_area * L, rel=1e-9)   # normals inward
    assert m.area == pytest.approx(polygon_perimeter(R, n) * L + 2 * polygon_area, rel=1e-9)
    c, nrm = m.face_centroids, m.face_normals
    start, end = np.isclose(c[:, 0], 0.0), np.isclose(c[:, 0], L)
    np.testing.assert_allclose(nrm[start], np.tile([1, 0, 0], (start.sum(), 1)), atol=1e-12)
    np.testing.assert_allclose(nrm[end], np.tile([-1, 0, 0], (end.sum(), 1)), atol=1e-12)


def test_drum_end_wall_hole():
    m = build("drum", {"radius": 1.0, "length": 2.0, "end_hole_radius": 0.3})
    n = default_segments()
    assert m.open_edge_count() == 2 * n
    assert radial(m.vertices).min() == pytest.approx(0.3)


@pytest.mark.parametrize("flights", [1, 6, 12])
def test_drum_straight_flights(flights):
    R, L, h = 1.2, 3.0, 0.18
    m = build("drum", {"radius": R, "length": L, "flights": flights, "flight_height": h})
    plates = two_sided(m)
    assert plates.connected_components() == flights
    assert plates.area == pytest.approx(flights * h * L, rel=1e-12)
    assert radial(plates.vertices[np.unique(plates.faces)]).min() == pytest.approx(R - h)
    # each flight is radial; its stored normal is tangential (the leading face)
    c = plates.face_centroids
    e_t = np.stack([np.zeros(len(c)), -c[:, 2], c[:, 1]], axis=1) / radial(c)[:, None]
    assert np.allclose(np.einsum("ij,ij->i", plates.face_normals, e_t), 1.0)
    assert one_sided(m).is_closed                                     # the shell stays closed
    assert default_segments(flights) % flights == 0


def test_drum_l_flights_and_thick_flights():
    R, L, h, lip = 1.0, 2.0, 0.15, 0.08
    p = {"radius": R, "length": L, "flights": 8, "flight_height": h, "flight_shape": "L",
         "flight_lip": lip, "include_shell": False, "end_walls": False}
    m = build("drum", p)
    assert m.connected_components() == 8 and m.two_sided.all()
    assert m.area == pytest.approx(8 * (h + lip) * L, rel=1e-12)
    r_tip = math.hypot(R - h, lip)
    assert radial(m.vertices).max() == pytest.approx(R)
    assert np.isclose(radial(m.vertices), r_tip).any()
    thick = build("drum", {**p, "flight_thickness": 0.01})
    assert thick.is_closed and thick.signed_volume > 0 and thick.connected_components() == 8
    # plate area x thickness, less the mitre overlap at the corner
    assert thick.signed_volume == pytest.approx(8 * (h + lip) * L * 0.01, rel=0.05)


def test_drum_flight_section():
    m = build("drum", {"radius": 1.0, "length": 3.0, "flights": 4, "flight_height": 0.1,
                       "flight_start": 1.0, "flight_end": 2.0, "include_shell": False,
                       "end_walls": False})
    np.testing.assert_allclose(m.bounds[:, 0], [1.0, 2.0])


def test_drum_incline():
    a = math.radians(5.0)
    R, L = 0.5, 4.0
    m = build("drum", {"radius": R, "length": L, "incline_deg": 5.0})
    axis = np.array([math.cos(a), 0.0, -math.sin(a)])
    along = m.vertices @ axis
    off_axis = np.linalg.norm(m.vertices - along[:, None] * axis, axis=1)
    assert along.min() == pytest.approx(0.0, abs=1e-12) and along.max() == pytest.approx(L)
    assert off_axis.max() == pytest.approx(R)
    assert m.bounds[1, 2] < R                 # the discharge end (x = L) is lower


def test_drum_errors():
    with pytest.raises(GeometryError) as e:
        build("drum", {"radius": 1.0, "length": 2.0, "flights": 6, "flight_height": 1.0},
              key="bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh.flight_height" and "radius" in e.value.reason
    with pytest.raises(GeometryError, match="flight_height"):
        build("drum", {"radius": 1.0, "length": 2.0, "flights": 6})
    with pytest.raises(GeometryError, match="through the shell") as e:
        build("drum", {"radius": 1.0, "length": 2.0, "flights": 6, "flight_height": 0.1,
                       "flight_shape": "L", "flight_lip": 0.6})
    assert e.value.key.endswith("flight_lip")


# ----------------------------------------------------------------------------------- paddles
def test_paddle_shaft_counts_area_and_placement():
    rows, ppr, pl, w, L = 24, 4, 0.3, 0.12, 6.0
    p = {"length": L, "shaft_radius": 0.08, "rows": rows, "paddles_per_row": ppr,
         "paddle_length": pl, "paddle_width": w, "paddle_pitch_deg": 30, "stagger_deg": 45}
    m = build("paddle_shaft", {**p, "include_shaft": False})
    assert m.connected_components() == rows * ppr
    assert m.two_sided.all()
    assert m.area == pytest.approx(rows * ppr * pl * w, rel=1e-12)
    # rows centred along the shaft, row_spacing = length / rows
    assert m.bounds[0, 0] > 0 and m.bounds[1, 0] < L
    half = 0.5 * w * math.cos(math.radians(30))
    assert m.bounds[0, 0] == pytest.approx(L / rows / 2 - half)
    assert m.bounds[1, 0] == pytest.approx(L - L / rows / 2 + half)
    tri_x = np.unique(np.round(m.face_centroids[:, 0], 9))    # the two triangles of a plate
    row_x = 0.5 * (tri_x[0::2] + tri_x[1::2])                   # sit symmetrically about it
    assert len(row_x) == rows and row_x[0] == pytest.approx(L / rows / 2)
    np.testing.assert_allclose(np.diff(row_x), L / rows)
    # a positive pitch: the leading face has a +x component (conveys towards +x)
    np.testing.assert_allclose(m.face_normals[:, 0], math.sin(math.radians(30)), atol=1e-12)
    tip = math.hypot(0.08 + pl, 0.5 * w * math.sin(math.radians(30)))
    assert radial(m.vertices).max() == pytest.approx(tip)

    full = build("paddle_shaft", p)
    assert full.connected_components() == rows * ppr + 1
    shaft = one_sided(full)
    assert shaft.is_closed and shaft.signed_volume > 0          # normals out of the shaft
    n = default_segments(4)
    assert shaft.signed_volume == pytest.approx(0.5 * n * 0.08 ** 2 * math.sin(2 * math.pi / n)
                                                * L, rel=1e-9)


def test_contract_example_paddle_shaft_builds():
    m = build("paddle_shaft", {"length": 6.0, "shaft_radius": 0.08, "paddles_per_row": 4,
                               "rows": 24, "paddle_pitch_deg": 30})
    assert two_sided(m).connected_components() == 96


def test_thick_paddles_are_closed_boxes():
    m = build("paddle_shaft", {"length": 1.0, "shaft_radius": 0.05, "rows": 3,
                               "paddles_per_row": 2, "paddle_length": 0.1,
                               "paddle_width": 0.08, "paddle_thickness": 0.01,
                               "include_shaft": False})
    assert m.is_closed and m.connected_components() == 6 and not m.two_sided.any()
    assert m.signed_volume == pytest.approx(6 * 0.1 * 0.08 * 0.01, rel=1e-9)


def test_paddle_errors():
    base = {"length": 6.0, "shaft_radius": 0.08, "rows": 24, "paddles_per_row": 4}
    with pytest.raises(GeometryError) as e:
        build("paddle_shaft", {**base, "paddle_length": 0.4, "shell_radius": 0.433},
              key="bodies[1].mesh")
    assert e.value.key == "bodies[1].mesh.paddle_length" and "shell" in e.value.reason
    ok = build("paddle_shaft", {**base, "shell_radius": 0.433})      # default length fits
    assert radial(ok.vertices).max() < 0.433
    with pytest.raises(GeometryError, match="beyond the shaft length"):
        build("paddle_shaft", {**base, "start": 1.0, "row_spacing": 0.3})


# ----------------------------------------------------------------------------------- screw
def test_screw_flight_area_matches_the_helicoid():
    p = {"length": 1.2, "shaft_radius": 0.08, "outer_radius": 0.38, "pitch": 0.3,
         "include_shaft": False}
    exact = helicoid_area(0.08, 0.38, 0.3, turns=4)
    coarse = build("screw", p)
    assert coarse.area == pytest.approx(exact, rel=0.015)
    fine = build("screw", {**p, "segments_per_turn": 192, "radial_segments": 12})
    assert fine.area == pytest.approx(exact, rel=1e-3)
    assert coarse.two_sided.all() and coarse.connected_components() == 1
    np.testing.assert_allclose(coarse.bounds, [[0, -0.38, -0.38], [1.2, 0.38, 0.38]], atol=1e-12)
    two = build("screw", {**p, "starts": 2})
    assert two.connected_components() == 2 and two.area == pytest.approx(2 * coarse.area)


@pytest.mark.parametrize("hand, sign", [("right", 1.0), ("left", -1.0)])
def test_screw_handedness(hand, sign):
    m = build("screw", {"turns": 1, "shaft_radius": 0.05, "outer_radius": 0.2, "pitch": 0.4,
                        "turns_direction": hand, "include_shaft": False,
                        "segments_per_turn": 24})
    v = m.vertices
    outer = np.isclose(radial(v), 0.2)
    quarter = outer & np.isclose(v[:, 0], 0.1)         # a quarter turn along
    assert quarter.sum() == 1
    np.testing.assert_allclose(v[quarter][0], [0.1, 0.0, sign * 0.2], atol=1e-12)
    # the stored normal is the face that pushes under positive rotation: -x for right-hand
    assert np.all(np.sign(m.face_normals[:, 0]) == -sign)
    alias = build("screw", {"turns": 1, "shaft_radius": 0.05, "outer_radius": 0.2,
                            "pitch": 0.4, "handedness": hand, "include_shaft": False})
    np.testing.assert_allclose(alias.vertices, m.vertices)


def test_screw_with_shaft_and_thickness():
    m = build("screw", {"length": 0.6, "shaft_radius": 0.05, "outer_radius": 0.2, "pitch": 0.2,
                        "start": 0.1})
    assert m.connected_components() == 2
    assert one_sided(m).is_closed
    np.testing.assert_allclose(m.bounds[:, 0], [0.0, 0.7])
    thick = build("screw", {"length": 0.6, "shaft_radius": 0.05, "outer_radius": 0.2,
                            "pitch": 0.2, "flight_thickness": 0.01, "include_shaft": False,
                            "segments_per_turn": 96, "radial_segments": 6})
    assert thick.is_closed
    # an axial offset of a helicoid sweeps the annulus area per turn x thickness
    assert thick.signed_volume == pytest.approx(3 * math.pi * (0.2 ** 2 - 0.05 ** 2) * 0.01,
                                                rel=0.01)


def test_screw_errors():
    base = {"length": 1.0, "shaft_radius": 0.1, "pitch": 0.3}
    with pytest.raises(GeometryError) as e:
        build("screw", {**base, "outer_radius": 0.1}, key="bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh.outer_radius"
    with pytest.raises(GeometryError, match="give one of them"):
        build("screw", {**base, "outer_radius": 0.3, "turns": 2})
    with pytest.raises(GeometryError, match="length"):
        build("screw", {"shaft_radius": 0.1, "outer_radius": 0.3, "pitch": 0.3})


def test_screw_and_paddles_share_one_shaft():
    """The seed study's optimised cooler: screw flights at the inlet, paddles after."""
    spec = [
        {"builder": "paddle_shaft", "length": 6.0, "shaft_radius": 0.08, "start": 1.35,
         "rows": 19, "paddles_per_row": 4, "paddle_length": 0.3, "paddle_width": 0.15,
         "paddle_pitch_deg": 30, "shell_radius": 0.433},
        {"builder": "screw", "length": 1.2, "shaft_radius": 0.08, "outer_radius": 0.38,
         "pitch": 0.3, "turns_direction": "left", "include_shaft": False,
         "shell_radius": 0.433},
    ]
    m = build_mesh(spec, key="bodies[0].mesh")
    assert m.connected_components() == 1 + 19 * 4 + 1
    assert one_sided(m).is_closed                        # one shaft, closed
    np.testing.assert_allclose(m.bounds[:, 0], [0.0, 6.0])
    flight = build_mesh(spec[1])
    paddles = two_sided(build_mesh(spec[0]))
    assert paddles.bounds[0, 0] > flight.bounds[1, 0]   # paddles start after the screw
    with pytest.raises(GeometryError) as e:
        build_mesh([spec[0], {**spec[1], "pich": 0.3}], key="bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh[1].pich" and "'pitch'" in e.value.reason


# ----------------------------------------------------------------------------------- hopper
def test_conical_hopper():
    rt, ro, h = 0.5, 0.05, 0.8
    m = build("hopper", {"top_radius": rt, "orifice_radius": ro, "height": h})
    n = default_segments()
    np.testing.assert_allclose(m.bounds, [[0, -rt, -rt], [h, rt, rt]], atol=1e-12)
    slant = math.hypot(h, rt - ro)
    # planar trapezoids: their height runs between the chord midpoints, at r cos(pi/n)
    panel_height = math.hypot(h, (rt - ro) * math.cos(math.pi / n))
    polygon = 0.5 * (polygon_perimeter(rt, n) + polygon_perimeter(ro, n)) * panel_height
    assert m.area == pytest.approx(polygon, rel=1e-9)
    assert m.area == pytest.approx(math.pi * (rt + ro) * slant, rel=0.005)
    assert m.open_edge_count() == 2 * n
    c = m.face_centroids
    assert np.all(np.einsum("ij,ij->i", m.face_normals[:, 1:], c[:, 1:]) < 0)   # inward


def test_wedge_hopper_upright():
    top, ori, depth, h = 1.0, 0.1, 0.3, 0.8
    m = build("hopper", {"kind": "wedge", "top_width": top, "orifice_width": ori,
                         "depth": depth, "height": h, "axis_direction": [0, 0, 1],
                         "origin": [0, 0, 1.0]})
    np.testing.assert_allclose(m.bounds, [[-depth / 2, -top / 2, 1.0],
                                          [depth / 2, top / 2, 1.0 + h]], atol=1e-12)
    slant = math.hypot(h, (top - ori) / 2)
    assert m.area == pytest.approx(2 * slant * depth + 2 * 0.5 * (top + ori) * h, rel=1e-12)
    low = m.vertices[np.isclose(m.vertices[:, 2], 1.0)]
    assert np.abs(low[:, 1]).max() == pytest.approx(ori / 2)          # the orifice is at the bottom
    c = m.face_centroids
    centre = np.stack([np.zeros(len(c)), np.zeros(len(c)), c[:, 2]], axis=1)
    assert np.all(np.einsum("ij,ij->i", m.face_normals, centre - c) > 0)   # inward


def test_hopper_errors():
    with pytest.raises(GeometryError, match="orifice must be smaller"):
        build("hopper", {"top_radius": 0.1, "orifice_radius": 0.2, "height": 1.0})
    with pytest.raises(GeometryError) as e:
        build("hopper", {"kind": "wedge", "top_width": 1.0, "orifice_width": 0.1,
                         "height": 1.0}, key="h")
    assert e.value.key == "h.depth"


# ----------------------------------------------------------------------------------- chute
def test_chute():
    L, w, hw, a = 2.0, 0.4, 0.1, 30.0
    m = build("chute", {"length": L, "width": w, "wall_height": hw, "incline_deg": a})
    assert m.area == pytest.approx(L * w + 2 * L * hw, rel=1e-12)
    floor = np.isclose(m.face_normals @ [0, 1, 0], 0.0)
    s, c = math.sin(math.radians(a)), math.cos(math.radians(a))
    np.testing.assert_allclose(m.face_normals[floor], np.tile([s, 0, c], (floor.sum(), 1)),
                               atol=1e-12)
    assert m.bounds[0, 2] == pytest.approx(-L * s)            # descends along +x
    walls = m.face_normals[~floor]
    assert np.all(np.sign(walls[:, 1]) == -np.sign(m.face_centroids[~floor][:, 1]))
    bare = build("chute", {"length": L, "width": w, "side_walls": False})
    assert bare.area == pytest.approx(L * w)


# ----------------------------------------------------------------------------------- placement
def test_origin_and_axis_direction():
    R, L = 0.5, 2.0
    m = build("drum", {"radius": R, "length": L, "origin": [1.0, 2.0, 3.0],
                       "axis_direction": [0, 2, 0]})
    np.testing.assert_allclose(m.bounds, [[1 - R, 2, 3 - R], [1 + R, 2 + L, 3 + R]],
                               atol=1e-12)
    up = build("drum", {"radius": R, "length": L, "axis_direction": [0, 0, 1]})
    np.testing.assert_allclose(up.bounds, [[-R, -R, 0], [R, R, L]], atol=1e-12)
    assert up.is_closed and up.signed_volume < 0
    back = build("chute", {"length": 1.0, "width": 0.2, "axis_direction": [-1, 0, 0]})
    floor = np.isclose(back.face_normals[:, 2], 1.0)
    assert floor.any()                                     # no roll: the floor stays up
    np.testing.assert_allclose(back.bounds[:, 0], [-1.0, 0.0], atol=1e-12)


def test_roll_deg_turns_about_the_axis():
    p = {"radius": 1.0, "length": 1.0, "flights": 1, "flight_height": 0.2,
         "include_shell": False, "end_walls": False}
    m = build("drum", {**p, "roll_deg": 90})
    assert np.allclose(m.vertices[:, 1], 0.0, atol=1e-12) and m.vertices[:, 2].min() > 0


def test_roll_comes_before_the_incline():
    a = math.radians(5.0)
    m = build("drum", {"radius": 1.0, "length": 2.0, "flights": 1, "flight_height": 0.2,
                       "include_shell": False, "end_walls": False, "roll_deg": 90,
                       "incline_deg": 5.0})
    assert np.allclose(m.vertices[:, 1], 0.0, atol=1e-12)      # the flight stays at the top
    along = m.vertices @ [math.cos(a), 0.0, -math.sin(a)]
    assert along.max() == pytest.approx(2.0)


def test_body_axis_matches_the_placed_mesh():
    spec = {"builder": "drum", "radius": 0.5, "length": 4.0, "end_walls": True,
            "incline_deg": 3.0, "origin": [1, 2, 3], "axis_direction": [0, 1, 0]}
    point, direction = geometry.body_axis(spec)
    m = build_mesh(spec)
    along = (m.vertices - point) @ direction
    off = np.linalg.norm(m.vertices - point - along[:, None] * direction, axis=1)
    assert along.min() == pytest.approx(0.0, abs=1e-12) and along.max() == pytest.approx(4.0)
    assert off.max() == pytest.approx(0.5)
    np.testing.assert_allclose(direction, [0, math.cos(math.radians(3)),
                                           -math.sin(math.radians(3))], atol=1e-12)


def test_max_edge_subdivides_without_cracks():
    m = build("box", {"min": [0, 0, 0], "max": [1, 2, 3], "max_edge": 0.25})
    edges = m.vertices[m.faces] - m.vertices[np.roll(m.faces, 1, axis=1)]
    assert np.linalg.norm(edges, axis=2).max() <= 0.25 + 1e-12
    assert m.is_closed and m.area == pytest.approx(22.0)
    d = build("drum", {"radius": 1, "length": 1, "flights": 3, "flight_height": 0.2,
                       "max_edge": 0.1})
    assert two_sided(d).area == pytest.approx(3 * 0.2 * 1.0)


def test_quantity_strings():
    a = build("drum", {"radius": "433 mm", "length": "6 m", "incline_deg": "0.05 rad"})
    b = build("drum", {"radius": 0.433, "length": 6.0, "incline_deg": math.degrees(0.05)})
    np.testing.assert_allclose(a.vertices, b.vertices)
    with pytest.raises(GeometryError, match="unit"):
        build("drum", {"radius": "433 kg", "length": 6.0})


# ----------------------------------------------------------------------------------- import
def _write_box(path, size_mm, file_type):
    import trimesh
    box = trimesh.creation.box(extents=size_mm)
    box.apply_translation(np.asarray(size_mm) / 2)
    box.export(str(path), file_type=file_type)
    return box


@pytest.mark.parametrize("suffix", ["stl", "obj"])
def test_import_round_trip_in_mm(tmp_path, suffix):
    size = [100.0, 200.0, 300.0]
    _write_box(tmp_path / f"part.{suffix}", size, suffix)
    m = load_mesh(f"part.{suffix}", units="mm", base_dir=tmp_path)
    np.testing.assert_allclose(m.bounds, [[0, 0, 0], [0.1, 0.2, 0.3]], atol=1e-9)
    assert m.area == pytest.approx(2 * (0.02 + 0.06 + 0.03))
    assert m.is_closed and m.signed_volume == pytest.approx(0.006) and not m.two_sided.any()
    via_scene = build_mesh({"file": f"part.{suffix}", "units": "mm", "origin": [1, 0, 0]},
                           key="bodies[0].mesh", base_dir=tmp_path)
    np.testing.assert_allclose(via_scene.bounds[0], [1, 0, 0], atol=1e-9)
    # units and scale multiply
    twice = load_mesh(tmp_path / f"part.{suffix}", units="cm", scale=0.2)
    np.testing.assert_allclose(twice.bounds[1], [0.2, 0.4, 0.6], atol=1e-9)


def test_import_wrong_units_and_missing_file(tmp_path):
    _write_box(tmp_path / "drum.stl", [6000.0, 866.0, 866.0], "stl")
    with pytest.raises(GeometryError) as e:
        build_mesh({"file": "drum.stl"}, key="bodies[2].mesh", base_dir=tmp_path)
    assert e.value.key == "bodies[2].mesh.units"
    assert "wrong units" in e.value.reason and 'units = "mm"' in e.value.reason
    with pytest.raises(GeometryError) as e:
        build_mesh({"file": "nope.stl"}, key="bodies[2].mesh", base_dir=tmp_path)
    assert e.value.key == "bodies[2].mesh.file" and "no such file" in e.value.reason
    with pytest.raises(GeometryError, match="expected one of"):
        load_mesh(tmp_path / "drum.stl", units="furlong")


def test_import_degenerate_triangle_and_repair(tmp_path):
    import trimesh
    box = trimesh.creation.box(extents=[1, 1, 1])
    v = np.vstack([box.vertices, [[0, 0, 2], [0, 0, 3], [0, 0, 4]]])    # collinear sliver
    f = np.vstack([box.faces, [[8, 9, 10]]])
    trimesh.Trimesh(v, f, process=False).export(str(tmp_path / "bad.stl"))
    with pytest.raises(GeometryError, match="degenerate"):
        load_mesh(tmp_path / "bad.stl")
    fixed = load_mesh(tmp_path / "bad.stl", repair=True)
    assert fixed.n_faces == 12 and fixed.is_closed


def test_open_imported_surface_is_two_sided(tmp_path):
    shell = build("drum", {"radius": 0.4, "length": 1.0, "end_walls": False})
    shell.to_trimesh().export(str(tmp_path / "shell.stl"))
    m = load_mesh(tmp_path / "shell.stl")
    assert m.two_sided.all() and m.area == pytest.approx(shell.area)


# ----------------------------------------------------------------------------------- registry
def test_unknown_builder_and_parameter_suggest_the_closest():
    with pytest.raises(GeometryError) as e:
        build_mesh({"builder": "dum", "radius": 1.0}, key="bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh.builder" and "'drum'" in e.value.reason
    with pytest.raises(GeometryError) as e:
        build("drum", {"radius": 1.0, "length": 2.0, "flight_hieght": 0.1},
              key="bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh.flight_hieght"
    assert "did you mean 'flight_height'" in e.value.reason


def test_missing_required_and_bad_values():
    with pytest.raises(GeometryError) as e:
        build("drum", {"length": 2.0}, key="bodies[0].mesh")
    assert e.value.key == "bodies[0].mesh.radius" and "missing" in e.value.reason
    with pytest.raises(GeometryError, match="positive"):
        build("drum", {"radius": 0.0, "length": 2.0})
    with pytest.raises(GeometryError, match="whole number"):
        build("drum", {"radius": 1.0, "length": 2.0, "flights": 2.5, "flight_height": 0.1})
    with pytest.raises(GeometryError, match="true or false"):
        build("drum", {"radius": 1.0, "length": 2.0, "end_walls": "yes"})
    with pytest.raises(GeometryError, match="did you mean 'L'"):
        build("drum", {"radius": 1.0, "length": 2.0, "flights": 2, "flight_height": 0.1,
                       "flight_shape": "l"})
    with pytest.raises(GeometryError, match="give builder"):
        build_mesh({"radius": 1.0}, key="bodies[0].mesh")


def test_describe_builders_lists_every_builder_and_parameter():
    text = geometry.describe_builders()
    for name, b in BUILDERS.items():
        assert f"  {name}:" in text
        for p in b.params:
            assert p.name in text
    for name in ("box", "drum", "paddle_shaft", "screw", "hopper", "chute", "file"):
        assert name in BUILDERS
    assert "origin" in text and "axis_direction" in text


def test_builders_callable_from_python():
    m = BUILDERS["box"](min=[0, 0, 0], max=[1, 1, 1])
    assert m.is_closed
    with pytest.raises(GeometryError) as e:
        BUILDERS["drum"](radius=1.0)
    assert e.value.key == "drum.length"
