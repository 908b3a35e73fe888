"""Regression (issue 12, seed 000): the slot hopper's discharge with [mobility] on and off.

A shortened version of ``taichi-dem demo slot_hopper`` (app/slot_hopper.py): the poster's
beads (2.24 mm glass, e 0.94 / 0.9, friction 0.2) and slot (11.2 d), a floor 34 d wide
instead of 56 d, a periodic depth of 3 d and 1750 beads (a bed about 15 d high) instead of 7700. Fill and
settle with mobility on (0.25 s), then from that one settled bed the slot opens twice, with
mobility off and on, for 0.35 s.

Checks:
* the settled bed is largely inactive (more than 30 % of the particles: the top two mobility
  cells stay active), and more than 10 % are still inactive when the slot opens: the test is
  that mobility wakes a frozen bed over an opening (a bed left frozen would not flow or would
  start late: the rates below would differ). In this narrow hopper (34 d) nothing stays
  inactive once the flow runs (measured: 0 at every later sample), so this is a test of the
  opening, not of frozen dead zones;
  (the speed-up itself is measured in BENCHMARKS.md, never asserted: the machine is shared);
* the discharge mass flow with mobility on is within 6 % of the flow with it off. Why 6 %: the
  two runs start from the same bed but diverge chaotically, so their difference is the
  run-to-run spread of the rate. Measured (2026-12-02, this file's parameters): the settled bed
  moved by 1e-9 m (round-off) at random, five times, and each bed discharged with mobility off
  (six runs: 78.17 - 81.24 g/s, std 1.11) and on (four runs: 79.40 - 82.27, std 1.19): one
  run's rate scatters by 1.45 % (pooled), the difference of two runs by sqrt(2) x 1.45 = 2.0 %,
  and 6 % is three of those. (Only the mean difference, 80.71 against 79.67 g/s, +1.3 %, is
  a statement about mobility: within 1.4 standard errors of zero. A tolerance of 3 % failed
  when a change of the order of floating-point additions alone - partner shares summed in
  another order - moved the rate off by 2.3 %.) A bed that stayed frozen over the slot would
  not flow at that rate at all.

MEASURED (this file's parameters, f32, 2-core shared machine, 2026-12-01, 39 - 60 s): settled
bed 1276 of 1750 inactive, 544 still inactive when the slot opened, none at any later sample;
discharge 80.26 g/s off, 79.34 g/s on (-1.15 %): a difference that comes from the first 5 ms
alone, i.e. the chaotic spread this tolerance is sized for. 2026-12-02 (the serial mode's
partner shares added directly, engine/stepper.py): 79.00 g/s off, 82.27 on (+4.1 %).
"""
import pytest

from taichi_dem.app import slot_hopper as sh

import taichi_dem as td

COUNT, DEPTH_D, WIDTH_D = 1750, 3.0, 34.0


@pytest.mark.slow
def test_slot_hopper_flow_with_and_without_mobility(tmp_path):
    geometry = dict(count=COUNT, depth_d=DEPTH_D, width_d=WIDTH_D)
    text = sh.scene_text(phase="fill", end_time=0.25, mobility=True, **geometry)
    with td.Simulation.from_text(text) as sim:
        sim.run()
        stats = sim.engine.model.effect("mobility").statistics()
        sh.write_bed(sim, tmp_path / "bed.csv")
        n = sim.particle_count
    assert n == COUNT
    assert stats["inactive_particles"] > 0.3 * n, stats
    rate_off, _, total, window = sh.discharge(tmp_path / "bed.csv", mobility=False, end_time=0.35,
                                              **geometry)
    rate_on, _, _, _ = sh.discharge(tmp_path / "bed.csv", mobility=True, end_time=0.35, **geometry)
    inactive = sh.discharge.inactive
    print(f"\n  settled: {stats}; inactive while discharging {inactive}; discharge {rate_off * 1e3:.2f} g/s off, {rate_on * 1e3:.2f} g/s on "
          f"({rate_on / rate_off - 1:+.2%}), fit window {window[0]:.3f} - {window[1]:.3f} s")
    # the slot opened under a frozen bed: mobility must wake it (the cells over the floor touch
    # the empty cells under it), else the flow starts late or never
    assert inactive[0] > 0.1 * n, inactive
    assert rate_off > 0.0
    assert rate_on == pytest.approx(rate_off, rel=0.06), (rate_on, rate_off, window)
