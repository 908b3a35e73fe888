"""The whole machine from its map (app/machine.py): the march must reduce to Kramers &
Croockewit's bed-depth equation for a plain drum, reach Saeman's uniform depth far from the
discharge, keep a self-conveying machine at the hold-up that carries the feed, and integrate
residence, torque and the outlet temperature as their closed forms give them."""
import math

import numpy as np
import pytest

from taichi_dem.app import machine as mc
from taichi_dem.errors import SceneError

R = 0.5                   # drum radius, m
N = 3.0 / 60.0            # rev/s (3 rpm)
BETA = 35.0               # dynamic angle, deg
THETA = 3.0               # incline, deg: the drum discharges towards -x
RHO_B = 1500.0            # bulk density, kg/m^3
SECTION = mc.Section(R, 0.0, RHO_B)


def drum_map(depths=(0.1, 0.2, 0.3, 0.45, 0.6), shaft_torque=None, conductance=None,
             airborne_share=None):
    """A plain drum's map as Saeman's law gives it, at one incline (gravity towards -x);
    ``airborne_share``: that part of the flow said to be carried in flight."""
    rows = []
    slope = -math.tan(math.radians(THETA))
    for d in depths:
        h = d * R
        H = float(SECTION.holdup(h))
        q = -mc.saeman_flow(SECTION, h, N, math.tan(math.radians(THETA)), BETA)
        figures = {"axial_mass_flow": (q, 0.0), "dynamic_angle": (BETA, 0.0)}
        if shaft_torque is not None:
            figures["shell/torque_per_metre"] = (shaft_torque * H, 0.0)
        if conductance is not None:
            figures["shell/conductance_per_metre"] = (conductance, 0.0)
        if airborne_share is not None:
            figures["airborne_mass_flow"] = (airborne_share * q, 0.0)
        rows.append(mc.MapRow(H, slope, figures))
    return mc.MachineMap(rows, SECTION, {"shell": 2 * math.pi * N}, 0.004, 1000.0,
                         {"shell": 300.0}, ["shell"])


def kramers(feed, length, h0, steps=20000, bed_share=1.0):
    """Kramers & Croockewit's equation as published (x from the discharge), RK4; with
    ``bed_share`` < 1 the depth gradient drives only that share of the flow (its rate over
    the share)."""
    phi = feed / RHO_B
    tb, sb = math.tan(math.radians(BETA)), math.sin(math.radians(BETA))
    tt = math.tan(math.radians(THETA))

    def rate(h):
        f = 2 * h / R - (h / R) ** 2
        return tb * (3 * phi / (4 * math.pi * N * R ** 3) * f ** -1.5 - tt / sb) / bed_share
    x = np.linspace(0.0, length, steps + 1)
    h = np.empty_like(x)
    h[0] = h0
    dx = x[1] - x[0]
    for k in range(steps):
        y = h[k]
        k1 = rate(y)
        k2 = rate(y + 0.5 * dx * k1)
        k3 = rate(y + 0.5 * dx * k2)
        k4 = rate(y + dx * k3)
        h[k + 1] = y + dx / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x, h


def saeman_depth(feed):
    """The uniform (plateau) depth at which Saeman's flow at the incline carries ``feed``."""
    c_half3 = 3 * (feed / RHO_B) * math.sin(math.radians(BETA)) / (
        4 * math.pi * N * math.tan(math.radians(THETA)))
    c = 2 * c_half3 ** (1 / 3)
    return R - math.sqrt(R * R - c * c / 4)


def test_section_geometry():
    s = mc.Section(0.4, 0.08, 1000.0)
    assert s.area(0.8) == pytest.approx(math.pi * (0.4 ** 2 - 0.08 ** 2), rel=1e-9)
    assert s.area(0.4) == pytest.approx(0.5 * math.pi * (0.4 ** 2 - 0.08 ** 2), rel=1e-9)
    assert s.area(0.3) == pytest.approx(mc._segment(0.4, 0.3), rel=1e-12)   # below the shaft
    for d in (0.05, 0.33, 0.5, 0.75):
        assert s.depth(s.holdup(d))[0] == pytest.approx(d, rel=1e-9)
    assert s.chord(0.4) == pytest.approx(0.8)


