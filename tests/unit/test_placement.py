import dataclasses
import math
import time

import numpy as np
import pytest

from taichi_dem.scene.loader import parse_scene
from taichi_dem.setup.placement import PlacedParticles, place_fills, sample_radii
from taichi_dem.errors import SceneError
from taichi_dem.scene.model import Body, RadiusDistribution

HEADER = """
[simulation]
seed = 1
[domain]
min = {dmin}
max = {dmax}
periodic = {periodic}
[materials.ash]
density = 870.0
youngs_modulus = 1.1e7
poisson_ratio = 0.25
[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3
[[interactions]]
pair = ["ash", "ash"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["ash", "steel"]
restitution = 0.5
friction = 0.5
[[interactions]]
pair = ["steel", "steel"]
restitution = 0.5
friction = 0.5
"""


def scene(body, dmin=(0, 0, 0), dmax=(1, 1, 1), periodic=(), base_dir=None):
    text = HEADER.format(dmin=list(dmin), dmax=list(dmax),
                         periodic="[" + ", ".join(f'"{a}"' for a in periodic) + "]") + body
    return parse_scene(text, source="place.toml", base_dir=base_dir)


def fill(material="ash", radius="0.01", count=100, region=None, extra=""):
    region = region or 'box = { min = [0, 0, 0], max = [1, 1, 1] }'
    return f"""
[[particles]]
material = "{material}"
radius = {radius}
count = {count}
region = {{ {region} }}
{extra}
"""


def min_image(d, scene_):
    d = np.array(d, float)
    lo, hi = np.array(scene_.domain.min), np.array(scene_.domain.max)
    for a, ax in enumerate("xyz"):
        if ax in scene_.domain.periodic:
            L = hi[a] - lo[a]
            d[..., a] -= L * np.round(d[..., a] / L)
    return d


def assert_no_overlap(p: PlacedParticles, scene_):
    """Brute force over all pairs (chunked)."""
    x, r = p.position, p.radius
    n = len(r)
    for s in range(0, n, 500):
        d = min_image(x[s:s + 500, None, :] - x[None, :, :], scene_)
        dist = np.sqrt((d * d).sum(-1))
        reach = r[s:s + 500, None] + r[None, :]
        idx = np.arange(s, min(s + 500, n))
        dist[np.arange(len(idx)), idx] = np.inf
        gap = dist - reach
        assert gap.min() >= -1e-12, f"overlap {gap.min():g}"


def assert_inside_box(p, lo, hi, tol=1e-12):
    assert np.all(p.position - p.radius[:, None] >= np.asarray(lo) - tol)
    assert np.all(p.position + p.radius[:, None] <= np.asarray(hi) + tol)


def test_box_fill_count_inside_no_overlap():
    s = scene(fill(count=3000, radius="0.008",
                   region='box = { min = [0.1, 0.2, 0.0], max = [0.9, 0.8, 0.5] }'))
    p = place_fills(s, np.random.default_rng(1))
    assert p.n == len(p) == 3000
    assert p.position.shape == (3000, 3) and p.position.dtype == np.float64
    assert p.radius.shape == (3000,) and np.all(p.radius == 0.008)
    assert_inside_box(p, (0.1, 0.2, 0.0), (0.9, 0.8, 0.5))
    assert_no_overlap(p, s)


def test_dense_box_fill_near_capacity():
    # 0.2 m cube, r = 1 cm: the FCC lattice holds a few hundred; ask for most of them
    s = scene(fill(count=500, radius="0.01",
                   region='box = { min = [0, 0, 0], max = [0.2, 0.2, 0.2] }'))
    p = place_fills(s, np.random.default_rng(3))
    assert p.n == 500
    assert_inside_box(p, (0, 0, 0), (0.2, 0.2, 0.2))
    assert_no_overlap(p, s)


def test_overfull_region_is_a_scene_error():
    # solid fraction 0.79: within the region's volume (the loader's bound) but beyond the
    # densest packing (0.74), so the placement refuses it
    s = scene(fill(count=1500, radius="0.01",
                   region='box = { min = [0, 0, 0], max = [0.2, 0.2, 0.2] }'))
    with pytest.raises(SceneError) as e:
        place_fills(s, np.random.default_rng(1))
    assert e.value.key == "particles[0].count" and e.value.file == "place.toml"
    assert "holds at most" in e.value.reason and "radius 0.01" in e.value.reason
    assert "enlarge the region or reduce count" in e.value.reason


