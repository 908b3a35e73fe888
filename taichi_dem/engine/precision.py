"""Temperatures, moisture and positions that f32 can hold: compensated summation.

Positions (issue 31 item 6). Far from the origin the f32 spacing q of a position grows (4.8e-7
m at 4-8 m): a step v dt below q / 2 is rounded away, so a particle slower than q / (2 dt)
does not move until its velocity has grown past it, and a resting bed 6 m out jitters at
~q / dt (mm/s) instead of coming to rest. In an f32 scene whose domain reaches beyond
model.SPLIT_POSITIONS_BEYOND each position is split: the f32 ``position`` and an f32
``position_residual`` (what the position cannot hold, below half its spacing); the drift
adds v dt to the pair in f64 and splits the sum back, and the contacts read the residuals where a
difference of positions is taken - x_i - x_j of two near particles is exact in f32
(Sterbenz), so adding r_i - r_j makes it as precise as at the origin. Mesh contacts take the
particle relative to its body's pivot the same way.

Temperatures and moisture (issue 10 item 7).

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


def make_split_add(real):
    """ti.func (position, residual, step) -> (position', residual'): the f32 pair plus the
    step (vectors, m), summed in f64 and split back (the f64 sum cannot be re-associated
    away by fast math, as an f32 two-sum could)."""

    @ti.func
    def split_add(position, residual, step):
        total = (ti.cast(position, ti.f64) + ti.cast(residual, ti.f64)) + ti.cast(step, ti.f64)
        rounded = ti.cast(total, real)
        return rounded, ti.cast(total - ti.cast(rounded, ti.f64), real)

    return split_add
