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

Each stage's body is a ti.func per particle (or cell), so that one rebuild runs three ways
with the same lists bit for bit: as separate parallel kernels, in one serial launch (the
serial mode, fused_rebuild) and in one launch on the persistent workers (the parallel mode
on the CPU, rebuild_on_workers).
"""


import taichi as ti

from .grid import GridSpec  # noqa: F401 (re-exported)
from ..setup.memory import bucket
from .state import PairState, grown_capacity
from . import transfer
from ..setup.tuning import FUSED_AFTER_QUIET_REBUILDS, LIST_GROWTH, SETTLED_ENTRIES_PER_PARTICLE
from .workers import WORKER_TASK, make_barrier, worker_range



@ti.func
def exclusive_scan(counts: ti.template(), starts: ti.template(), n):
    """starts[k] = counts[0] + ... + counts[k-1] for k = 0..n. Serial and so deterministic; a
    serial scan over ~1e5 entries costs ~0.1 ms on a CPU (TAICHI_NOTES). Call it at the top
    level of a kernel."""
    ti.loop_config(serialize=True)
    for k in range(n + 1):
        if k == 0:
            starts[0] = 0
        else:
            starts[k] = starts[k - 1] + counts[k - 1]


@ti.func
def previous_entry(old_key: ti.template(), start, count, key):
    """Where a list entry was before the rebuild: the old row of its particle (``start``,
    ``count``) is searched for the partner ``key`` (a particle id or a triangle id). Returns
    the old entry's index, -1 for a new entry."""
    found = -1
    for m in range(start, start + count):
        if old_key[m] == key:
            found = m
            break
    return found


def _slot_moves(order, pairs, walls: int):
    """ti.funcs k -> (slot k of each field's shadow takes slot order[k] of the field; slot k
    of each field takes it back): a permutation's two halves for every (field, shadow) of
    ``pairs`` at once (a per-wall field: each of its ``walls`` columns)."""
    plain = [(f, sh) for f, sh in pairs if len(f.shape) == 1]
    per_wall = [(f, sh) for f, sh in pairs if len(f.shape) == 2]

    @ti.func
    def into_shadow(k):
        source = order[k]
        for q in ti.static(range(len(plain))):
            plain[q][1][k] = plain[q][0][source]
        for q in ti.static(range(len(per_wall))):
            for w in ti.static(range(walls)):
                per_wall[q][1][k, w] = per_wall[q][0][source, w]

    @ti.func
    def back(k):
        for q in ti.static(range(len(plain))):
            plain[q][0][k] = plain[q][1][k]
        for q in ti.static(range(len(per_wall))):
            for w in ti.static(range(walls)):
                per_wall[q][0][k, w] = per_wall[q][1][k, w]
    return into_shadow, back


