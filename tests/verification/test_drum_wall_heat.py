"""Wall-to-bed heat transfer in a rotating drum of 2 mm glass beads in air against the
Schlünder-Mollekopf penetration model (issue 10 item 5, issue 32 item 2; thermal/correlations.py;
the experiment is tests/verification/drum_wall_heat.py, the figures
docs/verification/drum_wall_heat.md and docs/verification/first_layer.md).

A small version of the documented experiment: a 0.1 m drum slice 5 mm (2.5 bead diameters) long,
periodic along its axis, 10 and 20 % fill, a 72-sided shell at 100 C with 16 lifters 1 mm (half a
bead) high, the bed switched to 20 C once it rolls. The mechanics turn at 12 rpm (Froude 0.008,
rolling) with thermal time scaling S = 12/n, so the thermal contact time is the one of n = 2 and
6 rpm (drum_wall_heat.py says why the drum must turn S times faster under time scaling). dt
2.5e-5 s (about 15 steps per contact at the bed's impact speeds; the drum tradeoffs measured
outputs within 2.6 % up to 8 steps per contact, docs/tradeoffs/small_drum).

The lifters: on the smooth shell the bed does not ride with the drum - the beads touching the
shell move at 0.46 of its speed (median 0.58: they roll on it like a bearing; wall friction 1.0
or rolling friction 0.1 do not change that), and the penetration model assumes a wall element
covered by a bed at rest on it. With the lifters the first layer rides at 0.92-0.96.

Glass slides on glass at its measured friction, 0.092 (Foerster et al. 1994; drum_wall_heat.py
GLASS_FRICTION); the shell's stays 0.5 (the lifters make the bed ride). The average starts 1.1
contact times after the switch (the steady state the model averages over), and the model is
evaluated at the porosity of the riding bed the run measures (0.40 at 10 % fill, 0.37 at 20 %).

The default gas-gap law ("schlunder": thermal/first_layer.py, particle_transient.py) gives a bead
touching the shell Schlünder's first-layer conductance alpha_WP pi d^2/4 at the start of its
contact, falling to ~0.54 of it as the glass behind the gap warms (the resolved sphere).
Measured (W/(m^2 K); fill, thermal rpm: DEM / model; 2026-12-07, seed 1, skin 0.6 mm):

    0.1, 2: 120.4 / 109.2 (1.10)     0.1, 6: 137.4 / 149.6 (0.92)
    0.2, 2: 106.8 / 107.1 (1.00)     0.2, 6: 129.4 / 147.3 (0.88)

(With the skin at 0.1 mm, the former limit of the period, the same code gives 1.09, 0.92,
1.04 and 0.91: the skin changes the order of the sums' round-off, so the runs part ways.)

With the former friction 0.5 (no source) the same protocol gives 1.02, 0.86, 0.94 and 0.82: the
friction sets how densely the first layer covers the shell (0.63 of the covered area at 0.5,
0.68-0.71 at 0.092), and the contact part follows it. At 20 % fill and 6 rpm, friction 0.2 gives
0.825 and 0.3 gives 0.792: the pass holds at the measured friction of clean glass only. The former default ("solid_resistance",
smooth shell, 15 % fill) gave 0.68 and 0.57 x. Asserted: within 15 % of the model, all four
(the issue's tolerance; the model's own uncertainty is of that order: phi_A 0.7-0.9 moves
alpha_WS by ~12 %, ZBS's fit ~25 % in k_bed, i.e. ~12 % in alpha_bed). The DEM's coefficient
rises less with the speed than the model's (1.15-1.20 x from 2 to 6 rpm against 1.37 x): the
lumped first layer stores the heat a continuum would conduct inward, so the particle's own
resistance, not the bed's penetration, sets the DEM's figure at these sub-particle penetration
depths (sqrt(a_bed t_c) = 0.6 mm at 6 rpm). So the DEM lies above the model at 2 rpm and below
it at 6 rpm.

Also asserted:
1. The bed rides with the shell (mean speed of the first layer > 0.85 of the shell's, averaged
   over the whole time since the switch: a window of 0.3 s alone reads 0.86 - 0.97), and the
   riding bed's porosity is a random packing's (0.34-0.45).
2. The DEM's contact part - heat flow over (covered area x (T_wall - T_first layer)) - lies
   between the first layer's quasi-steady and fresh conductances per covered area (count x G /
   area; the resolved sphere's limits of G).
3. The coefficient rises with the speed, but less than sqrt(n) (penetration alone): 1.03 <
   h(6)/h(2) < sqrt(3). Both runs of a fill have one thread and the same seed, so the same
   mechanics: every sub-window of the average compares the same packings and must show the rise.
"""
import math

import numpy as np
import pytest

from drum_wall_heat import GLASS, GLASS_FRICTION, drum_wall_heat, models, wall_particle_conductance

# skin 0.6 mm (0.3 d): the period is shorter than two list cutoffs, so the search covers it
# in one cell; the default skin (1 mm here, the cascade's speed) lists longer rows. Measured at
# 10 % fill: 0.1 mm (the former limit of the period) 530 ns per particle-step, 0.6 mm 345,
# 1 mm 450-480. The skin changes when the lists are rebuilt, not which pairs touch.
SMALL = dict(length=0.005, settle=0.4, measure=0.3, dt=2.5e-5, output_interval=0.025,
             threads=1, flights=16, flight_height=1e-3, model="schlunder",
             friction=GLASS_FRICTION, skin=6e-4)
