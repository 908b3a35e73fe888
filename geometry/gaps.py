"""The narrowest gap between two bodies turning about a common axis (plain numpy).

A paddle shaft turning inside a shell sweeps its paddle tips past every point of the shell:
whatever the angle, a sphere must pass between the tips and the shell. In the half-plane of
(axial position, distance from the axis), each body's surface is a cloud of points; the inner
body's outermost extent and the outer body's innermost extent in each axial slab bound the
annulus every sphere crossing that slab must fit through. The gap is the smallest radial
distance between the two envelopes over the slabs both occupy - a radial gap, exact for
coaxial surfaces of revolution swept past each other (shell and paddle tips), a lower bound
of the 3-D gap otherwise.
"""
import numpy as np


def surface_points(vertices: np.ndarray, faces: np.ndarray, per_face: int = 6,
                   seed: int = 0) -> np.ndarray:
    """The vertices, edge midpoints and ``per_face`` random points of each triangle (m)."""
    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    if len(f) == 0:
        return v
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    rng = np.random.default_rng(seed)
    u = rng.random((len(f), per_face, 2))
    flip = u.sum(axis=2) > 1.0
    u[flip] = 1.0 - u[flip]
    inside = (a[:, None] + u[..., :1] * (b - a)[:, None] + u[..., 1:] * (c - a)[:, None])
    return np.concatenate([v, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a),
                           inside.reshape(-1, 3)])


def radial_gap(inner_points: np.ndarray, outer_points: np.ndarray, axis_point, axis_direction,
               slab: float) -> tuple[float, float]:
    """(gap m, axial position m of the narrowest slab) between an inner body's points and an
    outer body's, about the axis (``axis_point`` m, ``axis_direction`` unit), in slabs of
    ``slab`` m along it; (inf, nan) when they share no slab."""
    d = np.asarray(axis_direction, float)
    d = d / np.linalg.norm(d)
    p = np.asarray(axis_point, float)

    def profile(points):
        rel = np.asarray(points, float) - p
        along = rel @ d
        radius = np.linalg.norm(rel - np.outer(along, d), axis=1)
        return np.floor(along / slab).astype(np.int64), along, radius
    ki, ai, ri = profile(inner_points)
    ko, ao, ro = profile(outer_points)
    best, where = np.inf, np.nan
    inner_max = {}
    for k, r in zip(ki, ri):
        if r > inner_max.get(k, -np.inf):
            inner_max[k] = r
    outer_min = {}
    for k, r in zip(ko, ro):
        if r < outer_min.get(k, np.inf):
            outer_min[k] = r
    for k, r_in in inner_max.items():
        # a sphere crossing slab k meets the outer body in this slab or its neighbours
        r_out = min(outer_min.get(k + s, np.inf) for s in (-1, 0, 1))
        if r_out > r_in and r_out - r_in < best:
            best, where = r_out - r_in, (k + 0.5) * slab
    return float(best), float(where)