def test_march_reduces_to_kramers_for_a_plain_drum():
    feed = 1.2 * 1.0                             # kg/s
    length, h0 = 12.0, 0.02
    law = mc.TransportLaw(drum_map())
    assert law.single_incline
    prof = mc.march(law, length, feed, -math.tan(math.radians(THETA)), h0,
                    overflow_holdup=float(SECTION.holdup(R)), steps=800)
    assert not prof.overflows and prof.flow_sign == -1
    x_ref, h_ref = kramers(feed, length, h0)
    up = length - prof.x                         # the march's distance from the discharge
    for d in (0.05, 0.3, 1.0, 3.0, 8.0, 12.0):
        got = float(np.interp(d, up[::-1], prof.depth[::-1]))
        assert got == pytest.approx(float(np.interp(d, x_ref, h_ref)), rel=2e-3), d
    # far from the discharge, Saeman's uniform depth
    assert prof.depth[0] == pytest.approx(saeman_depth(feed), rel=5e-3)


def test_the_depth_gradient_drives_only_what_the_bed_carries():
    """With 70 % of the flow carried in flight (a flighted drum's curtains), the bed's depth
    gradient drives the other 30 %: Kramers' equation with its rate over 0.3. The uniform
    depth far upstream is the same (no gradient there), the stretch before the discharge
    where the bed thins is shorter, and the hold-up larger."""
    feed, length, h0 = 1.2, 12.0, 0.02
    law = mc.TransportLaw(drum_map(airborne_share=0.7))
    assert law.bed_share == pytest.approx(np.full(5, 0.3))
    prof = mc.march(law, length, feed, -math.tan(math.radians(THETA)), h0,
                    overflow_holdup=float(SECTION.holdup(R)), steps=800)
    x_ref, h_ref = kramers(feed, length, h0, bed_share=0.3)
    up = length - prof.x
    for d in (0.02, 0.1, 0.3, 1.0, 3.0, 12.0):
        got = float(np.interp(d, up[::-1], prof.depth[::-1]))
        assert got == pytest.approx(float(np.interp(d, x_ref, h_ref)), rel=2e-3), d
    assert prof.depth[0] == pytest.approx(saeman_depth(feed), rel=5e-3)
    plain = mc.answer(drum_map(), length, feed, -math.tan(math.radians(THETA)), 0.02, steps=800)
    flighted = mc.answer(drum_map(airborne_share=0.7), length, feed,
                         -math.tan(math.radians(THETA)), 0.02, steps=800)
    assert flighted.holdup > plain.holdup
    # a map without the figure at some row keeps the whole flow driven (phi_bed = 1)
    rows = drum_map(airborne_share=0.7).rows
    rows[2].figures.pop("airborne_mass_flow")
    mixed = mc.TransportLaw(mc.MachineMap(rows, SECTION, {}, 0.004))
    assert mixed.bed_share[2] == 1.0 and mixed.bed_share[0] == pytest.approx(0.3)


def test_march_residence_torque_and_outlet_temperature():
    feed = 1.2
    length = 12.0
    m = drum_map(shaft_torque=-2.0, conductance=150.0)
    ans = mc.answer(m, length, feed, -math.tan(math.radians(THETA)), discharge_depth=0.02,
                    inlet_temperature=700.0, steps=800)
    x_ref, h_ref = kramers(feed, length, 0.02)
    hold_ref = float(np.trapezoid(SECTION.holdup(h_ref), x_ref))
    assert ans.holdup == pytest.approx(hold_ref, rel=3e-3)
    assert ans.residence_time == pytest.approx(hold_ref / feed, rel=3e-3)
    # the torque per metre is -2 N m per kg/m of hold-up: the total is -2 x the hold-up
    assert ans.torques["shell"] == pytest.approx(-2.0 * hold_ref, rel=3e-3)
    # constant conductance along a bed that never empties: the closed form
    t_out = 300.0 + 400.0 * math.exp(-150.0 * length / (feed * 1000.0))
    assert ans.outlet_temperature == pytest.approx(t_out, rel=1e-3)


