"""Temperatures and moisture that f32 can hold (issue 10 item 7): compensated summation.

The spacing of f32 at 723 K is 6.1e-5 K; an update T += dt Q/(m c) of ~1e-6 K per step, as in a
cooler, is rounded away and heat is lost or made. In f32 scenes every particle carries an f64
residual beside its f32 temperature (and moisture): the value is the sum, increments are added
in f64 (compensated summation) and split back, so the f32 part stays within half a spacing of
the value and the residual below it. Fluxes are computed from the f32 part (an error of at most
3e-5 K against temperature differences of kelvins); energy sums use the value.
"""
import taichi as ti


def make_compensated_add(real):
    """ti.func (value, residual, increment) -> (value', residual'): value + residual +
    increment in f64, split into ``real`` (the field's precision) and the f64 rest."""

    @ti.func
    def compensated_add(value, residual, increment):
        total = ti.cast(value, ti.f64) + residual + ti.cast(increment, ti.f64)
        rounded = ti.cast(total, real)
        return rounded, total - ti.cast(rounded, ti.f64)

    @ti.func
    def split(total):
        """An f64 value as (``real`` part, f64 residual)."""
        rounded = ti.cast(total, real)
        return rounded, total - ti.cast(rounded, ti.f64)

    return compensated_add, split
