"""Contact detection: a uniform cell grid built by counting sort, particles kept in cell order,
and a full neighbour list (CSR) with a Verlet skin, rebuilt only when some particle has moved
more than half the skin since the last rebuild.

At every rebuild: (1) remember each particle's old neighbour row by particle id, with the
partners' ids and the contact history; (2) sort particles by cell (serial scatter, so the
order is deterministic) and permute every per-particle array into that order - on a CPU the
memory order decides the speed; (3) count, prefix-sum and fill the neighbour rows; (4) find
each entry's mirror (the owner's entry of the same pair); (5) carry the tangential history of
pairs that persist from the old rows into the new ones. The owner of a pair is the particle
with the smaller id, which no reorder changes, so the history stays with its pair.
"""

import math

import numpy as np
import taichi as ti

from .state import PairState

MAX_CELLS_PER_PARTICLE = 8      # a sparse domain gets coarser cells instead of millions of empty ones
MIN_CELLS = 4096


class GridSpec:
    """Cell layout over the domain: cell size >= the largest pair cutoff (2 R_max + skin);
    periodic axes are tiled exactly by a whole number of cells."""

    def __init__(self, lo, hi, periodic: tuple[str, ...], cutoff: float, capacity: int):
        self.lo = np.asarray(lo, float)
        self.hi = np.asarray(hi, float)
        span = self.hi - self.lo
        self.periodic = tuple(int(a in periodic) for a in "xyz")
        size = cutoff
        while True:
            dims = []
            for k in range(3):
                n = int(math.floor(span[k] / size)) if self.periodic[k] else int(math.ceil(span[k] / size))
                dims.append(max(n, 1))
            if np.prod(dims, dtype=np.int64) <= max(MIN_CELLS, MAX_CELLS_PER_PARTICLE * capacity):
                break
            size *= 1.25           # a huge, sparse domain: coarser cells, still correct
        self.dims = tuple(dims)
        self.cell_size = tuple(float(span[k] / dims[k]) if self.periodic[k] else size
                               for k in range(3))
        self.span = tuple(float(s) for s in span)
        self.n_cells = int(np.prod(self.dims))

    def too_small_periodic_axes(self) -> list[str]:
        return [a for k, a in enumerate("xyz") if self.periodic[k] and self.dims[k] < 3]