def test_a_self_conveying_machine_carries_the_feed_at_its_own_hold_up():
    """q = a(H) + b(H) s fitted over two inclines; the plateau is where it equals the feed."""
    s1, s2 = 0.0, -math.tan(math.radians(5.0))   # level and raised 5 deg at +x
    rows = []
    for d in (0.15, 0.3, 0.45, 0.6):
        h = d * R
        H = float(SECTION.holdup(h))
        c3 = float(SECTION.chord(h)) ** 3
        for s in (s1, s2):
            q = c3 * (2.0 + 6.0 * s)          # conveys towards +x, against the incline
            rows.append(mc.MapRow(H, s, {"axial_mass_flow": (q, 0.0),
                                         "dynamic_angle": (BETA, 0.0)}))
    m = mc.MachineMap(rows, SECTION, {}, 0.01, None, {}, [])
    law = mc.TransportLaw(m)
    assert not law.single_incline
    a, b, _ = law.coefficients(float(SECTION.holdup(0.3 * R)))
    c3 = float(SECTION.chord(0.3 * R)) ** 3
    assert a == pytest.approx(2.0 * c3, rel=1e-6) and b == pytest.approx(6.0 * c3, rel=1e-6)
    feed = 0.5
    ans = mc.answer(m, 6.0, feed, s2, discharge_depth=0.01, steps=600)
    assert ans.profile.flow_sign == 1
    # plateau: c^3 (2 + 6 s2) = feed
    c = (feed / (2.0 + 6.0 * s2)) ** (1 / 3)
    h_plateau = R - math.sqrt(R * R - c * c / 4)
    assert ans.profile.depth[0] == pytest.approx(h_plateau, rel=5e-3)
    # the same machine inclined more carries the feed at a larger hold-up
    steeper = mc.answer(m, 6.0, feed, -math.tan(math.radians(8.0)), discharge_depth=0.01)
    assert steeper.inlet_holdup > ans.inlet_holdup


def test_capacity_is_the_feed_that_fills_the_inlet_end_to_the_overflow():
    m = drum_map()
    limit = float(SECTION.holdup(0.6 * R))
    cap = mc.capacity(m, 60.0, -math.tan(math.radians(THETA)), discharge_depth=0.02,
                      overflow_holdup=limit)
    # a long drum at its capacity is at Saeman's uniform depth at the overflow level
    expected = mc.saeman_flow(SECTION, 0.6 * R, N, math.tan(math.radians(THETA)), BETA)
    assert cap == pytest.approx(expected, rel=1e-2)
    over = mc.answer(m, 60.0, 1.05 * cap, -math.tan(math.radians(THETA)), 0.02, limit)
    assert over.overflows


def test_errors_follow_the_map_standard_errors():
    m = drum_map()
    for r in m.rows:                     # a 5 % standard error on every flow
        q, _ = r.figures["axial_mass_flow"]
        r.figures["axial_mass_flow"] = (q, 0.05 * abs(q))
    out = mc.with_errors(m, 12.0, [1.0], -math.tan(math.radians(THETA)), 0.02, draws=30)
    rel = out["errors"][0]["residence_time"] / out["feeds"][0].residence_time
    # the hold-up of a Saeman bed goes as q^(-2/3) in the chord cubed: ~3 % for 5 % in q,
    # less for the rows' independent draws partly cancelling
    assert 0.005 < rel < 0.06
    assert 0.0 < out["capacity_error"] / out["capacity"] < 0.1


def test_a_map_at_a_level_axis_only_is_refused():
    rows = [mc.MapRow(10.0, 0.0, {"axial_mass_flow": (0.1, 0.0), "dynamic_angle": (30.0, 0.0)})]
    with pytest.raises(SceneError, match="second incline"):
        mc.TransportLaw(mc.MachineMap(rows, SECTION, {}, 0.01))