def test_region_too_small_for_one_sphere():
    # refused on load, before any placement (and a count beyond the region's volume too)
    with pytest.raises(SceneError) as e:
        scene(fill(count=1, radius="0.1", region='box = { min = [0, 0, 0], max = [0.15, 1, 1] }'))
    assert e.value.key == "particles[0].radius" and "does not fit" in e.value.reason
    with pytest.raises(SceneError) as e:
        scene(fill(count=10 ** 15, radius="0.01"))
    assert e.value.key == "particles[0].count" and "whole volume" in e.value.reason


def test_cylinder_fill_inside():
    region = ('cylinder = { axis_point = [0.2, 0.3, 0.5], axis_direction = [1, 1, 0], '
              'radius = 0.15, length = 0.6 }')
    s = scene(fill(count=2000, radius="0.008", region=region))
    p = place_fills(s, np.random.default_rng(2))
    assert p.n == 2000
    a = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    rel = p.position - np.array([0.2, 0.3, 0.5])
    u = rel @ a
    radial = np.linalg.norm(rel - u[:, None] * a, axis=1)
    assert np.all(u - p.radius >= -1e-12) and np.all(u + p.radius <= 0.6 + 1e-12)
    assert np.all(radial + p.radius <= 0.15 + 1e-12)
    assert_inside_box(p, (0, 0, 0), (1, 1, 1))
    assert_no_overlap(p, s)


def test_clear_of_walls():
    walls = """
[[walls]]
name = "floor"
plane = { point = [0, 0, 0.3], normal = [0, 0, 1] }
material = "steel"
[[walls]]
name = "slope"
plane = { point = [0.5, 0.5, 0.5], normal = [-1, 0, 1] }
material = "steel"
"""
    s = scene(fill(count=1000, radius="0.01") + walls)
    p = place_fills(s, np.random.default_rng(5))
    assert p.n == 1000
    for w in s.walls:
        signed = (p.position - np.array(w.point)) @ np.array(w.normal)
        assert np.all(signed >= p.radius - 1e-12)
    assert_no_overlap(p, s)


def test_walls_leave_no_room():
    walls = """
[[walls]]
name = "lid"
plane = { point = [0, 0, 0.5], normal = [0, 0, -1] }
material = "steel"
[[walls]]
name = "floor"
plane = { point = [0, 0, 0.45], normal = [0, 0, 1] }
material = "steel"
"""
    s = scene(fill(count=1, radius="0.05") + walls)
    with pytest.raises(SceneError) as e:
        place_fills(s, np.random.default_rng(5))
    assert e.value.key == "particles[0].count"


@pytest.mark.parametrize("periodic", [("x",), ("x", "y"), ("x", "y", "z")])
def test_clear_of_periodic_images(periodic):
    # the region spans the whole domain: spheres near opposite faces must not meet through them
    s = scene(fill(count=1500, radius="0.02",
                   region='box = { min = [0, 0, 0], max = [0.5, 0.5, 0.5] }'),
              dmin=(0, 0, 0), dmax=(0.5, 0.5, 0.5), periodic=periodic)
    p = place_fills(s, np.random.default_rng(7))
    assert p.n == 1500
    assert_no_overlap(p, s)
    assert_inside_box(p, (0, 0, 0), (0.5, 0.5, 0.5))


