"""Low-level surface makers for the builders: structured grids, slabs, surfaces of revolution.

Orientation rule used throughout: for a grid ``P[i, j]`` the quad
``(i,j) (i+1,j) (i+1,j+1) (i,j+1)`` is split into two triangles whose normal is along
``dP/di x dP/dj``.
"""
from __future__ import annotations

import math

import numpy as np

from .mesh import GeometryError, TriMesh

# A built mesh may have at most this many triangles (and profile points): more is a unit
# mistake or an absurd ratio of sizes (a 1 km drum of 1 mm chords). Builder.build opens a
# budget; the makers below spend it *before* they allocate, so an absurd scene fails at once
# instead of exhausting memory.
MAX_TRIANGLES = 5_000_000
_budget: dict = {"left": None}


class triangle_budget:
    """``with triangle_budget(): ...`` - the makers may spend MAX_TRIANGLES in the block."""

    def __enter__(self):
        self.saved = _budget["left"]
        _budget["left"] = MAX_TRIANGLES

    def __exit__(self, *exc):
        _budget["left"] = self.saved
        return False


def _too_many(n: float, what: str) -> GeometryError:
    return GeometryError("", f"the mesh would need {n:.3g} {what}, more than "
                             f"{MAX_TRIANGLES:,}: a length or count is absurd next to the "
                             "others (wrong units?)")


def spend(n: float, what: str = "triangles") -> None:
    """Count ``n`` against the open budget (none open: no limit)."""
    left = _budget["left"]
    if left is None:
        return
    if not n <= left:                      # also NaN
        raise _too_many(n, what)
    _budget["left"] = left - n


def afford(n: float, what: str = "triangles") -> None:
    """Refuse ``n`` more than the open budget holds, without spending it (call before
    allocating what a later maker spends)."""
    left = _budget["left"]
    if left is not None and not n <= left:
        raise _too_many(n, what)


def pieces(length: float, target: float, what: str = "pieces along an edge") -> int:
    """``max(1, ceil(length / target))``, refused (before any allocation) beyond
    MAX_TRIANGLES: the number of segments that split ``length`` into pieces <= ``target``."""
    n = length / target if target > 0 else math.inf
    if not n <= MAX_TRIANGLES:
        raise _too_many(n, what)
    return max(1, math.ceil(n - 1e-9))


