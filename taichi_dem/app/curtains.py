"""The curtains of a flighted drum: which particles are airborne (falling from the flights
through the gas), the mass fraction they hold and the surface they show the gas, per metre of
drum - what a dryer's gas-solids heat transfer comes from (PHYSICS.md, "Flighted rotary
dryers": the airborne fraction is what meets the gas; the bed and the flights' loads are
shielded).

A particle is airborne when it touches nothing: no other particle and no body (its centre
farther than its radius from every triangle). Contacts are judged from positions alone, with a
tolerance of CONTACT_TOLERANCE radii for the contacts the step has just opened or is about to
close (a bed's particles overlap by a few per mille of a radius). A periodic axis is wrapped:
particles touch across its faces.
"""
from __future__ import annotations

import numpy as np

# a pair (or a particle and a body) closer than (1 + this) x the sum of radii (the radius)
# counts as touching
CONTACT_TOLERANCE = 0.02


def touching_another(position: np.ndarray, radius: np.ndarray, period_axis: int | None = None,
                     period: float = 0.0) -> np.ndarray:
    """(N,) bool: the particle touches another particle (centres within the sum of the radii
    times 1 + CONTACT_TOLERANCE), across the faces of a periodic axis of length ``period`` m."""
    from scipy.spatial import cKDTree
    n = len(position)
    out = np.zeros(n, bool)
    if n < 2:
        return out
    x, box = _periodic_box(position, period_axis, period)
    reach = 2.0 * float(np.max(radius)) * (1.0 + CONTACT_TOLERANCE)
    pairs = cKDTree(x, boxsize=box).query_pairs(reach, output_type="ndarray")
    if len(pairs) == 0:
        return out
    d = x[pairs[:, 0]] - x[pairs[:, 1]]
    if box is not None:
        d[:, period_axis] -= period * np.round(d[:, period_axis] / period)
    gap = np.linalg.norm(d, axis=1)
    near = gap <= (radius[pairs[:, 0]] + radius[pairs[:, 1]]) * (1.0 + CONTACT_TOLERANCE)
    out[pairs[near, 0]] = True
    out[pairs[near, 1]] = True
    return out


def _periodic_box(position, period_axis: int | None, period: float):
    """(positions, boxsize) for a cKDTree that wraps ``period_axis`` at ``period`` m: the
    positions shifted into the box's positive octant, that axis taken modulo the period.
    cKDTree wraps every axis of its box, so the others get a box far larger than the
    particles' span (no image ever comes near); (a copy, None) without a period."""
    x = np.asarray(position, float).copy()
    if period_axis is None or not period > 0.0:
        return x, None
    x -= x.min(axis=0) - 1.0
    x[:, period_axis] = np.mod(x[:, period_axis], period)
    box = np.full(3, 1e3 * (float(np.ptp(x)) + 1.0))
    box[period_axis] = period
    return x, box


def touching_bodies(position: np.ndarray, radius: np.ndarray, meshes, poses) -> np.ndarray:
    """(N,) bool: the particle touches a body: its centre within its radius (times 1 +
    CONTACT_TOLERANCE) of a triangle of one of ``meshes`` (trimesh.Trimesh at the scene's t = 0
    placement) at ``poses`` ((R, T): a vertex x0 is at R x0 + T now)."""
    import trimesh
    out = np.zeros(len(position), bool)
    for mesh, (rotation, translation) in zip(meshes, poses):
        if len(position) == 0:
            break
        local = (np.asarray(position, float) - translation) @ rotation      # R^T (x - T)
        # only the points whose distance to the mesh's box leaves room for a contact
        lo, hi = mesh.bounds
        gap = np.maximum(np.maximum(lo - local, local - hi), 0.0)
        candidate = np.linalg.norm(gap, axis=1) <= radius * (1.0 + CONTACT_TOLERANCE)
        idx = np.nonzero(candidate & ~out)[0]
        if len(idx) == 0:
            continue
        out[idx[_within(mesh, local[idx], radius[idx] * (1.0 + CONTACT_TOLERANCE))]] = True
    return out