class Broadphase:
    def __init__(self, engine):  # noqa: D107  (no postponed annotations here: Taichi reads them)
        self.e = engine
        self.grid = engine.grid
        t = self.tree = engine.new_tree()
        self.cell_count = t.add("cell_count", ti.i32, self.grid.n_cells)
        self.cell_start = t.add("cell_start", ti.i32, self.grid.n_cells + 1)
        self.cell_fill = t.add("cell_fill", ti.i32, self.grid.n_cells)
        self.total = t.add("total", ti.i32, 2)    # [pair entries, alive particles]
        t.finalize()
        self.rebuilds = 0
        self._compile_particle_kernels()

    # ------------------------------------------------------------------ kernels
    def _compile_particle_kernels(self):
        s = self.e.state
        g = self.grid
        lo = ti.Vector(list(g.lo))
        inv_cell = ti.Vector([1.0 / c for c in g.cell_size])
        dims = ti.Vector(list(g.dims))
        n_cells = g.n_cells
        cell_count, cell_start, cell_fill, total = self.cell_count, self.cell_start, self.cell_fill, self.total
        vec_fields, real_fields, int_fields, wall_fields = s.reorder_groups()
        n_walls = s.n_walls

        @ti.func
        def cell_of(p):
            c = ti.cast(ti.floor((p - lo) * inv_cell), ti.i32)
            c = ti.max(ti.min(c, dims - 1), 0)
            return (c[0] * dims[1] + c[1]) * dims[2] + c[2]

        @ti.kernel
        def save_rows(n: ti.i32):
            for i in range(n):
                pid = s.particle_id[i]
                s.old_row_start_by_id[pid] = s.row_start[i]
                s.old_row_count_by_id[pid] = s.row_count[i]

        @ti.kernel
        def sort_by_cell(n: ti.i32):
            for c in range(n_cells):
                cell_count[c] = 0
                cell_fill[c] = 0
            for i in range(n):
                # dead particles (left the domain) sort to the end and are dropped
                c = n_cells
                if s.alive[i] != 0:
                    c = cell_of(s.position[i])
                    cell_count[c] += 1
                s.cell[i] = c
            ti.loop_config(serialize=True)
            for c in range(n_cells + 1):
                if c == 0:
                    cell_start[0] = 0
                else:
                    cell_start[c] = cell_start[c - 1] + cell_count[c - 1]
            total[1] = cell_start[n_cells]
            ti.loop_config(serialize=True)
            for i in range(n):
                c = s.cell[i]
                if c < n_cells:
                    slot = cell_start[c] + cell_fill[c]
                    cell_fill[c] += 1
                    s.order[slot] = i

        @ti.kernel
        def permute(n: ti.i32):
            # new slot k takes old particle order[k]; every per-particle array moves together
            for f in ti.static(vec_fields):
                for k in range(n):
                    s.shadow_vec[k] = f[s.order[k]]
                for k in range(n):
                    f[k] = s.shadow_vec[k]
            for f in ti.static(real_fields):
                for k in range(n):
                    s.shadow_real[k] = f[s.order[k]]
                for k in range(n):
                    f[k] = s.shadow_real[k]
            for f in ti.static(int_fields):
                for k in range(n):
                    s.shadow_int[k] = f[s.order[k]]
                for k in range(n):
                    f[k] = s.shadow_int[k]
            for f in ti.static(wall_fields):
                for w in ti.static(range(n_walls)):
                    for k in range(n):
                        s.shadow_vec[k] = f[s.order[k], w]
                    for k in range(n):
                        f[k, w] = s.shadow_vec[k]
            for k in range(n):
                s.cell[k] = cell_of(s.position[k])
                s.reference_position[k] = s.position[k]

        self._save_rows, self._sort_by_cell, self._permute = save_rows, sort_by_cell, permute
        self._count_rows = self._make_neighbour_loop(count_only=True)

    def _make_neighbour_loop(self, count_only: bool, pairs: "PairState | None" = None):
        """Kernel visiting, for each particle, the candidates in the 27 surrounding cells that
        lie within the cutoff r_i + r_j + skin (minimum image on periodic axes)."""
        s = self.e.state
        g = self.grid
        dims = ti.Vector(list(g.dims))
        span = ti.Vector(list(g.span))
        skin = self.e.skin
        cell_start = self.cell_start

        @ti.func
        def minimum_image(d):
            for k in ti.static(range(3)):
                if ti.static(g.periodic[k]):
                    d[k] -= span[k] * ti.round(d[k] / span[k])
            return d

        @ti.func
        def is_candidate(i, j):
            ok = False
            if j != i and (s.inverse_mass[i] > 0.0 or s.inverse_mass[j] > 0.0):
                d = minimum_image(s.position[i] - s.position[j])
                cutoff = s.radius[i] + s.radius[j] + skin
                ok = d.dot(d) < cutoff * cutoff
            return ok

        if count_only:
            @ti.kernel
            def count_rows(n: ti.i32) -> ti.i32:
                for i in range(n):
                    c = s.cell[i]
                    cz = c % dims[2]
                    cy = (c // dims[2]) % dims[1]
                    cx = c // (dims[1] * dims[2])
                    cnt = 0
                    for offset in range(27):
                        nb = ti.Vector([cx + offset // 9 - 1, cy + (offset // 3) % 3 - 1, cz + offset % 3 - 1])
                        inside = True
                        for k in ti.static(range(3)):
                            if ti.static(g.periodic[k]):
                                nb[k] = (nb[k] + dims[k]) % dims[k]
                            elif nb[k] < 0 or nb[k] >= dims[k]:
                                inside = False
                        if inside:
                            nc = (nb[0] * dims[1] + nb[1]) * dims[2] + nb[2]
                            for j in range(cell_start[nc], cell_start[nc + 1]):
                                if is_candidate(i, j):
                                    cnt += 1
                    s.row_count[i] = cnt
                ti.loop_config(serialize=True)
                for i in range(n + 1):
                    if i == 0:
                        s.row_start[0] = 0
                    else:
                        s.row_start[i] = s.row_start[i - 1] + s.row_count[i - 1]
                return s.row_start[n]
            return count_rows

        p = pairs

        @ti.kernel
        def fill_rows(n: ti.i32):
            for i in range(n):
                c = s.cell[i]
                cz = c % dims[2]
                cy = (c // dims[2]) % dims[1]
                cx = c // (dims[1] * dims[2])
                slot = s.row_start[i]
                for offset in range(27):
                    nb = ti.Vector([cx + offset // 9 - 1, cy + (offset // 3) % 3 - 1, cz + offset % 3 - 1])
                    inside = True
                    for k in ti.static(range(3)):
                        if ti.static(g.periodic[k]):
                            nb[k] = (nb[k] + dims[k]) % dims[k]
                        elif nb[k] < 0 or nb[k] >= dims[k]:
                            inside = False
                    if inside:
                        nc = (nb[0] * dims[1] + nb[1]) * dims[2] + nb[2]
                        for j in range(cell_start[nc], cell_start[nc + 1]):
                            if is_candidate(i, j):
                                p.neighbour[slot] = j
                                slot += 1
        return fill_rows

    def compile_pair_kernels(self, pairs: PairState):
        """Kernels that touch the pair arrays; rebuilt whenever those are reallocated."""
        s = self.e.state
        p = pairs
        rolling_history = p.rolling_history is not None
        self._fill_rows = self._make_neighbour_loop(count_only=False, pairs=p)

        @ti.kernel
        def save_pairs(n: ti.i32):
            for i in range(n):
                for k in range(s.row_start[i], s.row_start[i] + s.row_count[i]):
                    p.old_partner_id[k] = s.particle_id[p.neighbour[k]]
                    p.old_tangential_history[k] = p.tangential_history[k]
                    if ti.static(rolling_history):
                        p.old_rolling_history[k] = p.rolling_history[k]

        @ti.kernel
        def link_and_carry(n: ti.i32):
            for i in range(n):
                pid = s.particle_id[i]
                old_start = s.old_row_start_by_id[pid]
                old_count = s.old_row_count_by_id[pid]
                for k in range(s.row_start[i], s.row_start[i] + s.row_count[i]):
                    j = p.neighbour[k]
                    partner = s.particle_id[j]
                    if pid < partner:
                        # owner: carry the history of this pair if it existed before
                        p.mirror[k] = -1
                        history = ti.Vector([0.0, 0.0, 0.0])
                        rolling = ti.Vector([0.0, 0.0, 0.0])
                        for m in range(old_start, old_start + old_count):
                            if p.old_partner_id[m] == partner:
                                history = p.old_tangential_history[m]
                                if ti.static(rolling_history):
                                    rolling = p.old_rolling_history[m]
                                break
                        p.tangential_history[k] = history
                        if ti.static(rolling_history):
                            p.rolling_history[k] = rolling
                    else:
                        # the owner's entry of the same pair lies in j's row
                        p.mirror[k] = -1
                        for m in range(s.row_start[j], s.row_start[j] + s.row_count[j]):
                            if p.neighbour[m] == i:
                                p.mirror[k] = m
                                break

        self._save_pairs, self._link_and_carry = save_pairs, link_and_carry

    # ------------------------------------------------------------------ driver
    def rebuild(self, n: int) -> int:
        """Re-sort particles and rebuild the neighbour list; returns the alive count."""
        e = self.e
        if e.pairs is not None:
            self._save_rows(n)
            self._save_pairs(n)
        else:
            e.state.old_row_count_by_id.fill(0)
        self._sort_by_cell(n)
        alive = int(self.total[1])
        self._permute(n)
        entries = int(self._count_rows(alive))
        if e.pairs is None or entries > e.pairs.capacity:
            e.grow_pairs(max(int(entries * 1.5), 1024))
        self._fill_rows(alive)
        self._link_and_carry(alive)
        self.rebuilds += 1
        self.entries = entries
        return alive
