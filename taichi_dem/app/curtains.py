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
    x = np.asarray(position, float).copy()
    box = None
    if period_axis is not None and period > 0.0:
        # cKDTree wraps every axis of its box: the periodic one at the period, the others in a
        # box far larger than the particles' span (no image ever comes near)
        x -= x.min(axis=0) - 1.0
        x[:, period_axis] = np.mod(x[:, period_axis], period)
        box = np.full(3, 1e3 * (float(np.ptp(x)) + 1.0))
        box[period_axis] = period
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
                    free: np.ndarray | None = None) -> dict:
    """A slice's curtains now: ``airborne_fraction`` (of the mass), ``curtain_area_per_metre``
    (the airborne particles' surface, m^2 per metre of drum) and ``curtain_slip_speed`` (their
    mean speed relative to the gas, m/s; NaN with none airborne). ``free``: the airborne mask
    when already known (airborne())."""
    if free is None:
        free = airborne(position, radius, meshes, poses, length, period_axis)
    total = float(np.sum(mass))
    slip = np.linalg.norm(np.asarray(velocity)[free] - np.asarray(gas_velocity, float), axis=1)
    return {"airborne_fraction": float(np.sum(mass[free])) / total if total > 0 else float("nan"),
            "curtain_area_per_metre": float(np.sum(4.0 * np.pi * radius[free] ** 2)) / length,
            "curtain_slip_speed": float(np.mean(slip)) if len(slip) else float("nan")}
