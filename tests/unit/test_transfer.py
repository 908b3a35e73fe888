"""engine/transfer.py: one kernel copies a set of fields to and from the host, with the values,
shapes and dtypes of to_numpy/from_numpy bit for bit."""
import numpy as np
import pytest
import taichi as ti

import taichi_dem as td
from taichi_dem.engine import transfer
from taichi_dem.engine.state import FieldTree


def test_bulk_copies_equal_the_per_field_copies(small_scene_text):
    rng = np.random.default_rng(7)
    with td.Simulation.from_text(small_scene_text()):       # (a live runtime)
        tree = FieldTree()
        fields = [tree.add("a", ti.f32, 11), tree.add("b", ti.f64, 11, vector=True),
                  tree.add("c", ti.i32, (4, 5)), tree.add("d", ti.u8, 7),
                  tree.add("e", ti.f32, (11, 2), vector=True), tree.add("f", ti.f64, 11)]
        tree.finalize()
        try:
            values = [rng.normal(size=11), rng.normal(size=(11, 3)),
                      rng.integers(-2**31, 2**31 - 1, (4, 5)), rng.integers(0, 256, 7),
                      rng.normal(size=(11, 2, 3)), rng.normal(size=11) * 1e300]
            transfer.write(zip(fields, values))
            bulk = transfer.read(fields)
            for f, v, got in zip(fields, values, bulk):
                expected = f.to_numpy()
                assert got.dtype == expected.dtype and got.shape == expected.shape
                assert np.array_equal(got, expected)
                # as from_numpy would have stored them (f64 -> f32 rounded to nearest)
                assert np.array_equal(expected, np.asarray(v).astype(expected.dtype))
                assert transfer.host_shape(f) == expected.shape
            with pytest.raises(ValueError, match="shape"):
                transfer.write([(fields[0], np.zeros(10))])
            # zero: every element of every field of the set (fill(0) on each), none outside it
            transfer.zero(fields[:5])
            for f in fields[:5]:
                assert not f.to_numpy().any(), f
            assert np.array_equal(fields[5].to_numpy(), np.asarray(values[5]))
        finally:
            tree.destroy()


def test_take_reads_then_leaves_zero(small_scene_text):
    """transfer.take: the values read gives, and every element zero afterwards, fields of
    different shapes in one set (the sums a sample empties)."""
    with td.Simulation.from_text(small_scene_text()):       # (a live runtime)
        tree = FieldTree()
        fields = [tree.add("a", ti.f32, 5), tree.add("b", ti.i32, (3, 4)),
                  tree.add("c", ti.f64, 2, vector=True)]
        tree.finalize()
        try:
            values = [np.arange(5.0) + 0.5, np.arange(12).reshape(3, 4) - 6,
                      np.array([[1.0, -2.0, 3.0], [4.0, 5.0, -6.0]])]
            transfer.write(zip(fields, values))
            taken = transfer.take(fields)
            for got, v in zip(taken, values):
                assert np.array_equal(got, v)
            for f in fields:
                assert not f.to_numpy().any(), f
        finally:
            tree.destroy()