def test_periodic_images_matter():
    """Without the periodic check this dense fill would put spheres within reach of images."""
    # a row of spheres of radius 0.1 on a lattice of spacing 0.21 along x in a domain 0.835
    # long: 4 fit between the faces (0.1 + 3 x 0.21 + 0.1 <= 0.835) but not around the
    # periodic loop (4 x 0.21 > 0.835)
    region = 'box = { min = [0, 0, 0], max = [0.835, 0.25, 0.25] }'
    s = scene(fill(count=4, radius="0.1", region=region), dmin=(0, 0, 0),
              dmax=(0.835, 0.25, 0.25), periodic=("x",))
    with pytest.raises(SceneError) as e:
        place_fills(s, np.random.default_rng(1))
    assert "holds at most 3" in e.value.reason
    s2 = scene(fill(count=4, radius="0.1", region=region), dmin=(0, 0, 0),
               dmax=(0.835, 0.25, 0.25))
    assert place_fills(s2, np.random.default_rng(1)).n == 4
    s3 = scene(fill(count=3, radius="0.1", region=region), dmin=(0, 0, 0),
               dmax=(0.835, 0.25, 0.25), periodic=("x",))
    assert_no_overlap(place_fills(s3, np.random.default_rng(1)), s3)


def test_clear_of_earlier_fills_and_file_fills(tmp_path):
    rng = np.random.default_rng(0)
    # a file fill of big spheres on a coarse grid (given after the count fills: still avoided)
    g = np.arange(0.1, 0.95, 0.2)
    xyz = np.array(np.meshgrid(g, g, g)).reshape(3, -1).T
    rows = "\n".join(f"{x},{y},{z},0.05,0,0,1" for x, y, z in xyz)
    (tmp_path / "big.csv").write_text("x,y,z,radius,vx,vy,vz\n" + rows + "\n")
    body = (fill(count=1500, radius="0.01", extra="temperature = 500.0") +
            fill(material="steel", count=1500, radius="{ mean = 0.008, std = 0.002, min = 0.005, "
                 "max = 0.012 }", extra="fixed = true\nvelocity = [1, 2, 3]") +
            '\n[[particles]]\nmaterial = "ash"\nfile = "big.csv"\n')
    s = scene(body, base_dir=tmp_path)
    p = place_fills(s, rng)
    n_file = len(xyz)
    assert p.n == 3000 + n_file
    assert_no_overlap(p, s)
    assert p.materials == ("ash", "steel")
    np.testing.assert_array_equal(p.fill, np.repeat([0, 1, 2], [1500, 1500, n_file]))
    np.testing.assert_array_equal(p.material, np.repeat([0, 1, 0], [1500, 1500, n_file]))
    assert p.fill.dtype == np.int32 and p.material.dtype == np.int32
    assert p.fixed.dtype == bool and p.fixed[1500:3000].all() and not p.fixed[:1500].any()
    # each fill's temperature, where it gives one, is the heat's (Effect.source_values)
    given = _fill_temperatures(s, p)
    assert np.all(given[0] == 500.0) and np.isnan(given[1]).all() and np.isnan(given[2]).all()
    np.testing.assert_array_equal(p.velocity[1500:3000], np.tile([1.0, 2.0, 3.0], (1500, 1)))
    np.testing.assert_array_equal(p.velocity[3000:], np.tile([0.0, 0.0, 1.0], (n_file, 1)))
    np.testing.assert_array_equal(p.position[3000:], xyz)
    assert np.all(p.angular_velocity == 0.0)


def _fill_temperatures(s, p) -> list:
    """Each fill's particles' temperatures as the heat transfer gives them (thermal/effects.py
    Temperature.source_values; NaN where the fill gives none), for a scene read without
    [thermal] (its materials have no heat capacity: the thermal masses are not looked at)."""
    from types import SimpleNamespace
    from taichi_dem.thermal.effects import Temperature
    heat = Temperature("", compensated=False)
    fake = SimpleNamespace(settings={"thermal": SimpleNamespace(moisture=False)},
                           materials=s.materials)
    out = []
    with np.errstate(divide="ignore"):
        for i, f in enumerate(s.fills):
            sel = p.fill == i
            out.append(heat.source_values(fake, f, p.materials, p.material[sel],
                                          np.ones(int(sel.sum())))["temperature"])
    return out


def test_file_fill_defaults_and_angular_velocity(tmp_path):
    (tmp_path / "f.csv").write_text("x,y,z,radius\n0.5,0.5,0.5,0.01\n0.2,0.2,0.2,0.01\n")
    body = ('[[particles]]\nmaterial = "ash"\nfile = "f.csv"\nvelocity = [0, 0, -1]\n'
            'angular_velocity = [0, 0, "60 rpm"]\n')
    p = place_fills(scene(body, base_dir=tmp_path), np.random.default_rng(0))
    assert p.n == 2
    np.testing.assert_allclose(p.velocity, [[0, 0, -1]] * 2)
    np.testing.assert_allclose(p.angular_velocity, [[0, 0, 2 * math.pi]] * 2)
    assert np.isnan(_fill_temperatures(scene(body, base_dir=tmp_path), p)[0]).all()


