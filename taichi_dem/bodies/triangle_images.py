"""The periodic image of a particle nearest a triangle (bodies/mesh_contacts.py): a body's
triangle may be longer than half a periodic slice, and then the minimum image of one vertex is
not the image that touches it."""
import taichi as ti

from ..effects.mesh_contact import closest_point_on_triangle
from ..engine.values import reader


def make_triangle_image(grid, reach: float):
    """ti.func ``triangle_image(x, a, b, c)`` -> the periodic image of point x (m) nearest to
    the triangle abc (world frame, m), x itself without periodic axes.

    The image nearest one vertex is right only while the triangle's extent along a periodic
    axis plus the reach is under half the period. A longer triangle (a floor plate or drum
    shell spanning a periodic slice) is tested against the neighbouring images as well, as
    many as its extent needs, and the image closest to the triangle wins: three closest-point
    searches for a drum shell's strip. Each particle's candidates are imaged once per step
    (MeshContacts.make_place_candidates), for its mesh contacts and the shields. ``reach``:
    the largest contact search distance (largest radius + skin), m."""
    periodic = grid.periodic
    minimum_image = grid.make_minimum_image()
    any_periodic = any(periodic)
    span_of = grid.layout_funcs()[2]
    reach_of = reader(grid.values, "triangle_reach", reach)

    @ti.func
    def images(x, a, b, c):
        """(base, n_side, span_v): the image of x nearest the triangle's box centre, the
        images worth testing on each side per axis and the period vector (1 on other axes)."""
        lo_t = ti.min(a, b, c)
        hi_t = ti.max(a, b, c)
        mid = 0.5 * (lo_t + hi_t)
        base = mid + minimum_image(x - mid)   # the image nearest the triangle's box centre
        # images on each side worth testing: those within half the extent + reach of mid
        n_side = ti.Vector([0, 0, 0])
        span_v = span_of()
        for k in ti.static(range(3)):
            if ti.static(not periodic[k]):
                span_v[k] = 1.0
        reach = reach_of()
        for k in ti.static(range(3)):
            if ti.static(periodic[k]):
                n_side[k] = ti.max(ti.cast(ti.ceil((0.5 * (hi_t[k] - lo_t[k]) + reach)
                                                   / span_v[k] - 0.5), ti.i32), 0)
        return base, n_side, span_v

    @ti.func
    def triangle_image(x, a, b, c):
        best = x
        if ti.static(any_periodic):
            base, n_side, span_v = images(x, a, b, c)
            best = base
            if n_side.sum() > 0:
                q, region = closest_point_on_triangle(base, a, b, c)
                best_sq = (base - q).norm_sqr()
                for sx in range(-n_side[0], n_side[0] + 1):
                    for sy in range(-n_side[1], n_side[1] + 1):
                        for sz in range(-n_side[2], n_side[2] + 1):
                            if sx != 0 or sy != 0 or sz != 0:
                                trial = base + ti.Vector([sx, sy, sz]) * span_v
                                q2, region2 = closest_point_on_triangle(trial, a, b, c)
                                d_sq = (trial - q2).norm_sqr()
                                if d_sq < best_sq:
                                    best = trial
                                    best_sq = d_sq
        return best

    return triangle_image