def test_machine_command_refuses_bad_input_with_file_key_reason(tmp_path, capsys):
    from taichi_dem.app.cli import main
    assert main(["machine", str(tmp_path / "none.json"), "--length", "6 m",
                 "--feed", "1 t/h"]) == 2
    assert "cannot read the map" in capsys.readouterr().err
    old = tmp_path / "old.json"
    old.write_text('{"rows": []}')
    assert main(["machine", str(old), "--length", "6 m", "--feed", "1 t/h"]) == 2
    assert "no 'machine' section" in capsys.readouterr().err
    import json
    two = tmp_path / "two.json"
    rows = [{"holdup_kg_per_m": 20.0, "axial_slope": s, "axial_mass_flow": -0.1 + s,
             "axial_mass_flow_standard_error": 0.0, "dynamic_angle": 30.0,
             "dynamic_angle_standard_error": 0.0} for s in (-0.05, -0.09)]
    two.write_text(json.dumps({"machine": {"shell_radius": 0.2, "bulk_density": 1500.0,
                                           "particle_diameter": 0.004}, "rows": rows}))
    assert main(["machine", str(two), "--length", "6 m", "--feed", "1 t/h"]) == 2
    assert "--incline" in capsys.readouterr().err
    assert main(["machine", str(two), "--length", "six metres", "--feed", "1 t/h",
                 "--incline", "3"]) == 2
    assert "--length" in capsys.readouterr().err
    assert main(["machine", str(two), "--length", "6 m", "--feed", "1 t/h", "--incline", "3",
                 "--feed-over", "2 m", "1 m", "--out", str(tmp_path / "out")]) == 2
    assert "--feed-over" in capsys.readouterr().err


def screw_map(a=2.0, b=6.0):
    """A self-conveying section's map (an inlet screw): q = -c^3 (a - b s) at two inclines,
    towards -x as the drum_map's bed flows."""
    rows = []
    for d in (0.15, 0.3, 0.45, 0.6):
        h = d * R
        H = float(SECTION.holdup(h))
        c3 = float(SECTION.chord(h)) ** 3
        for s in (0.0, -math.tan(math.radians(5.0))):
            rows.append(mc.MapRow(H, s, {"axial_mass_flow": (-c3 * (a - b * s), 0.0),
                                         "dynamic_angle": (BETA, 0.0),
                                         "screw/torque_per_metre": (-3.0, 0.0)}))
    return mc.MachineMap(rows, SECTION, {}, 0.004, 1000.0, {}, ["screw"])


def test_a_machine_split_into_sections_of_one_map_is_the_same_machine():
    """Sections with their own maps (issue 31 item 3, the inlet screw): the depth is carried
    across each boundary, so one map cut into two sections gives the unsplit answers."""
    m = drum_map(shaft_torque=-2.0, conductance=150.0)
    slope = -math.tan(math.radians(THETA))
    whole = mc.answer(m, 12.0, 1.2, slope, 0.02, inlet_temperature=700.0, steps=800)
    split = mc.answer(m, 12.0, 1.2, slope, 0.02, inlet_temperature=700.0, steps=800,
                      inlet_sections=[(m, 4.0)])
    for name in ("holdup", "residence_time", "inlet_holdup", "outlet_temperature"):
        assert getattr(split, name) == pytest.approx(getattr(whole, name), rel=2e-3), name
    assert split.torques["shell"] == pytest.approx(whole.torques["shell"], rel=2e-3)
    assert split.profile.x[0] == pytest.approx(0.0) and split.profile.x[-1] == pytest.approx(12.0)
    assert np.all(np.diff(split.profile.x) >= 0)
    cap_whole = mc.capacity(m, 12.0, slope, 0.02)
    assert mc.capacity(m, 12.0, slope, 0.02, inlet_sections=[(m, 4.0)]) == \
        pytest.approx(cap_whole, rel=1e-2)


