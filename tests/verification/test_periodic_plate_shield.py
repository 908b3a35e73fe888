"""A zero-thickness plate shields two spheres on its two faces in a periodic slice, where the
plate is longer than the period and tilted against the periodic axis (bodies/mesh_contacts.py
``make_shields``, bodies/triangle_images.py ``triangle_image``).

The plate test of a pair takes each sphere's periodic image nearest the triangle (placed once
per step, ``make_place_candidates``): an image shifted by s periods P moves its side of the
plane by s (P . n). A plate along the period (n . P = 0) leaves it alone. This one spans two
periods (x from 0 to 40 mm, the period 20 mm), tilted 20 deg about y, so each period moves the
side by sin(20 deg) x 20 mm = 6.8 mm, more than the spheres' 2 mm radius. Its box centre lies at
x = 20 mm: for a sphere at x = 4 mm the image nearest that centre is at x = 24 mm, beside the
plate's far half, 6.8 mm from the plane, while the image that touches the plate is the sphere
itself, one period back. A test of the image nearest the box centre would find no crossing
there and let the pair push through the plate (measured, with the former bound on the side
that left the images' shift out: the test then fails at x = 4 mm). At x = 16 mm the image
nearest the centre is the sphere itself.

Two 2 mm steel spheres at rest, no gravity, each overlapping the plate by 5 % of its radius on
its own face, so they overlap each other by 0.2 mm through it; a third sphere, alone on another
stretch of the plate, overlaps it by the same 5 %. Shielded, each of the pair is pushed by the
plate alone, exactly as the lone sphere is (the same Hertz contact: to round-off); a pair
contact through the plate would add Hertz's pair force (at twice the overlap, R* = r / 2: 2x
the plate's), 3x the plate's push in all (measured so with the plate test switched off). The
plate's other period lies 6.9 mm away along the normal, out of the spheres' reach."""
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
    """The point of the plate (z = (x - PERIOD) tan(tilt)) above (x, y), m."""
    return np.array([x, y, (x - PERIOD) * math.tan(TILT)])


def scene(tmp_path, pair_x):
    """The periodic slab, the tilted plate over two periods, the pair about the plate's
    point at x = ``pair_x`` (y = -6 mm) and the lone sphere beside it (y = 12 mm)."""
    x0, x1, half = 0.0, 2.0 * PERIOD, 0.02
    corners = [plate_point(x0, -half), plate_point(x1, -half), plate_point(x1, half),
               plate_point(x0, half)]
    vertices = "".join("v " + " ".join(repr(float(x)) for x in c) + "\n" for c in corners)
    (tmp_path / "plate.obj").write_text(vertices + "f 1 2 3\nf 1 3 4\n")
    on_plate = plate_point(pair_x, -0.006)
    lone = plate_point(pair_x, 0.012)
    positions = [on_plate + (R - OVERLAP) * NORMAL, on_plate - (R - OVERLAP) * NORMAL,
                 lone + (R - OVERLAP) * NORMAL]
    return (h.header(dt=1e-8, lo=(0.0, -0.03, -0.03), hi=(PERIOD, 0.03, 0.03), periodic=("x",),
                     skin=0.0005, output_interval=1e-6)
            + h.material("steel", 7800.0, 2.0e11, 0.3) + h.all_interactions(["steel"])
            + h.csv_fill(tmp_path, "spheres.csv", "steel", positions, R)
            + '[[bodies]]\nname = "plate"\nmaterial = "steel"\nmesh = { file = "plate.obj" }\n')


@pytest.mark.parametrize("pair_x", [0.2 * PERIOD, 0.8 * PERIOD])
def test_a_tilted_plate_longer_than_the_period_shields_the_pair(tmp_path, pair_x):
    with taichi_dem.Simulation.from_text(scene(tmp_path, pair_x), base_dir=str(tmp_path)) as sim:
        sim.step(1)
        v = sim.particles()["velocity"]
    lone = v[2] @ NORMAL
    assert lone > 0.0                                   # the plate pushes it off its face
    # each of the pair as the lone sphere: along the normal, outward, to round-off
    assert v[0] @ NORMAL == pytest.approx(lone, rel=1e-9)
    assert v[1] @ NORMAL == pytest.approx(-lone, rel=1e-9)
