"""The map's axial transport of a rolling drum bed against Saeman's (1951) equation.

Saeman's uniform-bed flow, the plateau of Kramers & Croockewit's bed-depth equation, is
q = rho_b (4/3) pi n (c/2)^3 tan(theta) / sin(beta): n the drum's revolutions per second, c the
chord of the bed surface, theta the incline, beta the dynamic angle, rho_b the bed's bulk
density. Its assumptions: a rolling bed riding with the shell (no slip), particles that move
along the axis only while they run down the surface layer, a flat surface at beta, a thin
surface layer. The scene (saeman_drum.toml) meets them as far as spheres can: lifters and a
rough shell keep the bed riding with the shell (slip ratio 0.97) and its layer on the shell
from rolling along it (its axial speed a seventh of the bed's mean).

The slice at 15 % fill, 3 deg, 20 rpm, with Saeman's flow at the measured dynamic angle and
the chord of the hold-up at the map's bulk solid fraction (0.6). Measured (10 s runs): the
map's flow is 1.36 x Saeman's at 15 % fill and 1.26 x at 30 % (8 s, the test: 1.3 - 1.4); with
a smooth shell (wall friction 0.5, rolling friction 0.02; the bed still rides at 0.95, but its
layer on the shell rolls down the axis at a sixth of the bed's speed) 1.59 x and 1.31 x.

So this bed of spheres, 33 diameters across the drum and 7 deep at 15 % fill, is carried about
a third faster than Saeman's equation says. Saeman's is a thin-layer model of deep beds of fine
particles; Scott et al. (Ind. Eng. Chem. Res. 48 (2009) 159) find the Kramers-Saeman model good
for sand and poppy seeds but not for glass beads under some conditions, and Sullivan's and
Friedman & Marshall's correlations miss this code's small drum by 3x (bench/sullivan_drum.py).
The measured surface (through the top layer's highest centres) gives a chord whose segment
would hold the bed at a solid fraction of 0.44: an envelope, not the mean surface, so it is not
used for the check. What the test holds: the bed rides with the shell, its layer on the shell
does not creep, the angle is a rolling bed's, and the transport is Saeman's within +60 / -0 %:
a map that loses the transport (the slice's flow an average of something else) or doubles it
(a bed sliding down the shell) fails. Closing the gap to a 15 % tolerance needs beds of
D/d >= 100 (a bigger drum or smaller beads: 10x the particles) - noted in the issue.
"""
import math
from pathlib import Path

import pytest

from taichi_dem.app import slice_map as sm
from taichi_dem.app.machine import saeman_check

SCENE = Path(__file__).with_name("saeman_drum.toml")


@pytest.mark.slow
def test_map_transport_of_a_rolling_drum_is_saemans():
    text = SCENE.read_text()
    from taichi_dem.scene.loader import parse_scene
    scene = parse_scene(text, source=str(SCENE))
    geometry = sm.slice_geometry(scene)
    result = sm.run_slice(text, str(SCENE), ("fill", 0.15), 8.0)
    row = result.row()
    q, ratio = saeman_check(row, sm.machine_info(scene, geometry))
    print(f"\n  flow {row['axial_mass_flow']:.4g} +- {row['axial_mass_flow_standard_error']:.2g} "
          f"kg/s, Saeman {q:.4g} kg/s (x{ratio:.3f}); angle {row['dynamic_angle']:.3g} deg, "
          f"chord {row['surface_chord']:.4g} m, slip {row['slip_ratio']:.3f}, shell layer "
          f"{row['shell_layer_axial_speed']:.3g} m/s of {row['axial_speed']:.3g}")
    assert row["slip_ratio"] > sm.SLIP_BELOW                       # riding with the shell
    assert abs(row["shell_layer_axial_speed"]) < 0.3 * abs(row["axial_speed"])
    assert 25.0 < row["dynamic_angle"] < 45.0
    assert q < 0.0 and row["axial_mass_flow"] < 0.0                # down the incline, -x
    assert 1.0 < ratio < 1.6
    assert math.isfinite(row["axial_mass_flow_standard_error"])
