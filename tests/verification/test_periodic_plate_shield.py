"""A zero-thickness plate shields two spheres on its two faces in a periodic slice, where the
plate spans the whole period and is tilted against the periodic axis (bodies/mesh_contacts.py
``make_shields``, bodies/triangle_images.py ``plane_side_range``).

The plate test of a pair first bounds the side of the plane over every periodic image the
triangle's image search may choose: an image shifted by s periods P moves it by s (P . n). A
plate along the period (n . P = 0) leaves it alone; this one, tilted 20 deg about y across a
period of 20 mm, moves it by sin(20 deg) x 20 mm = 6.8 mm per period, more than the spheres'
2 mm radius, so a wrong bound would skip the test and let the pair push through the plate.

Two 2 mm steel spheres at rest, no gravity, each overlapping the plate by 5 % of its radius on
its own face, so they overlap each other by 0.2 mm through it; a third sphere, alone on another
stretch of the plate, overlaps it by the same 5 %. Shielded, each of the pair is pushed by the
plate alone, exactly as the lone sphere is (the same Hertz contact: to round-off); a pair
contact through the plate would add Hertz's pair force (at twice the overlap, R* = r / 2: 2x
the plate's), 3x the plate's push in all (measured so with the plate test switched off).
Checked at the period's middle and 1.5 mm from its seam (both spheres over the plate's face;
across the seam the plate's two ends are 7 mm apart in height, so a sphere there touches an
edge, not the face the lone one touches)."""
import math

import numpy as np
import pytest

import taichi_dem
import dem_helpers as h

R = 0.002
PERIOD = 0.02
TILT = math.radians(20.0)
NORMAL = np.array([-math.sin(TILT), 0.0, math.cos(TILT)])     # the plate's unit normal
OVERLAP = 0.05 * R


def plate_point(x, y):
    """The point of the plate (z = (x - PERIOD / 2) tan(tilt)) above (x, y), m."""
    return np.array([x, y, (x - 0.5 * PERIOD) * math.tan(TILT)])


def scene(tmp_path, pair_x):
    """The periodic slab, the tilted plate over the whole period, the pair about the plate's
    point at x = ``pair_x`` and the lone sphere at y = 12 mm."""
    x0, x1, half = 0.0, PERIOD, 0.02
    corners = [plate_point(x0, -half), plate_point(x1, -half), plate_point(x1, half),
               plate_point(x0, half)]
    vertices = "".join("v " + " ".join(repr(float(x)) for x in c) + "\n" for c in corners)
    (tmp_path / "plate.obj").write_text(vertices + "f 1 2 3\nf 1 3 4\n")
    on_plate = plate_point(pair_x, -0.006)
    lone = plate_point(0.5 * PERIOD, 0.012)
    positions = [on_plate + (R - OVERLAP) * NORMAL, on_plate - (R - OVERLAP) * NORMAL,
                 lone + (R - OVERLAP) * NORMAL]
    return (h.header(dt=1e-8, lo=(0.0, -0.03, -0.03), hi=(PERIOD, 0.03, 0.03), periodic=("x",),
                     skin=0.0005, output_interval=1e-6)
            + h.material("steel", 7800.0, 2.0e11, 0.3) + h.all_interactions(["steel"])
            + h.csv_fill(tmp_path, "spheres.csv", "steel", positions, R)
            + '[[bodies]]\nname = "plate"\nmaterial = "steel"\nmesh = { file = "plate.obj" }\n')


@pytest.mark.parametrize("pair_x", [0.5 * PERIOD, 0.0015])
def test_a_tilted_plate_over_the_whole_period_shields_the_pair(tmp_path, pair_x):
    with taichi_dem.Simulation.from_text(scene(tmp_path, pair_x), base_dir=str(tmp_path)) as sim:
        sim.step(1)
        v = sim.particles()["velocity"]
    lone = v[2] @ NORMAL
    assert lone > 0.0                                   # the plate pushes it off its face
    # each of the pair as the lone sphere: along the normal, outward, to round-off
    assert v[0] @ NORMAL == pytest.approx(lone, rel=1e-9)
    assert v[1] @ NORMAL == pytest.approx(-lone, rel=1e-9)
