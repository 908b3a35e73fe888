"""Bulk copies between fields and host arrays: one kernel for a whole set of fields.

``field.to_numpy()`` and ``field.from_numpy()`` compile one Taichi kernel per field (the field
is a template argument), ~20-50 ms each even from the kernel cache; a simulation reads and
writes ~100 fields once (tables, the first particles, a checkpoint, the particles' readout),
which made these copies 20-37 % of a small test's compilation (BENCHMARKS.md "Stop 23").
Here one kernel copies every field of a set through one flat f64 array: f32, f64, i32 and u8
values are all exact in f64, so the copies are bit for bit those of to_numpy/from_numpy.
"""
# (no postponed annotations: Taichi reads the kernels' annotations)

import math

import numpy as np
import taichi as ti

from . import backend

# field dtypes whose every value an f64 holds exactly, with the numpy dtype to_numpy gives
_NUMPY_DTYPE = {ti.f32: np.float32, ti.f64: np.float64, ti.i32: np.int32, ti.u8: np.uint8,
                ti.i8: np.int8, ti.i16: np.int16, ti.u16: np.uint16, ti.u32: np.uint32}
_kernels: dict = {}      # (direction, runtime generation, field ids) -> (kernel, layout, fields)


class _Layout:
    """Where each field's values sit in the flat f64 array: offset, shape (the field's shape,
    then its components for a vector field), numpy dtype."""

    def __init__(self, fields):
        self.entries = []
        offset = 0
        for f in fields:
            components = getattr(f, "n", None) if hasattr(f, "m") else None
            shape = tuple(f.shape) + ((components,) if components else ())
            self.entries.append((offset, shape, _NUMPY_DTYPE[f.dtype]))
            offset += math.prod(shape)
        self.size = max(offset, 1)


def host_shape(field) -> tuple:
    """The shape of ``field.to_numpy()`` (the field's shape, then its components if a
    vector), without copying."""
    return _Layout([field]).entries[0][1]


def _supported(fields) -> bool:
    return all(f.dtype in _NUMPY_DTYPE and (not hasattr(f, "m") or f.m == 1) for f in fields)


def _compile(direction: str, fields):
    """The copy kernel of ``fields`` and its layout: one loop over the largest field's
    elements, copying element t of every field that has one (each loop is a task that Taichi
    compiles and loads from its cache on its own, ~5 ms each warm: one loop per distinct
    field shape made a set of mixed shapes cost several)."""
    layout = _Layout(fields)
    offsets = [o for o, _, _ in layout.entries]
    components = [getattr(f, "n", 0) if hasattr(f, "m") else 0 for f in fields]
    dtypes = [f.dtype for f in fields]
    shapes = [tuple(f.shape) for f in fields]
    sizes = [math.prod(shape) for shape in shapes]
    largest = max(sizes)
    # element t of a field of this shape: its index along each axis (row-major, as numpy)
    strides = [tuple(math.prod(shape[d + 1:]) for d in range(len(shape))) for shape in shapes]
    reading = direction in ("read", "take")
    zeroing = direction == "zero"
    taking = direction == "take"            # read, then zero

    axes = [len(shape) for shape in shapes]

    @ti.func
    def index_of(k: ti.template(), t):
        """Element t of field k: t itself, or its index along each axis (row-major)."""
        if ti.static(axes[k] == 1):
            return t
        else:
            I = ti.Vector([0] * axes[k])
            for d in ti.static(range(axes[k])):
                I[d] = (t // strides[k][d]) % shapes[k][d]
            return I

    @ti.kernel
    def copy(flat: ti.types.ndarray(dtype=ti.f64, ndim=1)):
        for t in range(largest):
            for k in ti.static(range(len(fields))):
                # (a field smaller than the largest: only its own elements)
                if ti.static(sizes[k] == largest) or t < sizes[k]:
                    I = index_of(k, t)
                    if ti.static(components[k]):
                        for c in ti.static(range(components[k])):
                            if ti.static(reading):
                                flat[offsets[k] + t * components[k] + c] = ti.cast(
                                    fields[k][I][c], ti.f64)
                                if ti.static(taking):
                                    fields[k][I][c] = ti.cast(0, dtypes[k])
                            elif ti.static(zeroing):
                                fields[k][I][c] = ti.cast(0, dtypes[k])
                            else:
                                fields[k][I][c] = ti.cast(flat[offsets[k] + t * components[k] + c],
                                                          dtypes[k])
                    elif ti.static(reading):
                        flat[offsets[k] + t] = ti.cast(fields[k][I], ti.f64)
                        if ti.static(taking):
                            fields[k][I] = ti.cast(0, dtypes[k])
                    elif ti.static(zeroing):
                        fields[k][I] = ti.cast(0, dtypes[k])
                    else:
                        fields[k][I] = ti.cast(flat[offsets[k] + t], dtypes[k])
    return copy, layout


def _kernel(direction: str, fields):
    generation = backend.generation()
    key = (direction, generation, tuple(id(f) for f in fields))
    if key not in _kernels:
        # kernels of an earlier runtime, or many of destroyed fields (grown arrays, closed
        # simulations): forget them (the field objects held here keep their ids from reuse)
        if len(_kernels) > 256 or any(k[1] != generation for k in _kernels):
            _kernels.clear()
        _kernels[key] = (*_compile(direction, fields), list(fields))
    kernel, layout, _ = _kernels[key]
    return kernel, layout


def read(fields, direction: str = "read") -> list[np.ndarray]:
    """Host copies of ``fields``, each as ``field.to_numpy()`` gives it (same shape, dtype
    and values), by one kernel for the whole set."""
    fields = list(fields)
    if not fields:
        return []
    if not _supported(fields):
        out = [f.to_numpy() for f in fields]
        if direction == "take":
            for f in fields:
                f.fill(0)
        return out
    kernel, layout = _kernel(direction, fields)
    flat = np.zeros(layout.size, np.float64)
    kernel(flat)
    return [flat[o:o + math.prod(shape)].reshape(shape).astype(dtype)
            for o, shape, dtype in layout.entries]


def take(fields) -> list[np.ndarray]:
    """``read(fields)`` and then ``zero(fields)`` (sums emptied as they are sampled), by one
    kernel for the whole set."""
    return read(fields, "take")


def write(pairs) -> None:
    """``field.from_numpy(array)`` for each (field, array) of ``pairs``, by one kernel for the
    whole set: the array is cast to the field's dtype on the host first, as from_numpy does.
    An array of another shape than the field's raises ValueError."""
    pairs = list(pairs)
    if not pairs:
        return
    fields = [f for f, _ in pairs]
    if not _supported(fields):
        for f, a in pairs:
            f.from_numpy(a)
        return
    kernel, layout = _kernel("write", fields)
    flat = np.zeros(layout.size, np.float64)
    for (o, shape, dtype), (f, a) in zip(layout.entries, pairs):
        a = np.asarray(a)
        if a.shape != shape:
            raise ValueError(f"array of shape {a.shape} for a field of shape {shape}")
        flat[o:o + a.size] = a.astype(dtype).reshape(-1)
    kernel(flat)


def zero(fields) -> None:
    """``field.fill(0)`` for each of ``fields``, by one kernel for the whole set (``fill``
    compiles one per field)."""
    fields = list(fields)
    if not fields:
        return
    if not _supported(fields):
        for f in fields:
            f.fill(0)
        return
    kernel, _ = _kernel("zero", fields)
    kernel(np.zeros(1, np.float64))