def test_an_inlet_screw_section_carries_the_feed_at_its_own_hold_up():
    # a screw that carries 20 c^3 kg/s on its own: ~6x the drum's Saeman flow at this bed
    drum, screw = drum_map(), screw_map(a=20.0)
    slope = -math.tan(math.radians(THETA))
    feed = 0.5
    plain = mc.answer(drum, 12.0, feed, slope, 0.02)
    with_screw = mc.answer(drum, 12.0, feed, slope, 0.02, inlet_sections=[(screw, 3.0)])
    # the screw's own plateau: c^3 (20 - 6 s) = feed
    c = (feed / (20.0 - 6.0 * slope)) ** (1 / 3)
    assert with_screw.profile.depth[0] == pytest.approx(R - math.sqrt(R * R - c * c / 4), rel=1e-2)
    assert with_screw.inlet_holdup < plain.inlet_holdup
    # the screw's torque over its 3 m only, from its own map (-3 N m per metre at the mapped
    # hold-ups, anchored at 0 for an empty machine)
    part = with_screw.profile.x <= 3.0
    hs, vs = mc._interpolate_figure(screw, "screw/torque_per_metre", slope)
    expected = np.trapezoid(np.interp(with_screw.profile.holdup[part], hs, vs),
                            with_screw.profile.x[part])
    assert with_screw.torques["screw"] == pytest.approx(expected, rel=1e-6)
    assert "screw" not in plain.torques
    # the drum part (x > 3 m) is the plain drum's last 9 m
    drum_part = with_screw.profile.x >= 3.0
    assert np.interp(6.0, with_screw.profile.x[drum_part], with_screw.profile.holdup[drum_part]) \
        == pytest.approx(np.interp(6.0, plain.profile.x, plain.profile.holdup), rel=0.05)


def test_bad_sections_are_refused():
    drum = drum_map()
    slope = -math.tan(math.radians(THETA))
    with pytest.raises(SceneError, match="not shorter than the machine"):
        mc.answer(drum, 12.0, 0.5, slope, inlet_sections=[(drum, 12.0)])
    backwards = screw_map(a=-2.0, b=6.0)            # conveys towards +x, against the drum
    for r in backwards.rows:
        q, _ = r.figures["axial_mass_flow"]
        r.figures["axial_mass_flow"] = (q + 100.0 * float(SECTION.chord(SECTION.depth(r.holdup)[0])) ** 3, 0.0)
    with pytest.raises(SceneError, match="opposite directions"):
        mc.answer(drum, 12.0, 0.5, slope, inlet_sections=[(backwards, 2.0)])


def test_a_section_the_incline_does_not_move_sits_at_its_own_plateau():
    """A screw whose mapped flow does not change with the incline beyond its noise (b within
    two standard errors of 0, negative at a hold-up): its hold-up is where its own flow carries
    the feed, flat along it; a b < 0 beyond the noise is refused."""
    rows = []
    for H, q in ((20.0, 1.0), (40.0, 2.2), (60.0, 3.0)):
        for s, dq in ((0.0, 0.0), (-math.tan(math.radians(5.0)), -0.01)):   # b = -0.11 kg/s
            rows.append(mc.MapRow(H, s, {"axial_mass_flow": (-(q + dq), 0.02),
                                         "dynamic_angle": (BETA, 0.0)}))
    screw = mc.MachineMap(rows, SECTION, {}, 0.004, None, {}, [])
    law = mc.TransportLaw(screw)
    assert law.plateau_only
    drum = drum_map()
    slope = -math.tan(math.radians(THETA))
    ans = mc.answer(drum, 12.0, 1.5, slope, 0.02, inlet_sections=[(screw, 2.0)])
    part = ans.profile.x < 2.0 - 1e-9         # (the drum's profile starts at 2 m)
    # 1.5 kg/s: between 0.995 at 20 and 2.195 at 40 kg/m (the inclines' mean)
    expected = 20.0 + 20.0 * (1.5 - 0.995) / (2.195 - 0.995)
    assert ans.profile.holdup[part] == pytest.approx(expected, rel=1e-6)
    for r in rows:                                 # the same b with no noise: refused
        r.figures["axial_mass_flow"] = (r.figures["axial_mass_flow"][0], 0.0)
    with pytest.raises(SceneError, match="falls with the slope"):
        mc.answer(drum, 12.0, 1.5, slope, 0.02, inlet_sections=[(screw, 2.0)])