def _within(mesh, points: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """(N,) bool: the point is within ``reach`` (m, per point) of a triangle of ``mesh``.
    Exact: the triangles are first narrowed to those whose bounding sphere (about the centroid)
    comes within reach (a KD-tree on the centroids), then measured by trimesh's closest point."""
    import trimesh
    from scipy.spatial import cKDTree
    triangles = np.asarray(mesh.triangles, float)
    centroid = triangles.mean(axis=1)
    sphere = float(np.max(np.linalg.norm(triangles - centroid[:, None, :], axis=2)))
    near = cKDTree(centroid).query_ball_point(points, sphere + reach)
    point_of = np.repeat(np.arange(len(points)), [len(n) for n in near])
    if len(point_of) == 0:
        return np.zeros(len(points), bool)
    triangle_of = np.concatenate([np.asarray(n, int) for n in near])
    closest = trimesh.triangles.closest_point(triangles[triangle_of], points[point_of])
    distance = np.full(len(points), np.inf)
    np.minimum.at(distance, point_of, np.linalg.norm(closest - points[point_of], axis=1))
    return distance <= reach


def airborne(position, radius, meshes, poses, length: float,
             period_axis: int | None = None) -> np.ndarray:
    """(N,) bool: the particle touches no particle (across the periodic axis of length
    ``length`` m) and no body at its pose: it is in flight."""
    free = ~touching_another(position, radius, period_axis, length)
    idx = np.nonzero(free)[0]
    if len(idx):
        hit = touching_bodies(position[idx], radius[idx], meshes, poses)
        free[idx[hit]] = False
    return free


def curtain_figures(position, velocity, radius, mass, meshes, poses, length: float,
                    period_axis: int | None = None, gas_velocity=(0.0, 0.0, 0.0),
                    free: np.ndarray | None = None, surface: bool = True,
                    axis_direction=None) -> dict:
    """A slice's curtains now: ``airborne_fraction`` (of the mass), ``curtain_area_per_metre``
    (the airborne particles' surface, m^2 per metre of drum) and ``curtain_slip_speed`` (their
    mean speed relative to the gas, m/s; NaN with none airborne); with ``surface``, also the
    rest's surface open to the gas (exposed_fraction(): the bed's top and the flights' loads),
    ``surface_area_per_metre`` (m^2/m) and ``surface_slip_speed`` (its area-weighted mean
    speed relative to the gas, m/s). ``free``: the airborne mask when already known
    (airborne()). With ``axis_direction`` (a unit vector along the drum), also
    ``airborne_mass_flow``: the part of the axial mass flow carried in flight, sum m v_a / L
    over the airborne particles (kg/s), so a slice's transport splits into what the curtains
    carry and what the bed and the flights carry."""
    if free is None:
        free = airborne(position, radius, meshes, poses, length, period_axis)
    total = float(np.sum(mass))
    relative = np.linalg.norm(np.asarray(velocity) - np.asarray(gas_velocity, float), axis=1)
    slip = relative[free]
    out = {"airborne_fraction": float(np.sum(mass[free])) / total if total > 0 else float("nan"),
           "curtain_area_per_metre": float(np.sum(4.0 * np.pi * radius[free] ** 2)) / length,
           "curtain_slip_speed": float(np.mean(slip)) if len(slip) else float("nan")}
    if axis_direction is not None:
        axial = np.asarray(velocity, float)[free] @ np.asarray(axis_direction, float)
        out["airborne_mass_flow"] = float(np.sum(np.asarray(mass)[free] * axial)) / length
    if surface:
        held = np.nonzero(~free)[0]
        area = np.zeros(len(held))
        if len(held):
            fraction = exposed_fraction(position, radius, meshes, poses, length, period_axis,
                                        only=held)
            area = 4.0 * np.pi * radius[held] ** 2 * fraction
        out["surface_area_per_metre"] = float(np.sum(area)) / length
        out["surface_slip_speed"] = (float(np.sum(area * relative[held]) / np.sum(area))
                                     if np.sum(area) > 0 else float("nan"))
    return out


# the directions a particle's surface is probed in (exposed_fraction): ~4 % of its area each
# (a bed's figure sums hundreds of particles, so its own resolution is far finer)
EXPOSURE_DIRECTIONS = 24
# a direction is open when its ray runs this many mean diameters without meeting a particle
# or a body: the pores of a random packing (mean chord ~0.44 d at porosity 0.4, chords
# distributed exponentially) let through exp(-2 / 0.44) ~ 1 % of the rays from inside a bed
EXPOSURE_REACH_DIAMETERS = 2.0


def sphere_directions(count: int) -> np.ndarray:
    """(count, 3) unit vectors spread evenly over the sphere (the Fibonacci lattice: each
    stands for 4 pi / count of it)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    azimuth = np.pi * (1.0 + 5.0 ** 0.5) * k
    ring = np.sqrt(1.0 - z * z)
    return np.stack([ring * np.cos(azimuth), ring * np.sin(azimuth), z], axis=1)


def exposed_fraction(position, radius, meshes=(), poses=(), length: float = 0.0,
                     period_axis: int | None = None, reach: float | None = None,
                     directions: int = EXPOSURE_DIRECTIONS, only=None) -> np.ndarray:
    """The fraction of each particle's surface that faces open gas: of ``directions`` normals
    spread evenly over it, those whose ray from the surface runs ``reach`` m (default
    EXPOSURE_REACH_DIAMETERS mean diameters) without entering another particle (across the
    periodic axis of length ``length`` m) or crossing a triangle of ``meshes`` at ``poses``
    ((R, T) as in touching_bodies). The gas sweeping past a bed meets its outer layer: a
    sphere alone is 1, one of two touching equal spheres 1 - (1 - cos 30 deg) / 2 = 0.933
    (the other hides the cap whose normals pass within a radius of its centre), one resting
    on a floor (1 + r / (r + reach)) / 2 = 0.6 at the default reach (the normals just below
    its equator clear the floor within the reach), and one inside a packing ~0. ``only``: the indices to measure (all by
    default); returns their fractions, each a multiple of 1 / ``directions``."""
    from scipy.spatial import cKDTree
    x = np.asarray(position, float)
    r = np.asarray(radius, float)
    idx = np.arange(len(x)) if only is None else np.asarray(only, int)
    if len(idx) == 0:
        return np.ones(0)
    span = EXPOSURE_REACH_DIAMETERS * 2.0 * float(np.mean(r)) if reach is None else float(reach)
    u = sphere_directions(directions)
    blocked = np.zeros((len(idx), directions), bool)
    xs, box = _periodic_box(x, period_axis, length)
    # other particles: those within the ray's reach of the surface (each pair both ways,
    # kept where the first is measured, grouped by it)
    pairs = cKDTree(xs, boxsize=box).query_pairs(float(np.max(r)) * 2.0 + span,
                                                 output_type="ndarray")
    first, second = np.r_[pairs[:, 0], pairs[:, 1]], np.r_[pairs[:, 1], pairs[:, 0]]
    row_of = np.full(len(x), -1)
    row_of[idx] = np.arange(len(idx))
    keep = row_of[first] >= 0
    order = np.argsort(row_of[first[keep]], kind="stable")
    a, b = row_of[first[keep]][order], second[keep][order]
    d = xs[b] - xs[idx[a]]                          # from the particle to its neighbour
    if box is not None:
        d[:, period_axis] -= length * np.round(d[:, period_axis] / length)
    # the nearest neighbours first: they hide most directions, and a particle they hide all
    # round (most of a bed's) needs no test against the farther ones
    near = np.einsum("pc,pc->p", d, d) < (4.0 * float(np.max(r))) ** 2
    _block(blocked, u, r[idx], a[near], b[near], d[near], r, span)
    far = ~near & ~blocked.all(axis=1)[a]
    _block(blocked, u, r[idx], a[far], b[far], d[far], r, span)
    rows, dirs = np.nonzero(~blocked)
    if len(rows) and len(meshes):
        start = x[idx[rows]] + r[idx[rows]][:, None] * u[dirs]
        hit = _segments_cross(meshes, poses, start, u[dirs], span)
        blocked[rows[hit], dirs[hit]] = True
    return 1.0 - blocked.mean(axis=1)


def _block(blocked, u, radius_of_row, a, b, d, radius, span, chunk=20000) -> None:
    """Mark in ``blocked`` (rows x directions) the directions ``u`` of row a whose ray from
    the surface, s + t u with s = r_a u and 0 <= t <= ``span``, enters the sphere of particle
    b (``radius``) at ``d`` from it: its closest approach to d, at t* = clip(u.d - r_a, 0,
    span) and s' = r_a + t*, is |s' u - d|^2 = |d|^2 - 2 s' u.d + s'^2 < r_b^2. The pairs
    come grouped by a (ascending)."""
    for lo in range(0, len(a), chunk):       # (nothing to do without pairs)
        ia, jb, dd = a[lo:lo + chunk], b[lo:lo + chunk], d[lo:lo + chunk]
        along = dd @ u.T                                              # (pairs, directions)
        ri = radius_of_row[ia][:, None]
        reach_to = ri + np.clip(along - ri, 0.0, span)
        gap = np.einsum("pc,pc->p", dd, dd)[:, None] - 2.0 * reach_to * along + reach_to ** 2
        hit = gap < (radius[jb] ** 2)[:, None]
        first = np.flatnonzero(np.r_[True, ia[1:] != ia[:-1]])
        blocked[ia[first]] |= np.logical_or.reduceat(hit, first, axis=0)


def _segments_cross(meshes, poses, start: np.ndarray, direction: np.ndarray,
                    span: float) -> np.ndarray:
    """(N,) bool: the segment start + t direction, 0 <= t <= span (m), crosses a triangle of
    one of ``meshes`` at ``poses``. The triangles are narrowed by their bounding spheres
    against the segment's (a KD-tree on the centroids), then each pair is tested exactly
    (Moller & Trumbore 1997)."""
    from scipy.spatial import cKDTree
    out = np.zeros(len(start), bool)
    for mesh, (rotation, translation) in zip(meshes, poses):
        todo = np.nonzero(~out)[0]
        if len(todo) == 0:
            break
        origin = (start[todo] - translation) @ rotation                 # R^T (x - T)
        ray = direction[todo] @ rotation
        triangles = np.asarray(mesh.triangles, float)
        centroid = triangles.mean(axis=1)
        sphere = float(np.max(np.linalg.norm(triangles - centroid[:, None, :], axis=2)))
        near = cKDTree(centroid).query_ball_point(origin + 0.5 * span * ray,
                                                  sphere + 0.5 * span)
        seg = np.repeat(np.arange(len(todo)), [len(n) for n in near])
        if len(seg) == 0:
            continue
        tri = np.concatenate([np.asarray(n, int) for n in near])
        for lo in range(0, len(seg), 200000):
            sg, tr = seg[lo:lo + 200000], tri[lo:lo + 200000]
            v0, v1, v2 = triangles[tr, 0], triangles[tr, 1], triangles[tr, 2]
            e1, e2, o, dvec = v1 - v0, v2 - v0, origin[sg], ray[sg]
            pvec = np.cross(dvec, e2)
            det = np.einsum("ij,ij->i", e1, pvec)
            ok = np.abs(det) > 1e-15
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            tvec = o - v0
            bu = np.einsum("ij,ij->i", tvec, pvec) * inv
            qvec = np.cross(tvec, e1)
            bv = np.einsum("ij,ij->i", dvec, qvec) * inv
            dist = np.einsum("ij,ij->i", e2, qvec) * inv
            cross = ok & (bu >= 0) & (bv >= 0) & (bu + bv <= 1) & (dist >= 0) & (dist <= span)
            out[todo[np.unique(sg[cross])]] = True
    return out
