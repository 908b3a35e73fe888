"""The triangle mesh type shared by the builders, the importer and the engine.

Conventions (every builder follows them; the engine may rely on them):

* Units are metres. ``vertices`` is ``(V, 3) float64``; ``faces`` is ``(F, 3) int64`` indices
  into ``vertices``.
* A face's normal is ``(v1 - v0) x (v2 - v0)`` normalised: the corners run counter-clockwise
  seen from the side the normal points to.
* **The normal points to the side particles live on.** Into the drum (the shell towards the
  axis, the end walls towards the drum's middle), into hoppers, chutes and container boxes, and
  out of solids such as the shaft, a thick paddle or a thick screw flight.
* Thin plates (lifting flights, zero-thickness paddles and screw flights) are a **single layer
  of triangles** marked in ``two_sided``: particles may touch either side, so contact on them
  must use the unsigned distance. There is never a second, coincident layer with reversed
  winding (that would double every contact force). A plate's stored normal is still defined:
  the face that leads (pushes material) when the body turns in the positive sense (right-hand
  rule) about its builder +x axis. Give a plate a thickness (``paddle_thickness``,
  ``flight_thickness``) to get a closed one-sided solid instead.
* A closed surface made of one-sided faces (a shaft, a box, a drum with full end walls, a
  thick paddle) is watertight and consistently wound: every edge is shared by exactly two
  faces that traverse it in opposite directions (:attr:`TriMesh.is_closed`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import math

import numpy as np


def rotation_matrix(axis, angle: float) -> np.ndarray:
    """Rodrigues rotation by ``angle`` rad about the unit ``axis`` (a 3 x 3 array)."""
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]], float)
    return np.eye(3) + s * k + (1 - c) * (k @ k)

# Scene-size sanity: a DEM body larger than this or smaller than that is a unit mistake.
MAX_EXTENT = 1000.0      # m
MIN_EXTENT = 1e-6        # m
# A triangle is degenerate when its height is below this fraction of its longest edge, or its
# longest edge is below this fraction of the mesh's bounding-box diagonal.
DEGENERATE_RATIO = 1e-9


class GeometryError(ValueError):
    """A bad mesh or builder input: ``key`` is the dotted scene key (e.g.
    ``"bodies[0].mesh.flight_height"``), ``reason`` says what is wrong and how to fix it.

    The scene loader turns it into ``SceneError(file, err.key, err.reason)``.
    """

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}" if key else reason)


class ParameterError(GeometryError):
    """Raised inside a builder or the importer about one of its parameters (``param``, e.g.
    ``"file"``); ``build()`` prefixes the scene key (``bodies[0].mesh.file``)."""

    def __init__(self, param: str, reason: str):
        super().__init__(param, reason)


@dataclass(frozen=True, eq=False)
class TriMesh:
    """An immutable triangle mesh in metres; see the module docstring for the conventions.

    ``two_sided`` is a ``(F,)`` bool array: True for faces of zero-thickness plates that
    particles may touch from either side; None means all False.
    """
    vertices: np.ndarray
    faces: np.ndarray
    two_sided: Optional[np.ndarray] = field(default=None)

    def __post_init__(self):
        v = np.ascontiguousarray(np.asarray(self.vertices, dtype=np.float64).reshape(-1, 3))
        f = np.asarray(self.faces)
        if f.size and not np.issubdtype(f.dtype, np.integer):
            if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
                raise GeometryError("", "faces must hold integer vertex indices")
        f = np.ascontiguousarray(f.astype(np.int64).reshape(-1, 3))
        if self.two_sided is None:
            t = np.zeros(len(f), dtype=bool)
        else:
            t = np.asarray(self.two_sided, dtype=bool).reshape(-1)
            if t.size == 1:
                t = np.full(len(f), bool(t[0]))
            elif t.shape != (len(f),):
                raise GeometryError("", "two_sided must have one flag per face")
        for a in (v, f, t):
            a.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        object.__setattr__(self, "two_sided", t)

    # ------------------------------------------------------------------ constructors
    @staticmethod
    def empty() -> "TriMesh":
        return TriMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))

    @staticmethod
    def concatenate(meshes) -> "TriMesh":
        meshes = list(meshes)
        if not meshes:
            return TriMesh.empty()
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        return TriMesh(np.concatenate([m.vertices for m in meshes]),
                       np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]),
                       np.concatenate([m.two_sided for m in meshes]))

    # ------------------------------------------------------------------ derived figures
    @property
    def n_faces(self) -> int:
        return len(self.faces)

    @property
    def bounds(self) -> np.ndarray:
        """``(2, 3)``: the bounding box's min and max corners, m."""
        if len(self.vertices) == 0:
            return np.zeros((2, 3))
        used = self.vertices[np.unique(self.faces)] if len(self.faces) else self.vertices
        return np.stack([used.min(axis=0), used.max(axis=0)])

    @property
    def extent(self) -> float:
        """Length of the bounding-box diagonal, m."""
        lo, hi = self.bounds
        return float(np.linalg.norm(hi - lo))

    def _cross(self) -> np.ndarray:
        v = self.vertices[self.faces]
        return np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])

    @property
    def face_areas(self) -> np.ndarray:
        return 0.5 * np.linalg.norm(self._cross(), axis=1)

    @property
    def area(self) -> float:
        """Total surface area, m^2 (a two-sided plate counts once)."""
        return float(self.face_areas.sum())

    @property
    def face_normals(self) -> np.ndarray:
        """``(F, 3)`` unit normals, pointing to the particle side (see the conventions)."""
        c = self._cross()
        n = np.linalg.norm(c, axis=1, keepdims=True)
        return c / np.where(n > 0, n, 1.0)

    @property
    def face_centroids(self) -> np.ndarray:
        return self.vertices[self.faces].mean(axis=1)

    @property
    def signed_volume(self) -> float:
        """Volume enclosed by the one-sided faces, m^3: positive when their normals point
        outward (a solid), negative when inward (a container). Meaningful when closed."""
        f = self.faces[~self.two_sided]
        v = self.vertices[f]
        return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)

    def _directed_edges(self, faces) -> np.ndarray:
        return np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])

    def open_edge_count(self) -> int:
        """Edges of the one-sided faces not matched by exactly one opposite edge (0 = closed)."""
        f = self.faces[~self.two_sided]
        if len(f) == 0:
            return 0
        e = self._directed_edges(f)
        key = np.sort(e, axis=1)
        _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        forward = (e[:, 0] < e[:, 1]).astype(np.int64)
        fwd_count = np.bincount(inv.reshape(-1), weights=forward, minlength=len(counts))
        good = (counts == 2) & (fwd_count == 1)
        return int(np.sum(~good))

    @property
    def is_closed(self) -> bool:
        """True when the one-sided faces form a watertight, consistently wound surface."""
        return bool((~self.two_sided).any()) and self.open_edge_count() == 0

    def connected_components(self) -> int:
        """Number of pieces (faces linked through shared vertices)."""
        if len(self.faces) == 0:
            return 0
        parent = np.arange(len(self.vertices))

        def find(i):
            root = i
            while parent[root] != root:
                root = parent[root]
            while parent[i] != root:
                parent[i], i = root, parent[i]
            return root

        for a, b, c in self.faces:
            ra, rb, rc = find(a), find(b), find(c)
            parent[rb] = ra
            parent[find(rc)] = ra
        return len({find(i) for i in np.unique(self.faces)})

    # ------------------------------------------------------------------ operations
    def merged(self, other: "TriMesh") -> "TriMesh":
        return TriMesh.concatenate([self, other])

    def transformed(self, rotation=None, translation=None) -> "TriMesh":
        """``x -> rotation @ x + translation``. A reflection (det < 0) also reverses the
        winding so that normals still point to the particle side."""
        r = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
        t = np.zeros(3) if translation is None else np.asarray(translation, dtype=np.float64)
        if r.shape != (3, 3) or t.shape != (3,):
            raise GeometryError("", "rotation must be 3x3 and translation a 3-vector")
        if not np.allclose(r @ r.T, np.eye(3), atol=1e-9):
            raise GeometryError("", "rotation is not orthonormal")
        faces = self.faces if np.linalg.det(r) > 0 else self.faces[:, ::-1]
        return TriMesh(self.vertices @ r.T + t, faces, self.two_sided)

    def flipped(self) -> "TriMesh":
        """The same surface with every normal reversed."""
        return TriMesh(self.vertices, self.faces[:, ::-1], self.two_sided)

    def with_two_sided(self, flag: bool) -> "TriMesh":
        return TriMesh(self.vertices, self.faces, np.full(len(self.faces), bool(flag)))

    def to_trimesh(self):
        import trimesh
        return trimesh.Trimesh(vertices=np.array(self.vertices), faces=np.array(self.faces),
                               process=False)

    # ------------------------------------------------------------------ validation
    def validate(self, key: str = "mesh") -> "TriMesh":
        """Check the mesh is usable by the engine; return self or raise :class:`GeometryError`.

        Errors: no triangles; non-finite vertices; indices out of range; degenerate triangles
        (repeated or collinear corners, or a longest edge below 1e-9 of the mesh size); a
        bounding box larger than 1 km or smaller than 1 um (wrong units?).
        """
        v, f = self.vertices, self.faces
        if len(f) == 0 or len(v) == 0:
            raise GeometryError(key, "the mesh has no triangles")
        bad = ~np.all(np.isfinite(v), axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise GeometryError(key, f"{int(bad.sum())} vertices are not finite (NaN or inf), "
                                     f"first vertex {i} = {v[i].tolist()}")
        if f.min() < 0 or f.max() >= len(v):
            i = int(np.flatnonzero((f < 0).any(axis=1) | (f >= len(v)).any(axis=1))[0])
            raise GeometryError(key, f"triangle {i} = {f[i].tolist()} indexes a vertex outside "
                                     f"0..{len(v) - 1}")
        lo, hi = self.bounds
        size = float(np.max(hi - lo))
        if size > MAX_EXTENT:
            raise GeometryError(key, f"the mesh is {size:.4g} m across, absurd for a DEM scene "
                                     "(wrong units? lengths are in metres: write 0.433 or "
                                     "\"433 mm\"; a file in mm takes units = \"mm\")")
        if size < MIN_EXTENT:
            raise GeometryError(key, f"the mesh is {size:.3g} m across, below 1 um (wrong "
                                     "units? lengths are in metres)")
        tri = v[f]
        edges = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]],
                         axis=1)
        longest = np.linalg.norm(edges, axis=2).max(axis=1)
        twice_area = np.linalg.norm(np.cross(edges[:, 0], -edges[:, 2]), axis=1)
        diag = float(np.linalg.norm(hi - lo))
        degenerate = (longest <= DEGENERATE_RATIO * diag) | \
                     (twice_area <= DEGENERATE_RATIO * longest ** 2)
        if degenerate.any():
            i = int(np.flatnonzero(degenerate)[0])
            raise GeometryError(key, f"{int(degenerate.sum())} of {len(f)} triangles are "
                                     f"degenerate (zero area: repeated or collinear corners), "
                                     f"first triangle {i} with corners {tri[i].tolist()}; "
                                     "for an imported file, repair = true drops them")
        return self