# --- a modelling choice's map marched beside the main one (issue 31 item 5) -----------------

def _scaled(m, name, factor):
    """A copy of map ``m`` with figure ``name`` times ``factor`` in every row."""
    rows = [mc.MapRow(r.holdup, r.axial_slope,
                      {n: ((v * factor, se) if n == name else (v, se))
                       for n, (v, se) in r.figures.items()}) for r in m.rows]
    return mc.MachineMap(rows, m.section, m.angular_speeds, m.particle_diameter,
                         m.heat_capacity, m.wall_temperatures, m.bodies)


def test_a_choice_that_changes_nothing_moves_no_answer():
    m = drum_map(shaft_torque=-2.0, conductance=150.0)
    base = mc.with_errors(m, 12.0, [1.2], -math.tan(math.radians(THETA)), 0.02,
                          inlet_temperature=700.0, draws=3)
    same = mc.with_errors(mc.substituted(m, m), 12.0, [1.2], -math.tan(math.radians(THETA)),
                          0.02, inlet_temperature=700.0, draws=3)
    d = mc.choice_differences(base, same)
    assert d["capacity"]["change"] == 0.0
    for name in ("residence_time", "holdup", "outlet_temperature", "shell/torque"):
        assert d["feeds"][0][name]["change"] == 0.0


def test_a_choice_that_doubles_the_conductance_gives_the_closed_form_outlet():
    feed, length = 1.2, 12.0
    m = drum_map(shaft_torque=-2.0, conductance=150.0)
    choice = mc.substituted(m, _scaled(m, "shell/conductance_per_metre", 2.0))
    base = mc.with_errors(m, length, [feed], -math.tan(math.radians(THETA)), 0.02,
                          inlet_temperature=700.0, draws=3)
    other = mc.with_errors(choice, length, [feed], -math.tan(math.radians(THETA)), 0.02,
                           inlet_temperature=700.0, draws=3)
    d = mc.choice_differences(base, other)["feeds"][0]
    t1 = 300.0 + 400.0 * math.exp(-150.0 * length / (feed * 1000.0))
    t2 = 300.0 + 400.0 * math.exp(-300.0 * length / (feed * 1000.0))
    # 5e-3: the march's 400 steps and the conductance's anchor at an empty bed (at the
    # discharge) leave each outlet ~0.2 % off its closed form, the difference twice that
    assert d["outlet_temperature"]["change"] == pytest.approx(t2 - t1, rel=5e-3)
    assert d["residence_time"]["change"] == pytest.approx(0.0, abs=1e-9)
    text = mc.choices_report({"doubled": mc.choice_differences(base, other)})
    assert "| doubled | 4.32 |" in text


def test_a_choice_mapped_at_one_incline_shifts_the_other_and_keeps_the_slope_effect():
    m = screw_map()
    one = [r for r in m.rows if r.axial_slope != 0.0]          # the choice at 5 deg only
    faster = mc.MachineMap([mc.MapRow(r.holdup, r.axial_slope,
                                      {n: ((v * 1.5, se) if n == "axial_mass_flow" else (v, se))
                                       for n, (v, se) in r.figures.items()}) for r in one],
                           m.section, {}, 0.006, 1000.0, {}, ["screw"])
    sub = mc.substituted(m, faster)
    base_law, law = mc.TransportLaw(m), mc.TransportLaw(sub)
    np.testing.assert_allclose(law.b_per_chord3, base_law.b_per_chord3, rtol=1e-9)
    for r in sub.rows:         # at 5 deg the choice's flows, at 0 deg shifted by as much
        ref = next(x for x in m.rows if x.holdup == r.holdup and x.axial_slope == r.axial_slope)
        at5 = next(x for x in one if x.holdup == r.holdup)
        assert r.mean("axial_mass_flow") == pytest.approx(
            ref.mean("axial_mass_flow") + 0.5 * at5.mean("axial_mass_flow"), rel=1e-12)
    assert sub.particle_diameter == 0.006


