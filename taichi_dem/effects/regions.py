"""Regions as compile-time tests: ``region_test(region)`` is a ti.func position (m) -> bool."""
import taichi as ti


def region_test(region):
    """A ti.func position -> bool: inside ``region`` (a scene Region), always True for None."""
    if region is None:
        @ti.func
        def inside(x):
            return True
        return inside
    if region.kind == "box":
        lo, hi = ti.Vector(list(region.box_min)), ti.Vector(list(region.box_max))

        @ti.func
        def inside(x):
            return (x >= lo).all() and (x <= hi).all()
        return inside
    p0, axis = ti.Vector(list(region.axis_point)), ti.Vector(list(region.axis_direction))
    length, r2 = region.length, region.radius ** 2

    @ti.func
    def inside(x):
        d = x - p0
        a = d.dot(axis)
        return a >= 0.0 and a <= length and (d - a * axis).norm_sqr() <= r2
    return inside