class Broadphase:
    # candidate slots per particle to begin with; a longer row widens the scratch (to 1.5x
    # the longest) and the search runs again
    FIRST_SCRATCH_WIDTH = 32

    def __init__(self, engine):  # noqa: D107  (no postponed annotations here: Taichi reads them)
        self.e = engine
        self.grid = engine.model.grid
        t = self.tree = engine.new_tree()
        # (a bucket of cells: the count itself is read at run time, engine/values.py)
        self.cell_count = t.add("cell_count", ti.i32, self.grid.cell_capacity)
        self.cell_start = t.add("cell_start", ti.i32, self.grid.cell_capacity + 1)
        self.cell_fill = t.add("cell_fill", ti.i32, self.grid.cell_capacity)
        # [pair entries, alive particles, the longest row (rebuild_on_workers)]
        self.total = t.add("total", ti.i32, 3)
        t.finalize()
        self.rebuilds = 0
        # steps stepped on the current lists (Engine.rebuild resets it; the drivers rebuild
        # when it reaches Model.rebuild_within_steps)
        self.list_age = 0
        # the ti.func bodies of the rebuild's kernels, for the one-launch rebuild of the serial
        # mode (fused_rebuild: compiled on use, dropped whenever one of them is recompiled)
        self.bodies = {}
        # their bodies per particle (or cell), for the rebuild on the workers
        # (rebuild_on_workers: compiled on use, dropped with fused_rebuild)
        self.row_funcs = {}
        self.fused = None
        self.on_workers = None
        # rebuilds in a row since an array was reallocated (fused_rebuild waits for
        # FUSED_AFTER_QUIET_REBUILDS of them), and those run as separate kernels while waiting
        self.quiet_rebuilds = 0
        self.fused_waits = 0
        self.worker_stages = [0, 0]     # rebuilds on the workers that stopped SEARCHED, LISTED
        self.fused_stages = [0, 0, 0]     # fused rebuilds that stopped SEARCHED, LISTED, DONE
        self._compile_particle_kernels()

    # ------------------------------------------------------------------ kernels
    def _compile_particle_kernels(self):
        s = self.e.state
        g = self.grid
        n_cells_of = g.layout_funcs()[5]
        cell_count, cell_start, cell_fill, total = self.cell_count, self.cell_start, self.cell_fill, self.total
        n_walls = s.n_walls
        cell_of = g.make_cell_of()[1]

        @ti.func
        def save_row(i):
            pid = s.particle_id[i]
            s.old_row_start_by_id[pid] = s.row_start[i]
            s.old_row_count_by_id[pid] = s.row_owned[i]

        @ti.func
        def save_rows_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                save_row(i)

        @ti.kernel
        def save_rows(n: ti.i32, serial_loops: ti.template()):
            save_rows_body(n, serial_loops)

        @ti.func
        def clear_cell(c):
            cell_count[c] = 0
            cell_fill[c] = 0

        @ti.func
        def bin_particle(i):
            """Particle i's cell, counted (an atomic add: particles of a cell bin at once)."""
            # dead particles (left the domain) sort to the end and are dropped
            c = n_cells_of()
            if s.alive[i] != 0:
                c = cell_of(s.position[i])
                cell_count[c] += 1
            s.cell[i] = c

        @ti.func
        def put_in_cell_order(n):
            """The cells' starts, the alive count and each particle's new slot ``order``;
            serial, so that the order within a cell - and so every result - is the same on
            any number of threads. Call it at a kernel's top level or on one worker."""
            n_cells = n_cells_of()
            exclusive_scan(cell_count, cell_start, n_cells)
            total[1] = cell_start[n_cells]
            ti.loop_config(serialize=True)
            for i in range(n):
                c = s.cell[i]
                if c < n_cells:
                    slot = cell_start[c] + cell_fill[c]
                    cell_fill[c] += 1
                    s.order[slot] = i

        @ti.func
        def sort_by_cell_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for c in range(n_cells_of()):
                clear_cell(c)
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                bin_particle(i)
            put_in_cell_order(n)

        @ti.kernel
        def sort_by_cell(n: ti.i32, serial_loops: ti.template()):
            sort_by_cell_body(n, serial_loops)

        @ti.func
        def settle(k):
            """Slot k after the moves: its cell, and the position its travel is measured from."""
            s.cell[k] = cell_of(s.position[k])
            s.reference_position[k] = s.position[k]

        # new slot k takes old particle order[k]; every per-particle array moves together,
        # through its own shadow: all of them into the shadows in one loop, back in another
        # (not reference_position, which settle sets)
        into_shadows, back = _slot_moves(s.order, s.reorder_pairs(), n_walls)

        @ti.func
        def permute_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for k in range(n):
                into_shadows(k)
            ti.loop_config(serialize=serial_loops)
            for k in range(n):
                back(k)
                settle(k)

        @ti.kernel
        def permute(n: ti.i32, serial_loops: ti.template()):
            permute_body(n, serial_loops)

        serial = self.e.serial_switch
        self._save_rows, self._sort_by_cell, self._permute = (
            serial(save_rows), serial(sort_by_cell), serial(permute))
        self.bodies.update(save_rows=save_rows_body, sort_by_cell=sort_by_cell_body,
                           permute=permute_body)
        self.row_funcs.update(save_row=save_row, clear_cell=clear_cell, bin_particle=bin_particle,
                              put_in_cell_order=put_in_cell_order,
                              moves=(into_shadows, back), settle=settle)
        self.drop_one_launch_rebuilds()
        self._compile_search(self.FIRST_SCRATCH_WIDTH)

    def _compile_search(self, width: int):
        """(Re)allocate the candidate scratch (``width`` per particle) and compile the search:
        for each particle, the partners in the 27 surrounding cells (9 runs of 3 along z where z
        is not periodic) within the cutoff
        r_i + r_j + skin (minimum image on periodic axes), in one pass. Rows longer than
        ``width`` are counted but not stored; the driver then widens the scratch and repeats."""
        if getattr(self, "scratch_tree", None) is not None:
            self.scratch_tree.destroy()
        self.scratch_width = width
        t = self.scratch_tree = self.e.new_tree()
        # one column more than the width: the slot past a full row, where the search writes
        # the particles it tests after the row is full (see candidate)
        scratch = self.scratch = t.add("candidate", ti.i32, (self.e.state.capacity, width + 1))
        t.finalize()
        s = self.e.state
        g = self.grid
        dims_of = g.layout_funcs()[4]
        skin_of = self.e.skin_of
        cell_start = self.cell_start
        total = self.total
        # two fixed particles are listed only when a pair effect conducts heat between them
        fixed_pairs = self.e.model.pair_heat
        margin = self.e.model.pair_margin

        minimum_image = g.make_minimum_image()
        cell_coordinates = g.make_cell_of()[0]

        # cells are numbered z fastest, so the three cells of a stencil column along z (not
        # periodic, or the wrap would break the run) are one run of cell-sorted particles:
        # 9 runs per particle instead of 27 cells, in the same order
        z_runs = not g.periodic[2]

        @ti.func
        def candidate(i, j, xi, ri, movable_i, count):
            """Particle j as a candidate partner of i: stored in i's scratch row when within
            the cutoff. Returns the row's new count."""
            # two fixed particles exert no forces (LAMMPS: neigh_modify exclude); they are
            # listed only when they conduct heat
            d = minimum_image(xi - s.position[j])
            rj = s.radius[j]
            cutoff = ri + rj + skin_of()
            if ti.static(margin > 0.0):
                cutoff += ti.static(margin) * ti.max(ri, rj)
            listed = (d.dot(d) < cutoff * cutoff) & (j != i)
            if ti.static(not fixed_pairs):
                listed = listed & (movable_i | (s.inverse_mass[j] > 0.0))
            # without branches: j is written at the row's next slot whether listed or not (an
            # unlisted j is overwritten by the next one, or lies past the row's end; past a
            # full row, in the spare column), and the count grows by the test's outcome. About
            # one test in six lists its particle, at random: a branch on it mispredicted a few
            # times per particle, ~15 cycles each, and the search ran 2x slower
            scratch[i, ti.min(count, width)] = j
            count += ti.cast(listed, ti.i32)
            return count

        @ti.func
        def neighbour_cell(k: ti.template(), coordinate, step):
            """The stencil's cell coordinate along axis k, wrapped on a periodic axis, and
            whether it is searched."""
            dims = dims_of()
            nb = coordinate + step
            inside = True
            if ti.static(g.periodic[k]):
                # a thin periodic axis of one or two cells: -1 and +1 (and 0) wrap onto the
                # same cell, which must be searched only once
                if ti.static(g.dims[k] == 2):
                    if step < 0:
                        inside = False
                elif ti.static(g.dims[k] == 1):
                    if step != 0:
                        inside = False
                # the wrap by a compare, not a modulo: an integer division costs tens of
                # cycles, and the search did ~20 of them per particle
                if nb < 0:
                    nb += dims[k]
                elif nb >= dims[k]:
                    nb -= dims[k]
            elif nb < 0 or nb >= dims[k]:
                inside = False
            return nb, inside

        @ti.func
        def search_row(i):
            """Particle i's candidate partners into its scratch row; returns (and stores in
            row_count) their number, which may exceed the scratch's width."""
            xi, ri, movable_i = s.position[i], s.radius[i], s.inverse_mass[i] > 0.0
            # the cell's coordinates from the position, as the sort found them (the same
            # arithmetic on the same position), rather than by dividing its number
            cell = cell_coordinates(xi)
            dims = dims_of()
            cx, cy, cz = cell[0], cell[1], cell[2]
            count = 0
            # the stencil unrolled, x outer and y inner (the order of the rows): each
            # neighbour coordinate is found once per particle
            if ti.static(z_runs):
                z_first = ti.max(cz - 1, 0)
                z_last = ti.min(cz + 1, dims[2] - 1)
                for step_x in ti.static((-1, 0, 1)):
                    nx, inside_x = neighbour_cell(0, cx, step_x)
                    for step_y in ti.static((-1, 0, 1)):
                        ny, inside_y = neighbour_cell(1, cy, step_y)
                        if inside_x and inside_y:
                            column = (nx * dims[1] + ny) * dims[2]
                            for j in range(cell_start[column + z_first],
                                           cell_start[column + z_last + 1]):
                                count = candidate(i, j, xi, ri, movable_i, count)
            else:
                # z periodic: the 27 cells in a loop, in the same order (x outer, z inner);
                # unrolled, the 27 copies of the search took 2.4 s to compile (against 0.7 s
                # for the 9 runs above), and the search runs only at rebuilds
                for offset in range(27):
                    nx, inside_x = neighbour_cell(0, cx, offset // 9 - 1)
                    ny, inside_y = neighbour_cell(1, cy, (offset // 3) % 3 - 1)
                    nz, inside_z = neighbour_cell(2, cz, offset % 3 - 1)
                    if inside_x and inside_y and inside_z:
                        nc = (nx * dims[1] + ny) * dims[2] + nz
                        for j in range(cell_start[nc], cell_start[nc + 1]):
                            count = candidate(i, j, xi, ri, movable_i, count)
            s.row_count[i] = count
            return count

        @ti.func
        def start_rows(n):
            """The rows' starts and the entries they hold (serial: at a kernel's top level or
            on one worker)."""
            exclusive_scan(s.row_count, s.row_start, n)
            total[0] = s.row_start[n]

        @ti.func
        def find_candidates_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                search_row(i)
            longest = 0
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                ti.atomic_max(longest, s.row_count[i])
            start_rows(n)
            return longest

        @ti.kernel
        def find_candidates(n: ti.i32, serial_loops: ti.template()) -> ti.i32:
            return find_candidates_body(n, serial_loops)

        self._find_candidates = self.e.serial_switch(find_candidates)
        self.bodies["find_candidates"] = find_candidates_body
        self.row_funcs.update(search_row=search_row, start_rows=start_rows)
        self.drop_one_launch_rebuilds()

    def _make_compact(self, pairs: "PairState"):
        """Kernel copying the scratch rows into the CSR list, owned pairs (partner id larger)
        at the front of each row, the others at the back."""
        s = self.e.state
        p = pairs
        scratch_field = lambda: self.scratch  # noqa: E731  (the scratch may be reallocated)
        scratch = scratch_field()

        @ti.func
        def compact_row(i):
            front = s.row_start[i]
            back = s.row_start[i] + s.row_count[i] - 1
            pid = s.particle_id[i]
            for c in range(s.row_count[i]):
                j = scratch[i, c]
                # without a branch (owned or not is a coin toss: a branch on it would
                # mispredict half the time)
                owned = ti.cast(pid < s.particle_id[j], ti.i32)
                p.neighbour[ti.select(owned, front, back)] = j
                front += owned
                back -= 1 - owned
            s.row_owned[i] = front - s.row_start[i]

        @ti.func
        def compact_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                compact_row(i)

        @ti.kernel
        def compact(n: ti.i32, serial_loops: ti.template()):
            compact_body(n, serial_loops)
        self.bodies["compact"] = compact_body
        self.row_funcs["compact_row"] = compact_row
        self.drop_one_launch_rebuilds()
        return self.e.serial_switch(compact)

    def compile_pair_kernels(self, pairs: PairState):
        """Kernels that touch the pair arrays; rebuilt whenever those are reallocated."""
        s = self.e.state
        p = pairs
        # the state each contact carries (declared by the effects), with its previous copy
        carried = [(getattr(p, n), getattr(p, "old_" + n)) for n in p.contact_field_names]
        self._compact = self._make_compact(p)

        @ti.func
        def save_pair_row(i):
            for k in range(s.row_start[i], s.row_start[i] + s.row_owned[i]):
                p.old_partner_id[k] = s.particle_id[p.neighbour[k]]
                p.old_contact[k] = p.contact[k]
                for f in ti.static(carried):
                    f[1][k] = f[0][k]

        @ti.func
        def save_pairs_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                save_pair_row(i)

        @ti.kernel
        def save_pairs(n: ti.i32, serial_loops: ti.template()):
            save_pairs_body(n, serial_loops)

        @ti.func
        def link_row(i):
            """Row i's entries: the owned ones carry their pair's state from the old row,
            the others find their mirror in the partner's owned part."""
            pid = s.particle_id[i]
            old_start = s.old_row_start_by_id[pid]
            old_count = s.old_row_count_by_id[pid]
            owned_end = s.row_start[i] + s.row_owned[i]
            for k in range(s.row_start[i], owned_end):
                # owned: carry the state of this pair if it existed before the rebuild
                p.mirror[k] = -1
                old = previous_entry(p.old_partner_id, old_start, old_count,
                                     s.particle_id[p.neighbour[k]])
                if old >= 0:
                    p.contact[k] = p.old_contact[old]
                    for f in ti.static(carried):
                        f[0][k] = f[1][old]
                else:
                    p.contact[k] = ti.u8(0)
                    for f in ti.static(carried):
                        f[0][k] = ti.Vector([0.0, 0.0, 0.0])
            for k in range(owned_end, s.row_start[i] + s.row_count[i]):
                # not owned: the owner's entry of the same pair lies in j's owned part
                j = p.neighbour[k]
                p.mirror[k] = -1
                for m in range(s.row_start[j], s.row_start[j] + s.row_owned[j]):
                    if p.neighbour[m] == i:
                        p.mirror[k] = m
                        break

        @ti.func
        def link_and_carry_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                link_row(i)

        @ti.kernel
        def link_and_carry(n: ti.i32, serial_loops: ti.template()):
            link_and_carry_body(n, serial_loops)

        self._save_pairs = self.e.serial_switch(save_pairs)
        self._link_and_carry = self.e.serial_switch(link_and_carry)
        self.bodies.update(save_pairs=save_pairs_body, link_and_carry=link_and_carry_body)
        self.row_funcs.update(save_pair_row=save_pair_row, link_row=link_row)
        self.drop_one_launch_rebuilds()

    # ------------------------------------------------------------------ driver
    @property
    def entries(self) -> int:
        """Neighbour entries listed at the last rebuild (read from the device when asked:
        the one-launch rebuild does not hand it back)."""
        return int(self.total[0])

    @entries.setter
    def entries(self, value: int):
        """(Checkpoints restore it; the restored ``total`` field already holds it.)"""

    # stages the one-launch rebuild reached (fused_rebuild)
    SEARCHED, LISTED, DONE = 1, 2, 3

    def _compile_fused(self):
        """One serial launch for a whole rebuild: the serial mode's answer to a rebuild of ~20
        launches and field reads (~1 ms of host time on these machines, several steps of a
        small scene). The same ti.func bodies as the separate kernels, in the same order;
        where an array is too small it stops and says at which stage (the host then grows
        the array and finishes with the separate kernels, every stage being repeatable)."""
        e = self.e
        b = self.bodies
        mesh = e.mesh
        has_mesh = mesh is not None
        save_rows, save_pairs, sort_by_cell, permute, find_candidates, compact, link_and_carry = (
            b[k] for k in ("save_rows", "save_pairs", "sort_by_cell", "permute",
                           "find_candidates", "compact", "link_and_carry"))
        width, pair_capacity = self.scratch_width, e.pairs.capacity
        total = self.total
        flush_loads = mesh_save_rows = count_bins = fill_bins = mesh_find = compact_and_carry = None
        set_frames = mesh_start = None
        items_capacity = mesh_width = entries_capacity = 0
        if has_mesh:
            mb = mesh.bodies
            flush_loads, mesh_save_rows, count_bins, fill_bins, mesh_find, compact_and_carry = (
                mb[k] for k in ("flush_loads", "save_rows", "count_bins", "fill_bins",
                                "find_candidates", "compact_and_carry"))
            set_frames, mesh_start = mesh.frames.set_frames, mesh.mesh_start
            items_capacity, mesh_width = mesh.items_capacity, mesh.scratch_width
            entries_capacity = mesh.entries_capacity
        SEARCHED, LISTED, DONE = self.SEARCHED, self.LISTED, self.DONE

        @ti.kernel
        def fused_rebuild(n: ti.i32, time: e.model.real) -> ti.types.vector(2, ti.i32):
            """rebuild(n) at ``time`` (s, the bodies' pose) on one thread; returns (alive
            particles, the stage reached)."""
            save_rows(n, True)
            save_pairs(n, True)
            if ti.static(has_mesh):
                flush_loads(n, True)
                mesh_save_rows(n, True)
            sort_by_cell(n, True)
            alive = total[1]
            permute(n, True)
            longest = find_candidates(alive, True)
            stage = SEARCHED
            if longest <= width and total[0] <= pair_capacity:
                compact(alive, True)
                link_and_carry(alive, True)
                stage = LISTED
                if ti.static(has_mesh):
                    set_frames(time)
                    if count_bins(True) <= items_capacity:
                        fill_bins(True)
                        mesh_longest = mesh_find(alive, True)
                        if mesh_longest <= mesh_width and mesh_start[alive] <= entries_capacity:
                            compact_and_carry(alive, True)
                            stage = DONE
                if ti.static(not has_mesh):
                    stage = DONE
            return ti.Vector([alive, stage])

        self.fused = fused_rebuild

    def drop_one_launch_rebuilds(self):
        """Forget the one-launch rebuilds (fused_rebuild, rebuild_on_workers): a body they
        inline was recompiled (a field reallocated); they compile again on their next use."""
        self.drop_fused_rebuild()
        self.on_workers = None

    def drop_fused_rebuild(self):
        """Forget fused_rebuild (a body it inlines was recompiled), and wait again for
        FUSED_AFTER_QUIET_REBUILDS rebuilds without a reallocation before compiling it."""
        self.fused = None
        self.quiet_rebuilds = 0

    # the barrier's stall threshold for the rebuild's waits, whose stall flags are not used
    # (a rebuild is one launch between runs of steps; those runs judge the stalls)
    REBUILD_STALL_SPINS = 1 << 30

    def _compile_on_workers(self):
        """The parallel mode's rebuild in one launch on the engine's persistent workers
        (engine/workers.py): the parallel kernels' stages in their order, each worker a
        contiguous share of the particles (or cells), a barrier between stages where the
        parallel kernels have a launch or a loop - ~30 of them, each ~40 - 100 us on
        Taichi's thread pool here, against ~0.2 us for a barrier - and one worker on the
        serial parts (the scans and the placing in cell order, beside which the others save
        the old rows). Every row is found as the kernels find it, so the lists are theirs
        bit for bit. Where an array is too small it stops after the search (SEARCHED), as
        fused_rebuild does."""
        e = self.e
        f = self.row_funcs
        save_row, save_pair_row, clear_cell, bin_particle, put_in_cell_order, moves, settle = (
            f[k] for k in ("save_row", "save_pair_row", "clear_cell", "bin_particle",
                           "put_in_cell_order", "moves", "settle"))
        search_row, start_rows, compact_row, link_row = (
            f[k] for k in ("search_row", "start_rows", "compact_row", "link_row"))
        workers = e.workers
        arrivals = e.worker_pool.arrivals
        barrier = make_barrier(arrivals, workers)
        n_cells_of = self.grid.layout_funcs()[5]
        total = self.total
        width, pair_capacity = self.scratch_width, e.pairs.capacity
        stall_spins = self.REBUILD_STALL_SPINS
        SEARCHED, LISTED = self.SEARCHED, self.LISTED

        @ti.func
        def meet(arrived):
            """Arrive at the barrier after the ``arrived``-th and wait for every worker;
            returns its number."""
            barrier(arrived + 1, stall_spins)
            return arrived + 1

        @ti.kernel
        def rebuild_on_workers(n: ti.i32) -> ti.types.vector(2, ti.i32):
            """rebuild(n) on the workers; returns (alive particles, the stage reached)."""
            arrivals[0] = 0
            arrivals[1] = 0
            total[2] = 0
            for task in range(workers * WORKER_TASK):
                if task % WORKER_TASK == 0:
                    w = task // WORKER_TASK
                    arrived = 0
                    first, last = worker_range(n, w, workers)
                    # (1) the particles sorted by cell (while worker 0 places them in cell
                    # order, the others save the old rows by particle id, with their pairs'
                    # state: both read the arrays before they move)
                    cells_first, cells_last = worker_range(n_cells_of(), w, workers)
                    for c in range(cells_first, cells_last):
                        clear_cell(c)
                    arrived = meet(arrived)
                    for i in range(first, last):
                        bin_particle(i)
                    arrived = meet(arrived)
                    if w == 0:
                        put_in_cell_order(n)
                    else:
                        saved_first, saved_last = worker_range(n, w - 1, workers - 1)
                        for i in range(saved_first, saved_last):
                            save_row(i)
                            save_pair_row(i)
                    arrived = meet(arrived)
                    # (2) every array moved into that order
                    for k in range(first, last):
                        moves[0](k)             # into the shadows
                    arrived = meet(arrived)
                    for k in range(first, last):
                        moves[1](k)             # back
                        settle(k)
                    arrived = meet(arrived)
                    # (3) the rows: search, their starts, the lists with their history
                    alive = total[1]
                    first, last = worker_range(alive, w, workers)
                    longest = 0
                    for i in range(first, last):
                        longest = ti.max(longest, search_row(i))
                    ti.atomic_max(total[2], longest)
                    arrived = meet(arrived)
                    if w == 0:
                        start_rows(alive)
                    arrived = meet(arrived)
                    if total[2] <= width and total[0] <= pair_capacity:
                        for i in range(first, last):
                            compact_row(i)
                        # (link_row reads the partners' owned entries)
                        arrived = meet(arrived)
                        for i in range(first, last):
                            link_row(i)
            stage = SEARCHED
            if total[2] <= width and total[0] <= pair_capacity:
                stage = LISTED
            return ti.Vector([total[1], stage])

        self.on_workers = rebuild_on_workers

    def rebuild(self, n: int) -> int:
        """Re-sort particles and rebuild the neighbour list; returns the alive count. In the
        serial mode one launch (fused_rebuild) unless an array must grow."""
        e = self.e
        self.quiet_rebuilds += 1
        if e.pairs is not None and e.serial and e.fused_rebuilds and (
                self.fused is not None or self.quiet_rebuilds > FUSED_AFTER_QUIET_REBUILDS):
            if self.fused is None:
                self._compile_fused()
            alive, stage = (int(v) for v in self.fused(n, e.time))
            self.fused_stages[stage - 1] += 1
            if stage == self.SEARCHED:
                self._list(alive)
            elif stage == self.LISTED:
                if e.mesh.rebuild_rows(alive, e.time):
                    e.recompile_pair_kernels()
            elif e.mesh is not None:
                e.mesh.binned_time = e.time
            self.rebuilds += 1
            return alive
        if e.pairs is not None and e.workers and not e.serial and e.rebuilds_on_workers:
            return self._rebuild_on_workers(n)
        if e.pairs is not None and e.serial and e.fused_rebuilds:
            self.fused_waits += 1
        if e.pairs is not None:
            self._save_rows(n)
            self._save_pairs(n)
            if e.mesh is not None:
                e.mesh.save_rows(n)
        else:
            transfer.zero([e.state.old_row_count_by_id]
                          + ([e.mesh.old_count_by_id] if e.mesh is not None else []))
        self._sort_by_cell(n)
        alive = int(self.total[1])
        self._permute(n)
        self._list(alive)
        self.rebuilds += 1
        return alive

    def _rebuild_on_workers(self, n: int) -> int:
        """rebuild(n) in the parallel mode on the engine's workers: one launch
        (rebuild_on_workers) for the particles' lists, the kernels for the mesh rows and
        wherever an array must grow."""
        e = self.e
        if e.mesh is not None:
            e.mesh.save_rows(n)
        if self.on_workers is None:
            self._compile_on_workers()
        alive, stage = (int(v) for v in self.on_workers(n))
        self.worker_stages[stage - 1] += 1
        if stage == self.SEARCHED:
            self._list(alive)          # grows what is too small, searches again, lists
        elif e.mesh is not None and e.mesh.rebuild_rows(alive, e.time):
            e.recompile_pair_kernels()
        self.rebuilds += 1
        return alive

    def _list(self, alive: int):
        """The neighbour rows of the ``alive`` particles, sorted and permuted (and the mesh
        candidate rows): search, grow what is too small, compact, carry the history."""
        e = self.e
        longest = int(self._find_candidates(alive))
        if longest > self.scratch_width:
            self._compile_search(bucket(int(longest * LIST_GROWTH) + 1, floor=16))
            if e.pairs is not None:
                self._compact = self._make_compact(e.pairs)
            longest = int(self._find_candidates(alive))
        entries = int(self.total[0])
        if e.pairs is None or entries > e.pairs.capacity:
            # the first list has room for every slot settled (the count of the fill does not
            # set its size, so a scene with a few particles more or less shares its kernels)
            settled_for = e.state.capacity if e.pairs is None else alive
            e.grow_pairs(grown_capacity(entries, alive, e.state.capacity, 1024,
                                        settled_per_particle=SETTLED_ENTRIES_PER_PARTICLE
                                        * settled_for / max(alive, 1)))
        self._compact(alive)
        self._link_and_carry(alive)
        if e.mesh is not None and e.mesh.rebuild_rows(alive, e.time):
            e.recompile_pair_kernels()     # the mesh entry arrays were reallocated