def test_count_zero_and_no_fills():
    p = place_fills(scene(fill(count=0)), np.random.default_rng(0))
    assert p.n == 0 and p.position.shape == (0, 3) and p.velocity.shape == (0, 3)
    p = place_fills(scene(""), np.random.default_rng(0))
    assert p.n == 0 and p.position.shape == (0, 3) and p.material.dtype == np.int32


def test_deterministic_for_seed():
    s = scene(fill(count=500, radius="{ mean = 0.01, std = 0.002, min = 0.006, max = 0.014 }"))
    a = place_fills(s, np.random.default_rng(42))
    b = place_fills(s, np.random.default_rng(42))
    c = place_fills(s, np.random.default_rng(43))
    np.testing.assert_array_equal(a.position, b.position)
    np.testing.assert_array_equal(a.radius, b.radius)
    assert not np.array_equal(a.position, c.position)


def test_positions_are_jittered_not_on_a_lattice():
    s = scene(fill(count=300, radius="0.01"))
    p = place_fills(s, np.random.default_rng(1))
    # no two spheres share an x coordinate (a bare lattice would repeat them)
    assert len(np.unique(np.round(p.position[:, 0], 12))) == p.n


def truncnorm_mean(mu, sd, lo, hi):
    phi = lambda x: math.exp(-0.5 * x * x) / math.sqrt(2 * math.pi)   # noqa: E731
    Phi = lambda x: 0.5 * (1 + math.erf(x / math.sqrt(2)))             # noqa: E731
    a, b = (lo - mu) / sd, (hi - mu) / sd
    return mu + sd * (phi(a) - phi(b)) / (Phi(b) - Phi(a))


@pytest.mark.parametrize("mu, sd, lo, hi", [
    (0.01, 0.002, 0.006, 0.014),     # symmetric, normal proposal
    (0.01, 0.002, 0.009, 0.02),      # asymmetric
    (0.01, 0.05, 0.005, 0.012),      # wide std: uniform proposal
])
def test_truncated_normal_radii(mu, sd, lo, hi):
    dist = RadiusDistribution(mean=mu, std=sd, min=lo, max=hi)
    r = sample_radii(dist, 200_000, np.random.default_rng(9))
    assert r.shape == (200_000,)
    assert r.min() >= lo and r.max() <= hi
    expected = truncnorm_mean(mu, sd, lo, hi)
    assert r.mean() == pytest.approx(expected, abs=4 * r.std() / math.sqrt(len(r)))


def test_fill_radii_within_bounds_and_mean():
    s = scene(fill(count=4000, radius="{ mean = 0.006, std = 0.001, min = 0.004, max = 0.008 }"))
    p = place_fills(s, np.random.default_rng(11))
    assert p.radius.min() >= 0.004 and p.radius.max() <= 0.008
    assert p.radius.mean() == pytest.approx(0.006, abs=1e-4)
    assert_no_overlap(p, s)


def test_constant_radius_sampling():
    r = sample_radii(RadiusDistribution(mean=0.01), 5, np.random.default_rng(0))
    np.testing.assert_array_equal(r, np.full(5, 0.01))
    assert sample_radii(RadiusDistribution(mean=0.01), 0, np.random.default_rng(0)).shape == (0,)


def test_sparse_fill_in_huge_region_is_fast():
    s = scene(fill(count=50, radius="0.001", region='box = { min = [0, 0, 0], max = [10, 10, 10] }'),
              dmax=(10, 10, 10))
    t = time.perf_counter()
    p = place_fills(s, np.random.default_rng(0))
    assert time.perf_counter() - t < 2.0
    assert p.n == 50
    assert_no_overlap(p, s)