def grid_faces(m: int, n: int, *, wrap_j: bool = False) -> np.ndarray:
    """Faces of an ``m x n`` point grid (index ``i * n + j``)."""
    jn = n if wrap_j else n - 1
    spend(2.0 * max(m - 1, 0) * max(jn, 0))
    i, j = np.meshgrid(np.arange(m - 1), np.arange(jn), indexing="ij")
    i, j = i.ravel(), j.ravel()
    j1 = (j + 1) % n
    a, b, c, d = i * n + j, (i + 1) * n + j, (i + 1) * n + j1, i * n + j1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def compact(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop triangles with a repeated index and vertices no triangle uses."""
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[keep]
    used, inv = np.unique(faces, return_inverse=True)
    return vertices[used], inv.reshape(-1, 3)


def weld(mesh: TriMesh) -> TriMesh:
    """Merge bit-identical vertices (the builders compute shared corners identically)."""
    uniq, inv = np.unique(mesh.vertices, axis=0, return_inverse=True)
    faces = inv.reshape(-1)[mesh.faces]
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    v, f = compact(uniq, faces)
    return TriMesh(v, f, mesh.two_sided[keep])


def sheet(points: np.ndarray, *, two_sided: bool = True, flip: bool = False) -> TriMesh:
    """A single-layer surface through the ``(m, n, 3)`` grid ``points``."""
    m, n, _ = points.shape
    f = grid_faces(m, n)
    if flip:
        f = f[:, ::-1]
    return TriMesh(points.reshape(-1, 3), f, np.full(len(f), two_sided))


def sheet_facing(points: np.ndarray, direction, *, two_sided: bool = False) -> TriMesh:
    """A sheet whose normals point along ``direction`` (a vector) rather than against it."""
    s = sheet(points, two_sided=two_sided)
    if float(np.sum(s.face_normals * s.face_areas[:, None], axis=0) @ np.asarray(direction)) < 0:
        s = s.flipped()
    return s


def slab(points: np.ndarray, offsets: np.ndarray) -> TriMesh:
    """A closed solid: the grid ``points`` moved by ``+offsets/2`` and ``-offsets/2`` (per point,
    ``(m, n, 3)``, or one vector), joined along the grid's boundary; normals outward."""
    m, n, _ = points.shape
    off = np.broadcast_to(np.asarray(offsets, dtype=np.float64), points.shape)
    top = (points + 0.5 * off).reshape(-1, 3)
    bot = (points - 0.5 * off).reshape(-1, 3)
    k = m * n
    f_top = grid_faces(m, n)
    f_bot = f_top[:, ::-1] + k
    # boundary loop in index order: along j at i=0, along i at j=n-1, back along j, back along i
    loop = ([(0, j) for j in range(n)] + [(i, n - 1) for i in range(1, m)]
            + [(m - 1, j) for j in range(n - 2, -1, -1)] + [(i, 0) for i in range(m - 2, 0, -1)])
    idx = [i * n + j for i, j in loop]
    sides = []
    for p, q in zip(idx, idx[1:] + idx[:1]):
        sides += [(p, q, q + k), (p, q + k, p + k)]
    f = np.concatenate([f_top, f_bot, np.asarray(sides, dtype=np.int64)])
    mesh = TriMesh(np.concatenate([top, bot]), f)
    return mesh if mesh.signed_volume > 0 else mesh.flipped()


def subdivide_polyline(points, target: float) -> np.ndarray:
    """Insert points so no segment of the polyline is longer than ``target``."""
    pts = np.asarray(points, dtype=np.float64)
    out = [pts[:1]]
    for a, b in zip(pts[:-1], pts[1:]):
        length = float(np.linalg.norm(b - a))
        if length == 0.0:
            continue
        n = pieces(length, target, "points along a profile")
        spend(n, "points along profiles")
        out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(out)


def revolve(profile, n: int, *, phase: float = 0.0, normals: str = "right",
            target: float | None = None, two_sided: bool = False) -> TriMesh:
    """Revolve a polyline ``[(x, r), ...]`` about the x axis with ``n`` segments, the vertices
    at angles ``phase + 2 pi j / n`` (measured from +y towards +z), on the true radius.

    ``normals = "right"``: the normals point to the right of the profile walked in order, in
    the (x right, r up) half-plane; so walking +x along a shell gives normals towards the axis,
    walking outwards (+r) at fixed x gives +x normals. ``"left"``: the other side. Points on the
    axis (r = 0) become one vertex (fans, no degenerate triangles).
    """
    prof = np.asarray(profile, dtype=np.float64)
    if target is not None:
        prof = subdivide_polyline(prof, target)
    afford(2.0 * len(prof) * n)
    theta = phase + 2.0 * np.pi * np.arange(n) / n
    x = np.repeat(prof[:, 0], n)
    r = np.repeat(prof[:, 1], n)
    t = np.tile(theta, len(prof))
    v = np.stack([x, r * np.cos(t), r * np.sin(t)], axis=1)
    f = grid_faces(len(prof), n, wrap_j=True)
    on_axis = np.repeat(prof[:, 1] == 0.0, n)
    first = np.repeat(np.arange(len(prof)) * n, n)
    remap = np.where(on_axis, first, np.arange(len(v)))
    v[on_axis, 1:] = 0.0
    f = remap[f]
    if normals == "left":
        f = f[:, ::-1]
    v, f = compact(v, f)
    return TriMesh(v, f, np.full(len(f), two_sided))


def rotation_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rotation_y(angle: float) -> np.ndarray:
    """Rotation about +y; ``rotation_y(a) @ x = (cos a, 0, -sin a)``: +x tilted down by a."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def align_x_to(direction) -> np.ndarray:
    """The rotation that turns +x onto ``direction`` without roll: builder +y goes to the
    horizontal ``z x d`` (normalised) and builder +z stays in the vertical plane through ``d``.
    For a vertical ``d`` builder +y stays +y."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    y = np.cross([0.0, 0.0, 1.0], d)
    if np.linalg.norm(y) < 1e-12:
        y = np.array([0.0, 1.0, 0.0])
    y /= np.linalg.norm(y)
    z = np.cross(d, y)
    return np.stack([d, y, z], axis=1)
