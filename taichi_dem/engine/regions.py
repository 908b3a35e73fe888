"""Regions as tests in the kernels: ``region_test(region, values, name)`` is a ti.func position
(m) -> bool. With ``values`` (engine/values.py RuntimeValues) the region's corners, axis and
size are read at run time under ``name``, so a moved outlet or radiation region compiles
nothing; without, they are compiled in."""
import taichi as ti

from .values import reader


def region_test(region, values=None, name: str = "region"):
    """A ti.func position -> bool: inside ``region`` (a scene Region: a box, or a finite
    cylinder from its axis point along its unit axis), always True for None."""
    if region is None:
        @ti.func
        def anywhere(x):
            return True
        return anywhere
    if region.kind == "box":
        lo_of = reader(values, name + "_min", tuple(region.box_min))
        hi_of = reader(values, name + "_max", tuple(region.box_max))

        @ti.func
        def inside_box(x):
            lo, hi = lo_of(), hi_of()
            return (x[0] >= lo[0] and x[0] <= hi[0] and x[1] >= lo[1] and x[1] <= hi[1]
                    and x[2] >= lo[2] and x[2] <= hi[2])
        return inside_box
    p0_of = reader(values, name + "_axis_point", tuple(region.axis_point))
    axis_of = reader(values, name + "_axis", tuple(region.axis_direction))
    length_of = reader(values, name + "_length", region.length)
    radius_sq_of = reader(values, name + "_radius_squared", region.radius ** 2)

    @ti.func
    def inside_cylinder(x):
        d = x - p0_of()
        axis = axis_of()
        u = d.dot(axis)
        radial = d - u * axis
        return u >= 0.0 and u <= length_of() and radial.dot(radial) <= radius_sq_of()
    return inside_cylinder
