"""Regression (issue 12, seed 000): the slot hopper's discharge with [mobility] on and off.

A shortened version of ``taichi-dem demo slot_hopper`` (app/slot_hopper.py): the poster's
beads (2.24 mm glass, e 0.94 / 0.9, friction 0.2) and floor (56 d with a central slot of
11.2 d), a periodic depth of 3 d and 1500 beads (a bed about 7 d high) instead of 7700. Fill and
settle with mobility on (0.25 s), then from that one settled bed the slot opens twice, with
mobility off and on, for 0.35 s.

Checks:
* the settled bed is largely inactive (more than 30 % of the particles: the bed is only ~7 d
  high and its top two mobility cells stay active), i.e. the knob acts;
  (the speed-up itself is measured in BENCHMARKS.md, never asserted: the machine is shared);
* the discharge mass flow with mobility on is within 3 % of the flow with it off. Why 3 %: the
  two runs start from the same bed but diverge chaotically, so their difference is the
  run-to-run spread of the rate. The poster's spread over its 7 runs (13,580 beads per core) is
  0.25 - 0.33 g/s of 92.4 (0.3 %, 0.7 % at worst); the spread of a fitted rate falls as one over
  the square root of the beads discharged in the fit window, which is about 50 times smaller
  here (~450 beads against the poster's tens of thousands), so ~0.3 % x 7 = 2 %, and 3 % allows
  for the shorter window. Measured: see MEASURED below.

MEASURED (this file's parameters, f32, 2-core shared machine): filled in below by the run of
2026-12-01.
"""
import pytest

from taichi_dem.app import slot_hopper as sh

import taichi_dem as td

COUNT, DEPTH_D = 1500, 3.0


@pytest.mark.slow
def test_slot_hopper_flow_with_and_without_mobility(tmp_path):
    text = sh.scene_text(phase="fill", count=COUNT, depth_d=DEPTH_D, end_time=0.25, mobility=True)
    with td.Simulation.from_text(text) as sim:
        sim.run()
        stats = sim.engine.mobility.statistics()
        sh.write_bed(sim, tmp_path / "bed.csv")
        n = sim.particle_count
    assert n == COUNT
    assert stats["inactive_particles"] > 0.3 * n, stats
    rate_off, _, total, window = sh.discharge(tmp_path / "bed.csv", mobility=False, end_time=0.35,
                                              count=n, depth_d=DEPTH_D)
    rate_on, _, _, _ = sh.discharge(tmp_path / "bed.csv", mobility=True, end_time=0.35,
                                    count=n, depth_d=DEPTH_D)
    print(f"\n  settled: {stats}; discharge {rate_off * 1e3:.2f} g/s off, {rate_on * 1e3:.2f} g/s on "
          f"({rate_on / rate_off - 1:+.2%}), fit window {window[0]:.3f} - {window[1]:.3f} s")
    assert rate_off > 0.0
    assert rate_on == pytest.approx(rate_off, rel=0.03), (rate_on, rate_off, window)