MECHANICS_RPM = 12.0
TOLERANCE = 0.15
_RUNS = {}


def run(fill, rpm):
    """The experiment at ``fill`` and thermal ``rpm`` (cached for the module)."""
    if (fill, rpm) not in _RUNS:
        r = drum_wall_heat(rpm=rpm, fill=fill, time_scale=MECHANICS_RPM / rpm, **SMALL)
        r["kwargs"] = {"model": "schlunder"}
        m = models(r)["physical"]
        print(f"\n  fill {fill:g}, {rpm:g} rpm: DEM {r['h']:.1f} (arc {r['h_arc']:.1f}) W/(m^2 K), "
              f"contact part {r['h_contact']:.0f}, bed part {r['h_bed']:.0f}; model "
              f"{m['alpha']:.1f} (contact {m['alpha_ws']:.0f}, bed {m['alpha_bed']:.0f}), "
              f"{r['h'] / m['alpha']:.2f} x; rides at {r['ride']:.2f} (window "
              f"{r['ride_window']:.2f}); wetted angle "
              f"{math.degrees(r['wetted_angle']):.0f} deg, t_c {r['contact_time']:.2f} s, "
              f"{r['wall_seconds']:.0f} s wall")
        _RUNS[(fill, rpm)] = r
    return _RUNS[(fill, rpm)]


@pytest.mark.slow
@pytest.mark.parametrize("fill, rpm", [(0.1, 2.0), (0.1, 6.0), (0.2, 2.0), (0.2, 6.0)])
def test_coefficient_matches_schlunder_mollekopf(fill, rpm):
    r = run(fill, rpm)
    assert r["h"] == pytest.approx(models(r)["physical"]["alpha"], rel=TOLERANCE)


@pytest.mark.slow
@pytest.mark.parametrize("fill", [0.1, 0.2])
def test_rolling_bed_rides_with_the_shell_and_keeps_its_beads(fill):
    for rpm in (2.0, 6.0):
        r = run(fill, rpm)
        assert r["lost"] == 0
        assert r["froude_mech"] < 0.01
        assert r["ride"] > 0.85
        # the bed covers the shell over about the flat-surface segment's angle
        assert r["wetted_angle"] == pytest.approx(r["wetted_angle_guess"], rel=0.2)
        # the riding bed is a random packing (the model is evaluated at this porosity)
        assert 0.34 < r["bed_porosity"] < 0.45


@pytest.mark.slow
def test_contact_part_is_between_the_first_layers_limits():
    from taichi_dem.thermal import correlations, first_layer
    from taichi_dem.thermal.particle_transient import conductance_ratio
    free_path = correlations.modified_mean_free_path(333.15)
    _, ratio, _ = conductance_ratio(1e-3, GLASS["k"], GLASS["density"], GLASS["c"], 0.0262,
                                    free_path, first_layer.REACH)
    fresh = wall_particle_conductance("schlunder")
    for rpm in (2.0, 6.0):
        r = run(0.1, rpm)
        per_area = r["first_layer_count"] / r["covered_area"]
        print(f"\n  {rpm:g} rpm: contact part {r['h_contact']:.0f}, limits "
              f"{per_area * fresh * ratio[-1]:.0f} - {per_area * fresh:.0f} W/(m^2 K)")
        # beads standing off the facets conduct less than touching ones: 0.85 of the lower limit
        assert 0.85 * per_area * fresh * ratio[-1] < r["h_contact"] < per_area * fresh


@pytest.mark.slow
def test_coefficient_rises_with_speed_slower_than_penetration_alone():
    slow, fast = run(0.1, 2.0), run(0.1, 6.0)
    ratio = fast["h"] / slow["h"]
    windows = np.array(fast["h_windows"]) / np.array(slow["h_windows"])
    print(f"\n  h(6 rpm) / h(2 rpm) = {ratio:.3f}, by sub-window {np.round(windows, 3)} "
          f"(penetration alone: {math.sqrt(3):.3f})")
    assert 1.03 < ratio < math.sqrt(3.0)
    assert np.all(windows > 1.0)


def test_passive_bed_solid_fraction_of_a_simple_cubic_lattice():
    """The porosity sampler against a packing whose solid fraction is known: beads on a simple
    cubic lattice of spacing 2 r fill pi / 6 = 0.5236 of space. The sector (6 radii deep, 0.5
    rad wide, 5 mm long: ~70 lattice cells) cuts cells at its edges, which moves the fraction
    by up to ~2 % of it; 20 000 points add a standard error of 0.0035. Tolerance 0.02."""
    from drum_wall_heat import passive_bed_solid_fraction
    r, big, length = 1e-3, 0.05, 0.006
    step = 2.0 * r
    g = np.arange(-big, big, step) + r
    x = np.arange(0.0, length, step) + r
    X, Y, Z = np.meshgrid(x, g, g, indexing="ij")
    lattice = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    lattice = lattice[np.hypot(lattice[:, 1], lattice[:, 2]) < big - 1.5 * r]
    # a ring of beads touching the shell over +-1 rad about the bottom marks the wetted arc
    a = np.linspace(-1.0, 1.0, 40)
    ring = np.column_stack([np.full_like(a, r), (big - r) * np.sin(a), -(big - r) * np.cos(a)])
    fraction = passive_bed_solid_fraction(np.vstack([lattice, ring]), r, big, length)
    assert fraction == pytest.approx(math.pi / 6.0, abs=0.02)
    # no beads on the shell: no wetted arc to sample
    assert math.isnan(passive_bed_solid_fraction(lattice, r, big, length))
