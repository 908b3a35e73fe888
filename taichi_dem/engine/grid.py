"""The cell grid over the domain, and the one place cells are numbered and stepped across
periodic faces (``GridSpec``): the neighbour search (broadphase.py) and the effects that
keep their own cells (a voidage per cell, coarser blocks of cells) all use it."""
import math

import numpy as np
import taichi as ti

MAX_CELLS_PER_PARTICLE = 8      # a sparse domain gets coarser cells instead of millions of empty ones
MIN_CELLS = 4096


class GridSpec:
    """Cell layout over the domain: cell size >= the largest pair cutoff (2 R_max + skin);
    periodic axes are tiled exactly by a whole number of cells."""

    def __init__(self, lo, hi, periodic: tuple[str, ...], cutoff: float, capacity: int,
                 least_cutoff: float | None = None):
        """``cutoff`` (m): the largest pair cutoff, the cells' least size; ``capacity``: the
        particle slots; ``least_cutoff`` (m): the smallest cutoff a scene of this kind could
        have (the skin is set by the time step), which sizes the cell arrays (see below)."""
        self.lo = np.asarray(lo, float)
        self.hi = np.asarray(hi, float)
        span = self.hi - self.lo
        self.periodic = tuple(int(a in periodic) for a in "xyz")
        most_cells = max(MIN_CELLS, MAX_CELLS_PER_PARTICLE * capacity)
        size = cutoff
        coarsened = False
        while True:
            dims = self._dims(span, size)
            if np.prod(dims, dtype=np.int64) <= most_cells:
                break
            size *= 1.25           # a huge, sparse domain: coarser cells, still correct
            coarsened = True
        self.dims = tuple(dims)
        self.cell_size = tuple(float(span[k] / dims[k]) if self.periodic[k] else size
                               for k in range(3))
        self.span = tuple(float(s) for s in span)
        self.n_cells = int(np.prod(self.dims))
        # the cell arrays' length: a bucket (engine/values.py), so that domains of a few cells
        # more or less share their kernels
        from .values import bucket
        from ..setup.tuning import MIN_CELL_SLOTS
        self.cell_capacity = max(bucket(self.n_cells), MIN_CELL_SLOTS)
        # the smallest cutoff (m): what other arrays binned by cell are sized for
        self.least_cutoff = min(cutoff, least_cutoff or cutoff)
        if least_cutoff is not None and least_cutoff < cutoff:
            # room for the cells of the smallest cutoff too: the skin follows the time step
            # (setup/timestep.py), so a 6x smaller dt made 10,000 cells of the main demo's
            # 4,332 and compiled every kernel again; the loops run to the cells in use (read
            # at run time), so the room costs memory only (a few ints a cell)
            least = int(np.prod(self._dims(span, least_cutoff), dtype=np.int64))
            self.cell_capacity = max(self.cell_capacity, bucket(min(least, most_cells)))
        if coarsened:
            # the count itself set the cells: room for what any count of its bucket could set
            self.cell_capacity = max(self.cell_capacity, bucket(
                max(MIN_CELLS, MAX_CELLS_PER_PARTICLE * bucket(capacity))))
        self.values = None

    def _dims(self, span, size: float) -> list[int]:
        """Cells per axis of cells at least ``size`` (m) wide: periodic axes tiled exactly."""
        dims = []
        for k in range(3):
            n = (int(math.floor(span[k] / size)) if self.periodic[k]
                 else int(math.ceil(span[k] / size)))
            dims.append(max(n, 1))
        return dims

    def bind(self, values) -> None:
        """Read the layout at run time from ``values`` (engine/values.py RuntimeValues): the
        ti.funcs made from here on close over slots, not numbers (what stays compiled in: the
        periodic axes). Unbound, they compile the numbers in."""
        self.values = values
        # written now, while no other field tree is being built (a write launches a kernel,
        # which Taichi refuses while a FieldsBuilder is open: an effect's allocate asks for
        # the layout while its own tree is)
        self.layout_funcs()

    def _read(self, name: str, value, integer: bool = False):
        """A ti.func () -> ``value`` (values.reader: at run time once bound)."""
        from .values import reader
        return reader(self.values, "grid_" + name, value, integer)

    def layout_funcs(self):
        """ti.funcs () -> lo, hi, span (m), the inverse cell size (1/m), the cells per axis
        and the cell count, read at run time once bound (``bind``)."""
        return (self._read("lo", tuple(float(x) for x in self.lo)),
                self._read("hi", tuple(float(x) for x in self.hi)),
                self._read("span", self.span),
                self._read("inverse_cell", tuple(1.0 / c for c in self.cell_size)),
                self._read("dims", tuple(int(d) for d in self.dims), integer=True),
                self._read("n_cells", int(self.n_cells), integer=True))

    def make_cell_arithmetic(self, dims=None):
        """The one place cells are numbered (z fastest) and stepped across periodic faces:
        ti.funcs ``number(v)`` (integer coordinates -> the cell's number), ``coordinates(c)``
        (number -> coordinates) and ``neighbour(v, offset)`` (offset 0..26 of the 3 x 3 x 3
        block around v -> (the neighbour's number, inside: 0 beyond a closed face), wrapped
        on periodic axes). ``dims``: cells per axis of a coarser grid over the same domain
        and periodic axes (an effect's blocks of cells), default this grid's. (The neighbour search
        unrolls its own stencil, with thin periodic axes handled: Broadphase.)"""
        if dims is None:
            dims_of = self.layout_funcs()[4]
        else:       # another grid's (an effect's blocks): compiled in
            fixed = ti.Vector([int(x) for x in dims])

            @ti.func
            def dims_of():
                return fixed
        periodic = self.periodic

        @ti.func
        def number(v):
            d = dims_of()
            return (v[0] * d[1] + v[1]) * d[2] + v[2]

        @ti.func
        def coordinates(c):
            d = dims_of()
            return ti.Vector([c // (d[1] * d[2]), (c // d[2]) % d[1], c % d[2]])

        @ti.func
        def neighbour(v, offset):
            d = dims_of()
            nb = v + ti.Vector([offset // 9 - 1, (offset // 3) % 3 - 1, offset % 3 - 1])
            inside = True
            for k in ti.static(range(3)):
                if ti.static(periodic[k]):
                    # one step at most: the wrap by a compare, as (nb + d) % d
                    if nb[k] < 0:
                        nb[k] += d[k]
                    elif nb[k] >= d[k]:
                        nb[k] -= d[k]
                elif nb[k] < 0 or nb[k] >= d[k]:
                    inside = False
            return number(nb), inside

        return number, coordinates, neighbour

    def make_cell_of(self):
        """ti.funcs position (m) -> the cell's integer coordinates (a vector), and position ->
        the cell's number (z fastest). Positions outside the grid go to its border cells."""
        lo_of, _, _, inv_cell_of, dims_of, _ = self.layout_funcs()
        number, _, _ = self.make_cell_arithmetic()

        @ti.func
        def cell_coordinates(p):
            c = ti.cast(ti.floor((p - lo_of()) * inv_cell_of()), ti.i32)
            return ti.max(ti.min(c, dims_of() - 1), 0)

        @ti.func
        def cell_of(p):
            return number(cell_coordinates(p))
        return cell_coordinates, cell_of

    def make_minimum_image(self):
        """ti.func d -> the shortest periodic image of the separation vector d (m)."""
        periodic = self.periodic
        span_of = self.layout_funcs()[2]

        @ti.func
        def minimum_image(d):
            span = span_of()
            for k in ti.static(range(3)):
                if ti.static(periodic[k]):
                    # positions are wrapped into the box, so one period at most separates images
                    if d[k] > 0.5 * span[k]:
                        d[k] -= span[k]
                    elif d[k] < -0.5 * span[k]:
                        d[k] += span[k]
            return d
        return minimum_image

    def too_small_periodic_axes(self, cutoff: float) -> list[str]:
        """Periodic axes shorter than two interaction reaches (m): there a particle could meet two
        images of one partner, and the minimum image is no longer the only one in reach."""
        return [a for k, a in enumerate("xyz") if self.periodic[k] and self.span[k] < 2.0 * cutoff]
