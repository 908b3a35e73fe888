"""Scene values the kernels read at run time instead of compiling them in (issue 45 item 1).

Taichi 1.7 keys its compiled-kernel cache on the kernel's IR. A number a kernel closes over
(``g = ti.Vector([0, 0, -9.81])``) is a constant in that IR, so two scenes that differ only
in gravity, the domain, the cell size or the skin compiled every kernel that read them again
(~1-2 s a scene: bench/jit_probe.py). Here such numbers live in two small device arrays, one
real and one integer, in slots numbered in the order the kernels' builders ask for them: the
IR holds the slot number, the array the value, and a scene with only its values changed
reads its kernels from the cache.

What still specialises a kernel - the kind of scene - is what is ``ti.static``: the enabled
effects, the precision, which axes are periodic, a periodic axis only one or two cells long
(the neighbour stencil is unrolled for it), the materials' count (the pair tables' shape), the
number of plane walls and bodies, and the capacity buckets (``bucket``) of the particle,
cell and triangle arrays. docs/architecture.md "What compiles" lists them.

``values.vector(name, v)`` and ``values.scalar(name, x)`` (and ``integer``/``integers``)
return a ti.func that reads the value; the same name gets the same slot (the value is
written again, so a rebuilt kernel reads the current one).
"""
from __future__ import annotations

import math

import taichi as ti

from ..setup.memory import bucket  # noqa: F401  (the capacity buckets: the kernels' shapes)

# room for the values of one simulation: the dryer demo uses 75 reals; each outlet adds 6 and
# each mass-flow plane 13, so a scene with a dozen sensors needs a few hundred (asked for more,
# it says so). 1,024 reals are 8 KiB.
REAL_SLOTS = 1024
INT_SLOTS = 256


class RuntimeValues:
    """Named scene values in device arrays (module docstring); ``tree`` a FieldTree of its own,
    made before any other of the simulation's, so the arrays' place never moves."""

    def __init__(self, tree, real):
        self.tree = tree
        self.reals = tree.add("runtime_reals", real, REAL_SLOTS)
        self.ints = tree.add("runtime_ints", ti.i32, INT_SLOTS)
        tree.finalize()
        self._real_slots: dict[str, tuple[int, int]] = {}
        self._int_slots: dict[str, tuple[int, int]] = {}

    def _slots(self, table: dict, size: int, name: str, width: int) -> int:
        if name in table:
            start, w = table[name]
            if w != width:
                raise ValueError(f"runtime value {name!r} asked for with {width} components, "
                                 f"first with {w}")
            return start
        start = sum(w for _, w in table.values())
        if start + width > size:
            raise RuntimeError(f"more runtime values than the {size} slots of "
                               "engine/values.py: raise REAL_SLOTS/INT_SLOTS")
        table[name] = (start, width)
        return start

    def _read(self, name: str, values: list, integer: bool):
        """A ti.func () -> ``values`` (one: a scalar; three: a vector) from their slots."""
        if not integer:
            values = [float(v) for v in values]
            if not all(math.isfinite(v) for v in values):
                raise ValueError(f"runtime value {name!r} is not finite: {values}")
        else:
            values = [int(v) for v in values]
        f = self.ints if integer else self.reals
        k = self._slots(self._int_slots if integer else self._real_slots,
                        INT_SLOTS if integer else REAL_SLOTS, name, len(values))
        for offset, v in enumerate(values):
            f[k + offset] = v
        if len(values) == 3:
            @ti.func
            def read_vector():
                return ti.Vector([f[k], f[k + 1], f[k + 2]])
            return read_vector

        @ti.func
        def read():
            return f[k]
        return read

    def vector(self, name: str, value):
        """A ti.func () -> the 3-vector ``value`` (real) read at run time."""
        return self._read(name, list(value), False)

    def scalar(self, name: str, value):
        """A ti.func () -> the real ``value`` read at run time."""
        return self._read(name, [value], False)

    def integers(self, name: str, value):
        """A ti.func () -> the integer 3-vector ``value`` read at run time."""
        return self._read(name, list(value), True)

    def integer(self, name: str, value):
        """A ti.func () -> the integer ``value`` read at run time."""
        return self._read(name, [value], True)


def reader(values, name: str, value, integer: bool = False):
    """A ti.func () -> ``value`` (a number, or a 3-tuple a vector): read at run time from
    ``values`` (a RuntimeValues) under ``name``, or compiled in when ``values`` is None."""
    vector = isinstance(value, (tuple, list))
    if values is None:
        if vector:
            constant = ti.Vector([int(x) if integer else float(x) for x in value])
        else:
            constant = int(value) if integer else float(value)

        @ti.func
        def read():
            return constant
        return read
    if vector:
        return (values.integers if integer else values.vector)(name, tuple(value))
    return (values.integer if integer else values.scalar)(name, value)