def test_128k_spheres_in_a_few_seconds():
    s = scene(fill(count=128_000, radius="{ mean = 0.0045, std = 0.0005, min = 0.004, "
                                          "max = 0.005 }",
                   region='box = { min = [0, 0, 0], max = [1, 1, 0.6] }') +
              fill(count=10_000, radius="0.004",
                   region='box = { min = [0, 0, 0.6], max = [1, 1, 1] }'),
              periodic=("x", "y"))
    t = time.perf_counter()
    p = place_fills(s, np.random.default_rng(0))
    elapsed = time.perf_counter() - t
    assert p.n == 138_000
    assert p.radius[:128_000].min() >= 0.004 and p.radius[:128_000].max() <= 0.005
    assert elapsed < 10.0, f"placement took {elapsed:.1f} s"
    # spot-check overlaps: a random sample (and the spheres nearest the periodic faces and the
    # boundary between the fills) against everything, brute force
    near = np.nonzero((p.position[:, 0] < 0.01) | (p.position[:, 1] > 0.99) |
                      (np.abs(p.position[:, 2] - 0.6) < 0.005))[0]
    rng = np.random.default_rng(1)
    sample = rng.choice(p.n, 300, replace=False)
    idx = np.unique(np.concatenate([sample, rng.choice(near, min(len(near), 300), replace=False)]))
    for chunk in np.array_split(idx, max(1, len(idx) // 50)):
        d = min_image(p.position[chunk, None, :] - p.position[None, :, :], s)
        dist = np.sqrt((d * d).sum(-1))
        dist[np.arange(len(chunk)), chunk] = np.inf
        assert (dist - (p.radius[chunk, None] + p.radius[None, :])).min() >= -1e-12


# --- body meshes ---------------------------------------------------------------------------------

SHAFT = """
[[bodies]]
name = "shaft"
material = "steel"
mesh = {{ builder = "paddle_shaft", length = 1.0, shaft_radius = 0.03, rows = {rows}, \
paddles_per_row = 4, paddle_length = 0.2, paddle_width = 0.06, paddle_thickness = 0.01, \
paddle_pitch_deg = 30 }}
"""
AROUND_SHAFT = ('cylinder = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], '
                'radius = 0.3, length = 1.0 }')
SHAFT_DOMAIN = dict(dmin=(-0.1, -0.4, -0.4), dmax=(1.1, 0.4, 0.4))


def _seg_dist(p, a, b):
    d = b - a
    t = np.clip(((p - a) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0.0, 1.0)
    e = p - (a + d * t[..., None])
    return np.sqrt((e * e).sum(-1))


def point_triangle_distance(p, tri):
    """Brute force, (n, 3) points x (m, 3, 3) triangles -> (n, m): the distance to the plane
    where the projection falls inside the triangle (barycentric coordinates), else the nearest
    edge."""
    p = p[:, None, :]
    a, b, c = tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]
    n = np.cross(b - a, c - a)
    area2 = (n * n).sum(-1)
    n_unit = n / np.sqrt(np.maximum(area2, 1e-300))[..., None]
    h = ((p - a) * n_unit).sum(-1)
    x = p - h[..., None] * n_unit
    # barycentric coordinates of the projection from sub-triangle areas
    u = (np.cross(c - b, x - b) * n).sum(-1) / np.maximum(area2, 1e-300)
    v = (np.cross(a - c, x - c) * n).sum(-1) / np.maximum(area2, 1e-300)
    w = 1.0 - u - v
    inside = (u >= 0) & (v >= 0) & (w >= 0) & (area2 > 0)
    edges = np.minimum(np.minimum(_seg_dist(p, a, b), _seg_dist(p, b, c)), _seg_dist(p, c, a))
    return np.where(inside, np.abs(h), edges)


def body_gap(p: PlacedParticles, scene_, idx, shifts=((0.0, 0.0, 0.0),)):
    """Smallest (distance to any body triangle, over the given image shifts) minus radius."""
    tri = np.concatenate([b.vertices[b.faces] for b in scene_.bodies])
    gap = np.inf
    for chunk in np.array_split(idx, max(1, len(idx) // 20)):
        for s in shifts:
            d = point_triangle_distance(p.position[chunk] + np.asarray(s), tri)
            gap = min(gap, (d.min(axis=1) - p.radius[chunk]).min())
    return gap


def nearest_to_body(p: PlacedParticles, scene_, k):
    """Indices of the k spheres whose surfaces come nearest to a body vertex, plus k random."""
    v = np.concatenate([b.vertices for b in scene_.bodies])
    near = np.full(p.n, np.inf)
    for chunk in np.array_split(np.arange(p.n), max(1, p.n // 200)):
        d = np.linalg.norm(p.position[chunk, None, :] - v[None], axis=-1).min(axis=1)
        near[chunk] = d - p.radius[chunk]
    rng = np.random.default_rng(0)
    return np.unique(np.concatenate([np.argsort(near)[:k], rng.choice(p.n, k, replace=False)]))


def test_checks_agree_with_brute_force_distance():
    from taichi_dem.setup.placement import _closest_sq_dist, _segment_sq_dist
    rng = np.random.default_rng(0)
    tri = rng.normal(size=(400, 3, 3))
    tri[:20, 2] = tri[:20, 0] + 0.3 * (tri[:20, 1] - tri[:20, 0])   # degenerate: collinear
    tri[20:30, 1] = tri[20:30, 0]                                    # two vertices equal
    pts = rng.normal(size=(400, 3)) * 1.5
    got = np.sqrt(_closest_sq_dist(pts, tri[:, 0], tri[:, 1], tri[:, 2]))
    want = np.diag(point_triangle_distance(pts, tri))
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    seg = np.sqrt(_segment_sq_dist(pts[:20], tri[:20, 0], tri[:20, 1]))
    np.testing.assert_allclose(got[:20], seg, rtol=1e-9, atol=1e-12)


def test_fill_around_paddle_shaft_is_clear_of_the_body():
    s = scene(fill(count=4000, radius="{ mean = 0.01, std = 0.002, min = 0.006, max = 0.012 }",
                   region=AROUND_SHAFT) + SHAFT.format(rows=4), **SHAFT_DOMAIN)
    assert len(s.bodies) == 1 and len(s.bodies[0].faces) > 500
    p = place_fills(s, np.random.default_rng(4))
    assert p.n == 4000
    assert_no_overlap(p, s)
    idx = nearest_to_body(p, s, 200)
    gap = body_gap(p, s, idx)
    assert gap >= -1e-12, f"a sphere overlaps the shaft by {-gap:g} m"
    assert gap < 0.02          # and the check is not vacuous: spheres do come near the paddles


def test_body_check_is_needed_for_that_fill():
    """Without the bodies the same fill overlaps the paddles (so the test above means something)."""
    s = scene(fill(count=4000, radius="{ mean = 0.01, std = 0.002, min = 0.006, max = 0.012 }",
                   region=AROUND_SHAFT) + SHAFT.format(rows=4), **SHAFT_DOMAIN)
    p = place_fills(dataclasses.replace(s, bodies=()), np.random.default_rng(4))
    assert body_gap(p, s, nearest_to_body(p, s, 200)) < 0.0


def test_body_check_with_a_built_mesh_and_file_fill(tmp_path):
    from taichi_dem import geometry
    m = geometry.build_mesh({"builder": "paddle_shaft", "length": 1.0, "shaft_radius": 0.05,
                             "rows": 3, "paddles_per_row": 2, "paddle_length": 0.15,
                             "paddle_width": 0.1})
    (tmp_path / "p.csv").write_text("x,y,z,radius\n0.5,0.25,0.25,0.02\n")
    s = scene(fill(count=600, radius="0.015", region=AROUND_SHAFT) +
              '\n[[particles]]\nmaterial = "ash"\nfile = "p.csv"\n', base_dir=tmp_path,
              **SHAFT_DOMAIN)
    s = dataclasses.replace(s, bodies=(Body(key="bodies[0]", name="shaft", material="steel",
                                            vertices=np.asarray(m.vertices, float),
                                            faces=np.asarray(m.faces, np.int64)),))
    p = place_fills(s, np.random.default_rng(2))
    assert p.n == 601
    assert_no_overlap(p, s)
    new = np.nonzero(p.fill == 0)[0]
    assert body_gap(p, s, new) >= -1e-12


def test_clear_of_body_images_across_periodic_faces():
    # a plate at x = 0.99 .. 1.03 in a domain periodic in x over [0, 1]: its part beyond x = 1
    # reappears at x = 0 .. 0.03, where the fill must leave room
    body = """
[[bodies]]
name = "plate"
material = "steel"
mesh = { builder = "box", min = [0.99, 0.1, 0.1], max = [1.03, 0.9, 0.9] }
"""
    s = scene(fill(count=3000, radius="0.015") + body, periodic=("x",))
    p = place_fills(s, np.random.default_rng(3))
    assert p.n == 3000
    assert_no_overlap(p, s)
    inner = (np.abs(p.position[:, 1:] - 0.5) < 0.38).all(axis=1)
    assert not np.any(inner & (p.position[:, 0] < 0.03 + p.radius)), "a sphere is in the image"
    idx = np.nonzero(p.position[:, 0] < 0.1)[0]
    assert len(idx) > 10
    assert body_gap(p, s, idx, shifts=((0, 0, 0), (1, 0, 0), (-1, 0, 0))) >= -1e-12


SLAB = """
[[bodies]]
name = "slab"
material = "steel"
mesh = { builder = "box", min = [0.0, 0.0, 0.09], max = [0.3, 0.3, 0.11] }
"""


def test_fill_beside_a_body_places_count_when_room_exists():
    s = scene(fill(count=700, radius="0.01",
                   region='box = { min = [0, 0, 0], max = [0.2, 0.2, 0.2] }') + SLAB)
    p = place_fills(s, np.random.default_rng(1))
    assert p.n == 700
    assert_no_overlap(p, s)
    assert body_gap(p, s, np.arange(p.n)) >= -1e-12


def test_body_taking_the_room_is_a_scene_error():
    # 1000 spheres fit in this cube on their own, not beside a slab through its middle
    s = scene(fill(count=1000, radius="0.01",
                   region='box = { min = [0, 0, 0], max = [0.2, 0.2, 0.2] }') + SLAB)
    assert place_fills(dataclasses.replace(s, bodies=()), np.random.default_rng(1)).n == 1000
    with pytest.raises(SceneError) as e:
        place_fills(s, np.random.default_rng(1))
    assert e.value.key == "particles[0].count"
    assert "clear of walls, bodies and earlier particles" in e.value.reason
    assert "enlarge the region or reduce count" in e.value.reason


def test_body_check_is_fast():
    # ~20k candidate lattice sites against a few thousand triangles
    s = scene(fill(count=5000, radius="0.006", region=AROUND_SHAFT) + SHAFT.format(rows=10),
              **SHAFT_DOMAIN)
    n_tri = len(s.bodies[0].faces)
    assert n_tri > 2000
    t = time.perf_counter()
    p = place_fills(s, np.random.default_rng(0))
    elapsed = time.perf_counter() - t
    assert p.n == 5000
    assert elapsed < 3.0, f"placement beside {n_tri} triangles took {elapsed:.2f} s"


def test_body_query_many_sites_many_triangles_is_fast():
    from taichi_dem.setup.placement import _Triangles
    s = scene(fill(count=10, radius="0.005", region=AROUND_SHAFT) + SHAFT.format(rows=10),
              **SHAFT_DOMAIN)
    tris = _Triangles(s, 0.01)
    rng = np.random.default_rng(0)
    pts = rng.uniform((0.0, -0.3, -0.3), (1.0, 0.3, 0.3), (100_000, 3))
    r = np.full(len(pts), 0.005)
    t = time.perf_counter()
    hit = tris.hits(pts, r)
    elapsed = time.perf_counter() - t
    assert elapsed < 3.0, f"100k sites vs {len(tris)} triangles took {elapsed:.2f} s"
    # agrees with brute force on the hits and on a sample of misses nearest the body
    tri = s.bodies[0].vertices[s.bodies[0].faces]
    sample = np.concatenate([np.nonzero(hit)[0][:150], np.nonzero(~hit)[0][:150]])
    d = np.concatenate([point_triangle_distance(pts[c], tri).min(axis=1)
                        for c in np.array_split(sample, 10)])
    np.testing.assert_array_equal(d < r[sample] * (1 + 1e-9), hit[sample])
