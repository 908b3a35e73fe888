"""Initial particle placement: turn a Scene's fills into arrays of non-overlapping spheres.

File fills are taken as given. A ``count``/``region`` fill is placed on a face-centred-cubic
lattice whose nearest-neighbour spacing is at least ``2 r_max (1 + 5 %)``, clipped to the
region: every site must hold a sphere of the largest radius wholly inside the region and the
domain, on the positive side of every wall plane, clear of every triangle of every body's mesh
(at its t = 0 position, with its periodic images) and clear of every particle placed before
(file fills first, then earlier count fills, with minimum-image distances across periodic
faces). ``count`` sites are drawn at random, radii are sampled, and each sphere is jittered
inside the ball of radius ``spacing / 2`` around its site (so new spheres can never overlap
each other); a jittered sphere that would break a constraint stays at its site.

Pure numpy (a sorted-key hash grid for neighbour queries; triangles are matched to the grid
cells their bounding boxes, grown by the sphere radius, overlap and that lie near their planes,
then tested exactly); deterministic for a given rng seed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from ..scene.model import ParticleFill, RadiusDistribution, Region, Scene

GAP = 0.05                 # lattice spacing = 2 r_max (1 + GAP)
_CLEAR = 1e-9              # relative clearance required between spheres


@dataclass(frozen=True, eq=False)
class PlacedParticles:
    """Placed initial particles, SI, in fill order.

    ``material`` indexes ``materials`` (the scene's material names, sorted); ``fill`` indexes
    ``scene.fills`` (what the effects give each fill's particles, their temperatures among
    them, is theirs: Effect.source_values).
    """
    position: np.ndarray           # (n, 3) float64, m
    radius: np.ndarray             # (n,) float64, m
    velocity: np.ndarray           # (n, 3) float64, m/s
    angular_velocity: np.ndarray   # (n, 3) float64, rad/s
    fixed: np.ndarray              # (n,) bool
    material: np.ndarray           # (n,) int32, index into `materials`
    fill: np.ndarray               # (n,) int32, index into scene.fills
    materials: tuple[str, ...] = ()

    @property
    def n(self) -> int:
        return int(self.radius.shape[0])

    def __len__(self) -> int:
        return self.n


def sample_radii(dist: RadiusDistribution, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` radii: constant, or a normal(mean, std) truncated to [min, max] (by rejection from
    the normal or from a uniform proposal, whichever accepts more; both accept >= 4 %)."""
    if n == 0:
        return np.empty(0)
    if dist.std == 0.0:
        return np.full(n, dist.mean)
    lo, hi, mu, sd = float(dist.min), float(dist.max), dist.mean, dist.std
    if hi <= lo:
        return np.full(n, lo)
    out = np.empty(n)
    filled = 0
    use_uniform = (hi - lo) < 2.5 * sd
    while filled < n:
        m = max(2 * (n - filled), 64)
        if use_uniform:
            x = rng.uniform(lo, hi, m)
            accept = rng.uniform(0.0, 1.0, m) < np.exp(-0.5 * ((x - mu) / sd) ** 2)
            x = x[accept]
        else:
            x = rng.normal(mu, sd, m)
            x = x[(x >= lo) & (x <= hi)]
        k = min(len(x), n - filled)
        out[filled:filled + k] = x[:k]
        filled += k
    return out


# --- neighbour queries ---------------------------------------------------------------------------

class _Grid:
    """Points binned into cells of size >= ``cell``; finds candidate pairs within one cell."""

    def __init__(self, points: np.ndarray, cell: float, lo, hi, periodic):
        self.lo = np.asarray(lo, float)
        self.length = np.asarray(hi, float) - self.lo
        self.periodic = np.asarray(periodic, bool)
        n = np.maximum(np.floor(self.length / cell).astype(np.int64), 1)
        # non-periodic axes: one extra cell each side for points on / slightly past the faces
        self.n = np.where(self.periodic, n, n + 2)
        self.size = np.where(self.periodic, self.length / n, cell)
        self.dense = float(np.prod(self.n.astype(float))) < 2.0 ** 62
        self.points = points
        c = self._cells(points)
        keys = self._key(c)
        self.order = np.argsort(keys, kind="stable")
        self.keys = keys[self.order]
        # a dense cell table (O(1) look-ups) when the number of cells is moderate
        ncell = float(np.prod(self.n.astype(float)))
        self.table = None
        if self.dense and ncell <= max(16.0 * len(points), float(1 << 22)):
            counts = np.bincount(self.keys, minlength=int(ncell))
            self.table = (np.cumsum(counts) - counts, counts)

    def _cells(self, p: np.ndarray) -> np.ndarray:
        c = np.floor((p - self.lo) / self.size).astype(np.int64)
        c = np.where(self.periodic, np.mod(c, self.n), np.clip(c + 1, 0, self.n - 1))
        return c

    def _key(self, c: np.ndarray) -> np.ndarray:
        if self.dense:
            return (c[:, 0] * self.n[1] + c[:, 1]) * self.n[2] + c[:, 2]
        h = (c[:, 0].astype(np.uint64) * np.uint64(73856093)) ^ \
            (c[:, 1].astype(np.uint64) * np.uint64(19349663)) ^ \
            (c[:, 2].astype(np.uint64) * np.uint64(83492791))
        return h.view(np.int64)

    def delta(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """a - b with the minimum-image convention on periodic axes."""
        d = a - b
        if self.periodic.any():
            L = np.where(self.periodic, self.length, 0.0)
            d = d - L * np.round(d / np.where(self.periodic, self.length, 1.0))
        return d

    def pairs(self, q: np.ndarray):
        """Yield (query index, point index) candidate arrays, one batch per neighbour offset."""
        if len(self.keys) == 0 or len(q) == 0:
            return
        cq = self._cells(q)
        # per axis and offset: the neighbour cell index and (non-periodic axes) its validity
        comp = []
        for a in range(3):
            per_off = {}
            for o in (-1, 0, 1):
                eff = o % int(self.n[a]) if self.periodic[a] else o
                if eff in per_off:
                    continue
                c = cq[:, a] + o
                if self.periodic[a]:
                    per_off[eff] = (np.mod(c, self.n[a]), None)
                else:
                    per_off[eff] = (c, (c >= 0) & (c < self.n[a]) if o else None)
            comp.append(list(per_off.values()))
        strides = (self.n[1] * self.n[2], self.n[2], 1)
        for cx, vx in comp[0]:
            for cy, vy in comp[1]:
                for cz, vz in comp[2]:
                    valid = [v for v in (vx, vy, vz) if v is not None]
                    if valid:
                        ok = valid[0] if len(valid) == 1 else np.logical_and.reduce(valid)
                        qi = np.nonzero(ok)[0]
                        if len(qi) == 0:
                            continue
                        cx_, cy_, cz_ = cx[qi], cy[qi], cz[qi]
                    else:
                        qi = None
                        cx_, cy_, cz_ = cx, cy, cz
                    if self.dense:
                        keys = cx_ * strides[0] + cy_ * strides[1] + cz_
                    else:
                        keys = self._key(np.stack([cx_, cy_, cz_], axis=1))
                    if self.table is not None:
                        cnt = self.table[1][keys]
                        has = np.nonzero(cnt)[0]
                        cnt = cnt[has]
                        start = self.table[0][keys[has]]
                    else:
                        start = np.searchsorted(self.keys, keys, "left")
                        cnt = np.searchsorted(self.keys, keys, "right") - start
                        has = np.nonzero(cnt)[0]
                        start, cnt = start[has], cnt[has]
                    if len(has) == 0:
                        continue
                    qsel = has if qi is None else qi[has]
                    total = int(cnt.sum())
                    rep_q = np.repeat(qsel, cnt)
                    first = np.repeat(np.cumsum(cnt) - cnt, cnt)
                    idx = np.repeat(start, cnt) + (np.arange(total) - first)
                    yield rep_q, self.order[idx]


_BRUTE_FORCE_PAIRS = 200_000     # query x point pairs below which _conflicts checks them all
_BRUTE_FORCE_TRIANGLE_PAIRS = 20_000     # sphere x triangle pairs below which hits does


def _conflicts(grid: _Grid, radii_pts: np.ndarray, q: np.ndarray, rq: np.ndarray,
               exclude_self: bool = False) -> np.ndarray:
    """Mask of queries overlapping any grid point (distance < (rq + r_point)(1 + clearance))."""
    bad = np.zeros(len(q), bool)
    if len(q) * len(grid.points) <= _BRUTE_FORCE_PAIRS:
        # a few candidates among a few hundred particles (a factory's every insertion): all
        # pairs in one array operation beat 27 cell offsets of tiny arrays
        if len(q) and len(grid.points):
            d = grid.delta(q[:, None, :], grid.points[None, :, :])
            reach = (rq[:, None] + radii_pts[None, :]) * (1.0 + _CLEAR)
            hit = np.einsum("ijk,ijk->ij", d, d) < reach * reach
            if exclude_self:
                m = min(len(q), len(grid.points))
                hit[np.arange(m), np.arange(m)] = False
            bad = hit.any(axis=1)
        return bad
    for qi, pj in grid.pairs(q):
        if exclude_self:
            keep = qi != pj
            qi, pj = qi[keep], pj[keep]
        d = grid.delta(q[qi], grid.points[pj])
        reach = (rq[qi] + radii_pts[pj]) * (1.0 + _CLEAR)
        hit = np.einsum("ij,ij->i", d, d) < reach * reach
        bad[qi[hit]] = True
    return bad


# --- body triangles ------------------------------------------------------------------------------

def _closest_sq_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Squared distance from points ``p`` to triangles ``abc`` (all (m, 3)), row by row:
    Ericson's closest-point Voronoi regions, with degenerate triangles as their three edges."""
    def dot(u, v):
        return np.einsum("ij,ij->i", u, v)

    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        # face interior (the fallback); then overwrite with edge and vertex regions
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        q = a + ab * v[:, None] + ac * w[:, None]
        # edge ab
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        t = d1 / np.where(m, d1 - d3, 1.0)
        q = np.where(m[:, None], a + ab * t[:, None], q)
        # edge ac
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        t = d2 / np.where(m, d2 - d6, 1.0)
        q = np.where(m[:, None], a + ac * t[:, None], q)
        # edge bc
        m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        t = (d4 - d3) / np.where(m, (d4 - d3) + (d5 - d6), 1.0)
        q = np.where(m[:, None], b + (c - b) * t[:, None], q)
        # vertices
        q = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)
        q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
        q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, q)
    e = p - q
    out = dot(e, e)
    n = np.cross(ab, ac)
    bad = ~np.isfinite(out) | (dot(n, n) <= 1e-24 * dot(ab, ab) * dot(ac, ac))
    if bad.any():                          # degenerate (zero-area) triangles: nearest edge
        i = np.nonzero(bad)[0]
        out[i] = np.minimum.reduce([_segment_sq_dist(p[i], u[i], v_[i])
                                    for u, v_ in ((a, b), (b, c), (c, a))])
    return out


