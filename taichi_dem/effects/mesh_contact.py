"""Particle-triangle contact geometry (PHYSICS.md "Particle-triangle contacts").

The closest point of a triangle to a sphere centre lies in the face, on an edge or at a
vertex (Ericson, Real-Time Collision Detection, section 5.1.5, Voronoi regions). The contact
normal points from that point to the centre, so a thin plate touched from either side pushes
the particle away from it.
"""
import taichi as ti

REGION_FACE, REGION_EDGE, REGION_VERTEX = 0, 1, 2


@ti.func
def closest_point_on_triangle(p, a, b, c):
    """Closest point of triangle (a, b, c) to ``p`` and its region (face, edge or vertex)."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = ab.dot(ap)
    d2 = ac.dot(ap)
    point = a
    region = REGION_VERTEX
    if d1 <= 0.0 and d2 <= 0.0:
        point = a
    else:
        bp = p - b
        d3 = ab.dot(bp)
        d4 = ac.dot(bp)
        if d3 >= 0.0 and d4 <= d3:
            point = b
        else:
            vc = d1 * d4 - d3 * d2
            if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
                point = a + d1 / (d1 - d3) * ab
                region = REGION_EDGE
            else:
                cp = p - c
                d5 = ab.dot(cp)
                d6 = ac.dot(cp)
                if d6 >= 0.0 and d5 <= d6:
                    point = c
                else:
                    vb = d5 * d2 - d1 * d6
                    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
                        point = a + d2 / (d2 - d6) * ac
                        region = REGION_EDGE
                    else:
                        va = d3 * d6 - d5 * d4
                        if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
                            point = b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
                            region = REGION_EDGE
                        else:
                            denom = 1.0 / (va + vb + vc)
                            point = a + ab * (vb * denom) + ac * (vc * denom)
                            region = REGION_FACE
    return point, region