def test_a_choice_without_the_main_maps_holdups_is_refused(tmp_path, capsys):
    m = drum_map()
    short = mc.MachineMap(m.rows[:2], m.section, m.angular_speeds, m.particle_diameter,
                          m.heat_capacity, m.wall_temperatures, m.bodies)
    with pytest.raises(SceneError, match="lacks the hold-up"):
        mc.substituted(m, short)


def test_machine_command_reports_each_choice(tmp_path, capsys):
    import json
    from taichi_dem.app.cli import main

    def write(m, path):
        rows = []
        for r in m.rows:
            row = {"holdup_kg_per_m": r.holdup, "axial_slope": r.axial_slope}
            for n, (v, se) in r.figures.items():
                row[n], row[n + "_standard_error"] = v, se
            rows.append(row)
        info = {"shell_radius": R, "shaft_radius": 0.0, "bulk_density": RHO_B,
                "particle_diameter": m.particle_diameter, "angular_speeds": m.angular_speeds,
                "wall_temperatures": m.wall_temperatures, "heat_capacity": m.heat_capacity,
                "bodies": m.bodies}
        path.write_text(json.dumps({"machine": info, "rows": rows}))
    m = drum_map(shaft_torque=-2.0, conductance=150.0)
    write(m, tmp_path / "map.json")
    write(_scaled(m, "shell/torque_per_metre", 1.1), tmp_path / "f64.json")
    assert main(["machine", str(tmp_path / "map.json"), "--length", "12 m", "--feed", "1.2 kg/s",
                 "--inlet-temperature", "700 K", "--draws", "3", "--choice", "f64",
                 str(tmp_path / "f64.json"), "--out", str(tmp_path / "out")]) == 0
    doc = json.loads((tmp_path / "out" / "machine.json").read_text())
    torque = doc["choices"]["f64"]["feeds"][0]["shell/torque"]
    assert torque["relative"] == pytest.approx(0.1, rel=1e-6)
    assert "What each modelling choice moves the answers by" in (
        tmp_path / "out" / "machine.md").read_text()


def test_a_feed_entering_over_a_stretch_ramps_the_flow_and_holds_less():
    """feed_entered: no flow upstream of the feed's stretch, all of it downstream, linear
    between; the march then holds less at the closed end than with the feed dropped there,
    and the same beyond the stretch. A stretch outside the machine is refused."""
    length, feed = 12.0, 1.2
    entered = mc.feed_entered(feed, length, (1.0, 3.0))      # from the inlet end
    assert entered(length - 0.5) == 0.0 and entered(length - 2.0) == pytest.approx(0.6)
    assert entered(length - 3.0) == pytest.approx(feed) and entered(0.0) == feed
    slope = -math.tan(math.radians(THETA))
    at_end = mc.answer(drum_map(), length, feed, slope, 0.02, steps=800)
    spread = mc.answer(drum_map(), length, feed, slope, 0.02, steps=800, feed_over=(1.0, 3.0))
    assert spread.holdup < at_end.holdup
    assert spread.profile.holdup[0] < at_end.profile.holdup[0]
    for x in (4.0, 8.0, 11.5):
        assert float(np.interp(x, spread.profile.x, spread.profile.holdup)) == pytest.approx(
            float(np.interp(x, at_end.profile.x, at_end.profile.holdup)), rel=1e-6)
    # the inlet end holds less, so more feed fits below the overflow
    assert mc.capacity(drum_map(), length, slope, 0.02, feed_over=(1.0, 3.0)) > mc.capacity(
        drum_map(), length, slope, 0.02)
    with pytest.raises(SceneError, match="feed-over"):
        mc.feed_entered(feed, length, (3.0, 1.0))