def _segment_sq_dist(p, a, b):
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    t = np.einsum("ij,ij->i", p - a, d) / np.maximum(dd, 1e-300)
    t = np.clip(np.where(dd > 0, t, 0.0), 0.0, 1.0)
    e = p - (a + d * t[:, None])
    return np.einsum("ij,ij->i", e, e)


class _Triangles:
    """The scene's body triangles at t = 0 (with the periodic images that come within ``pad``
    of the domain), for sphere-overlap queries."""

    _CHUNK = 1 << 20                       # candidate cells / pairs handled at once

    def __init__(self, scene: Scene, pad: float, triangles: "np.ndarray | None" = None):
        """``triangles``: (T, 3, 3) m, instead of the scene's bodies at t = 0."""
        if triangles is not None:
            tri = np.asarray(triangles, float).reshape(-1, 3, 3)
        else:
            tris = [np.asarray(b.vertices, float)[np.asarray(b.faces, np.int64).reshape(-1, 3)]
                    for b in scene.bodies if len(b.faces)]
            tri = np.concatenate(tris) if tris else np.empty((0, 3, 3))
        dlo, dhi = np.asarray(scene.domain.min, float), np.asarray(scene.domain.max, float)
        for a, ax in enumerate("xyz"):
            if ax not in scene.domain.periodic or len(tri) == 0:
                continue
            L = dhi[a] - dlo[a]
            lo, hi = tri[:, :, a].min(axis=1), tri[:, :, a].max(axis=1)
            kmin = np.ceil((dlo[a] - pad - hi) / L).astype(np.int64)
            kmax = np.floor((dhi[a] + pad - lo) / L).astype(np.int64)
            n = np.maximum(kmax - kmin + 1, 0)
            idx = np.repeat(np.arange(len(tri)), n)
            k = np.repeat(kmin, n) + (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n))
            tri = tri[idx].copy()
            tri[:, :, a] += (k * L)[:, None]
        self.tri = tri
        self.lo = tri.min(axis=1) if len(tri) else np.empty((0, 3))
        self.hi = tri.max(axis=1) if len(tri) else np.empty((0, 3))
        nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]) if len(tri) else \
            np.empty((0, 3))
        ln = np.linalg.norm(nrm, axis=1, keepdims=True)
        self.normal = np.where(ln > 0, nrm / np.where(ln > 0, ln, 1.0), 0.0)
        self.degenerate = ln[:, 0] <= 0 if len(tri) else np.empty(0, bool)

    def __len__(self) -> int:
        return len(self.tri)

    def hits(self, p: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Mask of spheres (centres ``p``, radii ``r``) that come closer than their radius
        (with the wall clearance) to any triangle."""
        bad = np.zeros(len(p), bool)
        if len(self.tri) == 0 or len(p) == 0:
            return bad
        reach = float(r.max()) * (1.0 + _CLEAR)
        plo, phi = p.min(axis=0), p.max(axis=0)
        near = np.all((self.hi + reach >= plo) & (self.lo - reach <= phi), axis=1)
        tid = np.nonzero(near)[0]
        if len(tid) == 0:
            return bad
        if len(p) * len(tid) <= _BRUTE_FORCE_TRIANGLE_PAIRS:
            # a factory's few candidates near a few hundred triangles: every pair at once,
            # cheaper than binning them (the same filters and distance as below)
            pi = np.repeat(np.arange(len(p)), len(tid))
            tt = np.tile(tid, len(p))
            q = p[pi]
            lim = r[pi] * (1.0 + _CLEAR)
            m = np.all((q >= self.lo[tt] - lim[:, None]) & (q <= self.hi[tt] + lim[:, None]),
                       axis=1)
            pi, tt, q, lim = pi[m], tt[m], q[m], lim[m]
            if len(pi):
                d2 = _closest_sq_dist(q, self.tri[tt, 0], self.tri[tt, 1], self.tri[tt, 2])
                bad[pi[d2 < lim * lim]] = True
            return bad
        # point grid: about one point per cell, never finer than the sphere diameter
        span = np.maximum(phi - plo, 0.0)
        fine = 2.0 * reach
        vol = float(np.prod(np.maximum(span, fine)))
        h = max(fine, (vol / len(p)) ** (1.0 / 3.0))
        dims = np.floor(span / h).astype(np.int64) + 1
        while float(np.prod(dims.astype(float))) > 2.0 ** 60:
            h *= 2.0
            dims = np.floor(span / h).astype(np.int64) + 1
        cell = np.minimum(np.floor((p - plo) / h).astype(np.int64), dims - 1)
        keys = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
        order = np.argsort(keys, kind="stable")
        skeys = keys[order]
        # cells overlapped by each triangle's bounding box grown by the reach
        c0 = np.clip(np.floor((self.lo[tid] - reach - plo) / h).astype(np.int64), 0, dims - 1)
        c1 = np.clip(np.floor((self.hi[tid] + reach - plo) / h).astype(np.int64), 0, dims - 1)
        ext = c1 - c0 + 1
        ncell = ext.prod(axis=1)
        slack = reach + 0.5 * h * np.sqrt(3.0)
        csum = np.cumsum(ncell)
        start_t = 0
        while start_t < len(tid):
            # a chunk of triangles with at most _CHUNK cells between them (at least one)
            base = csum[start_t - 1] if start_t else 0
            stop_t = max(int(np.searchsorted(csum, base + self._CHUNK, "right")), start_t + 1)
            sel = np.arange(start_t, stop_t)
            start_t = stop_t
            cnt = ncell[sel]
            rep = np.repeat(sel, cnt)
            j = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            e = ext[rep]
            cz = j % e[:, 2]
            cy = (j // e[:, 2]) % e[:, 1]
            cx = j // (e[:, 2] * e[:, 1])
            cc = c0[rep] + np.stack([cx, cy, cz], axis=1)
            # keep cells whose centre lies within reach + half a cell diagonal of the plane
            t = tid[rep]
            centre = plo + (cc + 0.5) * h
            dist = np.abs(np.einsum("ij,ij->i", centre - self.tri[t, 0], self.normal[t]))
            keep = (dist <= slack) | self.degenerate[t]
            t, cc = t[keep], cc[keep]
            ck = (cc[:, 0] * dims[1] + cc[:, 1]) * dims[2] + cc[:, 2]
            s0 = np.searchsorted(skeys, ck, "left")
            n = np.searchsorted(skeys, ck, "right") - s0
            has = n > 0
            t, s0, n = t[has], s0[has], n[has]
            # expand to (point, triangle) pairs, in pieces of bounded size
            ncum = np.cumsum(n)
            a = 0
            while a < len(n):
                pbase = ncum[a - 1] if a else 0
                b = max(int(np.searchsorted(ncum, pbase + self._CHUNK, "right")), a + 1)
                nn = n[a:b]
                tt = np.repeat(t[a:b], nn)
                k = np.repeat(s0[a:b], nn) + (np.arange(int(nn.sum())) -
                                              np.repeat(np.cumsum(nn) - nn, nn))
                pi = order[k]
                live = ~bad[pi]
                pi, tt = pi[live], tt[live]
                a = b
                if len(pi) == 0:
                    continue
                # cheap filters first: the grown bounding box, then the plane distance
                q = p[pi]
                lim = r[pi] * (1.0 + _CLEAR)
                m = np.all((q >= self.lo[tt] - lim[:, None]) &
                           (q <= self.hi[tt] + lim[:, None]), axis=1)
                pi, tt, q, lim = pi[m], tt[m], q[m], lim[m]
                v0 = self.tri[tt, 0]
                m = (np.abs(np.einsum("ij,ij->i", q - v0, self.normal[tt])) < lim) | \
                    self.degenerate[tt]
                pi, tt, q, lim, v0 = pi[m], tt[m], q[m], lim[m], v0[m]
                if len(pi) == 0:
                    continue
                d2 = _closest_sq_dist(q, v0, self.tri[tt, 1], self.tri[tt, 2])
                bad[pi[d2 < lim * lim]] = True
        return bad


# --- regions and constraints ---------------------------------------------------------------------

def _frame(region: Region):
    """(origin, 3x3 rows = local axes) so that world = origin + local @ axes."""
    if region.kind == "box":
        return np.zeros(3), np.eye(3)
    a = np.asarray(region.axis_direction, float)
    a = a / np.linalg.norm(a)
    helper = np.eye(3)[int(np.argmin(np.abs(a)))]
    e1 = np.cross(a, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    return np.asarray(region.axis_point, float), np.stack([a, e1, e2])


def _local_bounds(region: Region):
    if region.kind == "box":
        return np.asarray(region.box_min, float), np.asarray(region.box_max, float)
    R = region.radius
    return np.array([0.0, -R, -R]), np.array([region.length, R, R])


def _inside_region(region: Region, local: np.ndarray, r: np.ndarray) -> np.ndarray:
    lo, hi = _local_bounds(region)
    rr = r[:, None]
    if region.kind == "box":
        return np.all((local - rr >= lo) & (local + rr <= hi), axis=1)
    u = local[:, 0]
    rad2 = local[:, 1] ** 2 + local[:, 2] ** 2
    room = region.radius - r
    return (u - r >= 0.0) & (u + r <= region.length) & (room >= 0.0) & (rad2 <= room * room)


def _region_volume(region: Region) -> float:
    lo, hi = _local_bounds(region)
    if region.kind == "box":
        return float(np.prod(hi - lo))
    return float(np.pi * region.radius ** 2 * region.length)


def _valid(scene: Scene, region: Region, world, r, grid, grid_r, tris=None):
    """Mask: sphere (world centre, radius r) inside region and domain, clear of walls, of body
    triangles and of earlier particles."""
    dlo, dhi = np.asarray(scene.domain.min), np.asarray(scene.domain.max)
    origin, axes = _frame(region)
    ok = _inside_region(region, (world - origin) @ axes.T, r)
    ok &= np.all((world - r[:, None] >= dlo) & (world + r[:, None] <= dhi), axis=1)
    for w in scene.walls:
        ok &= (world - np.asarray(w.point)) @ np.asarray(w.normal) >= r
    if tris is not None and len(tris) and ok.any():
        idx = np.nonzero(ok)[0]
        ok[idx[tris.hits(world[idx], r[idx])]] = False
    if grid is not None and ok.any():
        idx = np.nonzero(ok)[0]
        ok[idx[_conflicts(grid, grid_r, world[idx], r[idx])]] = False
    return ok


def _lattice(region: Region, spacing: float, margin: float, kind: str):
    """Lattice sites (local coordinates) with nearest-neighbour distance ``spacing``, centred in
    the region's local box shrunk by ``margin``. ``kind`` "fcc" returns the full grid of pitch
    spacing/sqrt(2) with a parity label (each parity is one FCC lattice); "sc" a simple cubic
    grid of pitch ``spacing`` (parity 0), better in regions only a layer or two thick."""
    lo, hi = _local_bounds(region)
    h = spacing / np.sqrt(2.0) if kind == "fcc" else spacing
    axes = []
    for a in range(3):
        span = hi[a] - lo[a] - 2.0 * margin
        if span < 0.0:
            return np.empty((0, 3)), np.empty(0, np.int64)
        n = int(np.floor(span / h + 1e-9)) + 1
        start = lo[a] + margin + 0.5 * (span - (n - 1) * h)
        axes.append((start + h * np.arange(n), np.arange(n)))
    gx, gy, gz = np.meshgrid(axes[0][0], axes[1][0], axes[2][0], indexing="ij")
    pts = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1)
    if kind == "fcc":
        ix, iy, iz = np.meshgrid(axes[0][1], axes[1][1], axes[2][1], indexing="ij")
        parity = ((ix + iy + iz) % 2).ravel()
    else:
        parity = np.zeros(len(pts), np.int64)
    if region.kind == "cylinder":
        room = region.radius - margin
        keep = pts[:, 1] ** 2 + pts[:, 2] ** 2 <= room * room
        pts, parity = pts[keep], parity[keep]
    return pts, parity


def _sites(scene: Scene, region: Region, spacing: float, r_max: float, grid, grid_r,
           tris=None):
    """Valid lattice sites (world coordinates) for spheres of radius <= r_max: the best of the
    two FCC sublattices and (for thin regions) a simple cubic lattice."""
    origin, axes = _frame(region)
    lo, hi = _local_bounds(region)
    margin = r_max * (1.0 + 1e-6)
    kinds = ["fcc"]
    if np.min(hi - lo - 2.0 * margin) < 3.0 * spacing:
        kinds.append("sc")
    best = np.empty((0, 3))
    for kind in kinds:
        local, parity = _lattice(region, spacing, margin, kind)
        if len(local) == 0:
            continue
        world = origin + local @ axes
        ok = _valid(scene, region, world, np.full(len(local), r_max), grid, grid_r, tris)
        for par in ((0, 1) if kind == "fcc" else (0,)):
            sel = world[ok & (parity == par)]
            sel = _drop_periodic_conflicts(scene, sel, spacing)
            if len(sel) > len(best):
                best = sel
    return best


def _drop_periodic_conflicts(scene: Scene, sites: np.ndarray, spacing: float) -> np.ndarray:
    """Remove sites whose periodic image comes closer than ``spacing`` to another site."""
    per = [ax in scene.domain.periodic for ax in "xyz"]
    if not any(per) or len(sites) < 2:
        return sites
    lo, hi = np.asarray(scene.domain.min), np.asarray(scene.domain.max)
    span = sites.max(axis=0) - sites.min(axis=0)
    if not any(p and span[a] + spacing > (hi[a] - lo[a]) * (1 - 1e-12)
               for a, p in enumerate(per)):
        return sites
    # only sites within one spacing of a periodic face can meet an image
    near = np.zeros(len(sites), bool)
    for a, p in enumerate(per):
        if p:
            near |= (sites[:, a] - lo[a] < spacing) | (hi[a] - sites[:, a] < spacing)
    idx = np.nonzero(near)[0]
    if len(idx) < 2:
        return sites
    sub = sites[idx]
    grid = _Grid(sub, spacing, lo, hi, per)
    drop = np.zeros(len(sub), bool)
    limit = (spacing * (1.0 - 1e-9)) ** 2
    for qi, pj in grid.pairs(sub):
        keep = qi < pj
        qi, pj = qi[keep], pj[keep]
        d = grid.delta(sub[qi], sub[pj])
        hit = np.einsum("ij,ij->i", d, d) < limit
        # drop the member of each conflicting pair nearer the upper faces
        qi, pj = qi[hit], pj[hit]
        upper = np.where(sub[qi].sum(axis=1) >= sub[pj].sum(axis=1), qi, pj)
        drop[upper] = True
    keep_mask = np.ones(len(sites), bool)
    keep_mask[idx[drop]] = False
    return sites[keep_mask]


# Peak host memory of placing a region fill, per particle: the lattice sites (about 4 per
# particle, local and world coordinates, parity, masks) and the jitter arrays. Measured with
# tracemalloc on a 100,000-sphere box fill: 968 bytes per particle.
PLACEMENT_BYTES_PER_PARTICLE = 1000


def placement_memory_problem(count: int):
    """Why placing ``count`` spheres would not fit in the machine's memory (a reason), or
    None; from the count alone, before anything is allocated."""
    from .memory import host_memory_bytes
    need = count * PLACEMENT_BYTES_PER_PARTICLE
    have = host_memory_bytes()
    if have and need > have:
        return (f"placing {count:,} spheres needs about {need / 2 ** 30:,.1f} GiB of memory "
                f"({PLACEMENT_BYTES_PER_PARTICLE} bytes each), more than the machine's "
                f"{have / 2 ** 30:,.1f} GiB; reduce count")
    return None


def _place_region_fill(scene: Scene, fill: ParticleFill, rng: np.random.Generator,
                       prev_pos: np.ndarray, prev_r: np.ndarray, tris=None):
    count = fill.count
    if count == 0:
        return np.empty((0, 3)), np.empty(0)
    problem = placement_memory_problem(count)
    if problem:
        raise SceneError(scene.source, f"{fill.key}.count", problem)
    region = fill.region
    r_max = fill.radius.largest
    radii = sample_radii(fill.radius, count, rng)
    base = 2.0 * r_max * (1.0 + GAP)
    dlo, dhi = np.asarray(scene.domain.min), np.asarray(scene.domain.max)
    per = [ax in scene.domain.periodic for ax in "xyz"]
    grid = None
    if len(prev_pos):
        grid = _Grid(prev_pos, r_max + float(prev_r.max()), dlo, dhi, per)

    # A coarser lattice for sparse fills keeps the site count near a few times `count`.
    target = 4 * count + 1000
    n_est = _region_volume(region) * np.sqrt(2.0) / base ** 3
    factor = max(1.0, (n_est / target) ** (1.0 / 3.0))
    while True:
        spacing = base * factor
        sites = _sites(scene, region, spacing, r_max, grid, prev_r, tris)
        if len(sites) >= count or factor == 1.0:
            break
        factor = max(1.0, factor / 2.0)
    if len(sites) < count:
        clear = ("walls, bodies and earlier particles" if tris is not None and len(tris)
                 else "walls and earlier particles")
        raise SceneError(
            scene.source, f"{fill.key}.count",
            f"cannot place {count} spheres: the region holds at most {len(sites)} spheres of "
            f"radius {r_max:g} m (on a lattice of spacing {base:g} m, clear of {clear}); "
            f"enlarge the region or reduce count")
    chosen = sites[rng.choice(len(sites), size=count, replace=False)]

    # jitter within the ball of radius spacing/2 around each site
    room = np.maximum(0.5 * spacing - radii, 0.0) * (1.0 - 1e-9)
    direction = rng.normal(size=(count, 3))
    direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-300)
    dist = room * rng.uniform(0.0, 1.0, count) ** (1.0 / 3.0)
    moved = _fold_back(scene, region, chosen + direction * dist[:, None], radii)
    # the fold-back never moves a sphere further from its site, but make sure
    disp = moved - chosen
    norm = np.linalg.norm(disp, axis=1)
    scale = np.where(norm > room, room / np.maximum(norm, 1e-300), 1.0)
    moved = chosen + disp * scale[:, None]
    ok = _valid(scene, region, moved, radii, grid, prev_r, tris)
    for _ in range(3):                      # halve the jitter of the few still invalid
        bad = np.nonzero(~ok)[0]
        if len(bad) == 0:
            break
        moved[bad] = 0.5 * (moved[bad] + chosen[bad])
        ok[bad] = _valid(scene, region, moved[bad], radii[bad], grid, prev_r, tris)
    pos = np.where(ok[:, None], moved, chosen)
    return pos, radii


def _reflect(x, lo, hi):
    """Mirror coordinates below ``lo`` / above ``hi`` back inside, then clip."""
    x = np.where(x < lo, 2.0 * lo - x, x)
    x = np.where(x > hi, 2.0 * hi - x, x)
    return np.clip(x, lo, hi)


def _fold_back(scene: Scene, region: Region, p: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Mirror jittered centres back across the region, domain and wall limits they crossed (so
    spheres near a boundary are not piled onto it); cylinders are projected radially."""
    origin, axes = _frame(region)
    local = (p - origin) @ axes.T
    rr = r[:, None]
    if region.kind == "box":
        lo, hi = _local_bounds(region)
        local = _reflect(local, lo + rr, hi - rr)
    else:
        local[:, 0] = _reflect(local[:, 0], r, region.length - r)
        rho = np.hypot(local[:, 1], local[:, 2])
        lim = np.maximum(region.radius - r, 0.0)
        f = np.where(rho > lim, lim / np.maximum(rho, 1e-300), 1.0)
        local[:, 1:] *= f[:, None]
    p = origin + local @ axes
    p = _reflect(p, np.asarray(scene.domain.min) + rr, np.asarray(scene.domain.max) - rr)
    for w in scene.walls:
        n = np.asarray(w.normal)
        below = r - (p - np.asarray(w.point)) @ n
        p = p + np.where(below > 0.0, 2.0 * below, 0.0)[:, None] * n
    return p


def place_fills(scene: Scene, rng: np.random.Generator) -> PlacedParticles:
    """Place every fill of ``scene``: file fills as given, count/region fills without overlap
    (with each other, walls, body meshes at t = 0 and periodic images).

    Raises :class:`SceneError` (key ``particles[i].count``) when a region cannot hold its count.
    """
    materials = tuple(sorted(scene.materials))
    mat_index = {m: i for i, m in enumerate(materials)}
    fills = scene.fills
    pos: list = [None] * len(fills)
    rad: list = [None] * len(fills)
    for i, f in enumerate(fills):
        if f.positions is not None:
            pos[i] = np.asarray(f.positions, float).reshape(-1, 3)
            rad[i] = np.asarray(f.radii, float).reshape(-1)
    prev_pos = [p for p in pos if p is not None]
    prev_r = [r for r in rad if r is not None]
    tris = None
    pad = max((f.radius.largest for f in fills if f.positions is None and f.count), default=0.0)
    if scene.bodies and pad > 0.0:
        tris = _Triangles(scene, 2.0 * pad)
    for i, f in enumerate(fills):
        if f.positions is not None:
            continue
        pp = np.concatenate(prev_pos) if prev_pos else np.empty((0, 3))
        pr = np.concatenate(prev_r) if prev_r else np.empty(0)
        pos[i], rad[i] = _place_region_fill(scene, f, rng, pp, pr, tris)
        prev_pos.append(pos[i])
        prev_r.append(rad[i])

    def per_fill(value_of, width, dtype):
        parts = [value_of(i, f, len(rad[i])) for i, f in enumerate(fills)]
        shape = (0, width) if width else (0,)
        return np.concatenate(parts).astype(dtype) if parts else np.empty(shape, dtype)

    def vel(i, f, n):
        if f.velocities is not None:
            return np.asarray(f.velocities, float).reshape(n, 3)
        return np.tile(np.asarray(f.velocity, float), (n, 1))

    def ang(i, f, n):
        if f.angular_velocities is not None:
            return np.asarray(f.angular_velocities, float).reshape(n, 3)
        return np.tile(np.asarray(f.angular_velocity, float), (n, 1))

    return PlacedParticles(
        position=per_fill(lambda i, f, n: pos[i], 3, np.float64),
        radius=per_fill(lambda i, f, n: rad[i], 0, np.float64),
        velocity=per_fill(vel, 3, np.float64),
        angular_velocity=per_fill(ang, 3, np.float64),
        fixed=per_fill(lambda i, f, n: np.full(n, f.fixed), 0, bool),
        material=per_fill(lambda i, f, n: np.full(n, mat_index[f.material]), 0, np.int32),
        fill=per_fill(lambda i, f, n: np.full(n, i), 0, np.int32),
        materials=materials,
    )
