"""Wall-to-bed heat transfer in a rotating drum of 2 mm glass beads in air against the
Schlünder-Mollekopf penetration model (issue 10 item 5; thermal/correlations.py; the experiment
is tests/verification/drum_wall_heat.py, the figures docs/verification/drum_wall_heat.md).

A small version of the documented experiment: a 0.1 m drum slice 5 mm (2.5 bead diameters) long,
periodic along its axis, 10 % fill, a 72-sided smooth shell at 100 C, the bed switched to 20 C
once it rolls. The mechanics turn at 12 rpm (Froude 0.008, rolling) with thermal time scaling
S = 12/n, so the thermal contact time is the one of n = 2 and 6 rpm (the module's docstring
says why the drum must turn S times faster under time scaling). dt 2.5e-5 s (about 15 steps
per contact at the bed's impact speeds; the drum tradeoffs measured outputs within 2.6 % up
to 8 steps per contact, docs/tradeoffs/small_drum).

Measured in the documented (15 % fill, 8 mm) runs, W/(m^2 K): the default gas-gap model
(particle's resistance in series, "solid_resistance") 73 at 2 rpm and 84 at 6 rpm, against the
model's 108 and 148 (contact part 302, bed part 167 and 290, Zehner-Schlünder k_bed 0.165): the
DEM is 0.57-0.68 x the model. The cause is the first layer: that gas-gap law gives one bead
touching the shell 3.6e-4 W/K, 0.31 x Schlünder's isothermal-sphere alpha_WP (1.17e-3 W/K per
bead at l = 0.3 um), so the DEM's contact part is ~96 W/(m^2 K) instead of ~300 and it limits
the whole coefficient (the same law gives the packed bed half the ZBS conductivity). That is
the xfail: DEM within 25 % of the model at both speeds. The 25 %: the model's own uncertainty
(coverage phi_A 0.7-0.9 moves alpha_WS by ~12 %, ZBS's fit to its data ~25 % in k_bed, i.e.
~12 % in alpha_bed, the simple against the exact series form 5 %) and the DEM's (sub-window
scatter 3-5 %, covered triangles against the wetted arc 5-7 %), added in quadrature ~20 %.
The isothermal-surface gas-gap law, the upper bound, gives 196 at 6 rpm (1.32 x; not run
here, to keep the test short). What does agree, and is asserted:

1. The DEM's contact part - the heat flow over (covered area x (T_wall - T_first layer)) -
   is the first-layer beads' count times the gas-gap law's conductance of one bead touching
   the shell, per covered area, within 15 % (beads standing off the facets by up to 0.1 R
   conduct less; the gas-gap integral at contact is thermal/gas_gap.py's quadrature).
2. The coefficient rises with the speed, but less than sqrt(n) (the penetration-only limit:
   the contact resistance is in series): 1.03 < h(6)/h(2) < sqrt(3) (documented runs 1.15,
   the model 1.37, penetration alone 1.73). Both runs have one thread and the same seed, so
   the same mechanics: every sub-window of the average compares the same packings and must
   show the rise on its own.
"""
import math

import numpy as np
import pytest

from drum_wall_heat import drum_wall_heat, models, wall_particle_conductance

SMALL = dict(fill=0.1, length=0.005, settle=0.4, startup=0.6, measure=0.3, dt=2.5e-5,
             output_interval=0.025, threads=1)
MECHANICS_RPM = 12.0
TOLERANCE = 0.25


@pytest.fixture(scope="module")
def runs():
    out = {}
    law = "solid_resistance"
    for rpm in (2.0, 6.0):
        r = drum_wall_heat(rpm=rpm, time_scale=MECHANICS_RPM / rpm, model=law, **SMALL)
        r["kwargs"] = {"model": law}
        out[rpm] = r
        m = models(r)["physical"]
        print(f"\n  {rpm:g} rpm, {law}: DEM {r['h']:.1f} (arc {r['h_arc']:.1f}) W/(m^2 K), contact part "
              f"{r['h_contact']:.0f}, bed part {r['h_bed']:.0f}; model {m['alpha']:.1f} (contact "
              f"{m['alpha_ws']:.0f}, bed {m['alpha_bed']:.0f}); wetted angle "
              f"{math.degrees(r['wetted_angle']):.0f} deg, t_c {r['contact_time']:.2f} s, "
              f"window scatter {r['h_std_window']:.1f}, {r['wall_seconds']:.0f} s wall")
    return out


@pytest.mark.slow
def test_rolling_bed_keeps_its_beads_and_rolls(runs):
    for r in runs.values():
        assert r["lost"] == 0
        assert r["froude_mech"] < 0.01
        # the bed covers the shell over about the flat-surface segment's angle
        assert r["wetted_angle"] == pytest.approx(r["wetted_angle_guess"], rel=0.15)
        # covered triangles and the beads' angular span agree on the wetted area
        assert r["wetted_angle_from_area"] == pytest.approx(r["wetted_angle"], rel=0.15)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "the default (solid_resistance) gas-gap law gives a bead touching the shell 0.31 x "
    "Schlünder's isothermal-sphere conductance, so the DEM's contact part is ~96 instead of ~300 "
    "W/(m^2 K) and limits the coefficient: documented runs 73 / 84 W/(m^2 K) at 2 / 6 rpm "
    "against the model's 108 / 148 (0.68 / 0.57 x); docs/verification/drum_wall_heat.md"))
def test_coefficient_matches_schlunder_mollekopf(runs):
    for r in runs.values():
        model = models(r)["physical"]["alpha"]
        assert r["h"] == pytest.approx(model, rel=TOLERANCE)


@pytest.mark.slow
def test_contact_part_is_the_first_layer_conductance(runs):
    for r in runs.values():
        g = wall_particle_conductance(r["kwargs"]["model"])
        expected = r["first_layer_count"] * g / r["covered_area"]
        assert r["h_contact"] == pytest.approx(expected, rel=0.15)
        assert r["h_contact"] < expected * 1.02        # standing off only lowers it


@pytest.mark.slow
def test_coefficient_rises_with_speed_slower_than_penetration_alone(runs):
    slow, fast = runs[2.0], runs[6.0]
    ratio = fast["h"] / slow["h"]
    # one thread and one seed: both runs move the beads identically (the heat does not act on
    # the mechanics), so each sub-window compares the same packings and must show the rise
    windows = np.array(fast["h_windows"]) / np.array(slow["h_windows"])
    print(f"\n  h(6 rpm) / h(2 rpm) = {ratio:.3f}, by sub-window {np.round(windows, 3)} "
          f"(penetration alone: {math.sqrt(3):.3f})")
    assert 1.03 < ratio < math.sqrt(3.0)
    assert np.all(windows > 1.0)
