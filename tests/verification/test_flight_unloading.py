"""The flights of the dryer slice unload as the geometric model of the rotary-dryer literature
says (app/flights.py; PHYSICS.md, "Flighted rotary dryers"): a slice of the dryer demo's drum
(1 m, 8 L-flights of 80 mm with a 40 mm lip, 8 rpm, 4.7 deg) at 10 % fill, three spheres of
24 mm thick, run 12 s (1.5 turns) by `taichi-dem map`'s run_slice.

1. The shape. The measured load against the flight's angle follows the model (the solids
   behind a surface through the lip's tip at Schofield & Glikin's kinetic angle) with its one
   parameter, the dynamic friction mu, fitted: the root-mean-square difference is within 10 %
   of a full flight's load. Tolerance: the surface of a heap of spheres is rough by about a
   radius; a layer one radius deep along the full flight's surface (about 60 mm here) is 10 %
   of its 0.007 m^2.
2. The end of the unloading. The last solids sit on the lip, which tilts down past the top;
   they go when its tilt passes the kinetic angle, at 90 deg + gamma. The material's own
   angle of repose, measured on a heap (demos/dryers/aggregate_heap.toml: 19.8 deg), gives
   gamma there without any fit: the flight is measured empty (the first bin of 7.5 deg whose
   mean load is under 5 % of the first's) within one bin of the model's angle.
   This holds for these free-rolling spheres only: the calibrated aggregate's slices
   (heap 38.9 deg, rule 129-130 deg) empty their flights in the same bin, 108.75 deg
   (docs/machine/dryer_slice/flights.md), so the agreement here does not show that the
   heap's angle sets the end; at this size the lip (1.7 diameters) may.

What the spheres do not follow (docs/machine/dryer_slice/flights.md): in the pocket, walled in
by the leg, the lip and the shell three to seven spheres across, they stand far steeper than on
an open heap - the fitted mu is 1.1 - 1.5 where the heap gives 0.36 - so the model needs the
fitted angle, not the heap's, before the last solids.
"""
import math
import tomllib
from pathlib import Path

import pytest

from taichi_dem.app import flights as fl
from taichi_dem.app.machine import parse_holdup
from taichi_dem.app.overrides import apply, to_text
from taichi_dem.app.slice_map import run_slice

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "demos" / "dryers" / "dryer_slice.toml"
THICK = 0.072                      # three diameters of the 24 mm spheres
HEAP_ANGLE_DEG = 19.8              # demos/dryers/aggregate_heap.toml, measured (its header)


@pytest.fixture(scope="module")
def unloading():
    doc = apply(tomllib.loads(SCENE.read_text()), {
        "domain.max": [THICK, 0.52, 0.52], "bodies.0.mesh.length": THICK,
        "particles.0.region.box.max": [THICK, 0.3, -0.1]}, str(SCENE))
    result = run_slice(to_text(doc), str(SCENE), parse_holdup("10 %"), 12.0,
                       base_dir=SCENE.parent, incline=4.7)
    assert result.flight_unloading is not None
    return result.flight_unloading


def test_the_load_follows_the_geometric_model_with_one_fitted_friction(unloading):
    assert unloading["rms_difference_of_full"] <= 0.10, unloading
    # loaded from the start, and empty long before the flight comes down again
    first = unloading["load_kg_per_m"][0]
    late = [m for a, m in zip(unloading["flight_angle_deg"], unloading["load_kg_per_m"])
            if a > 130.0]
    assert first > 5.0 and late and max(late) < 0.05 * first


def test_the_flight_is_empty_where_the_heap_angle_says(unloading):
    flights = fl.Flights(8, 0.5, 0.08, 0.04)
    mu = math.tan(math.radians(HEAP_ANGLE_DEG))
    expected = math.degrees(fl.final_discharge_angle(flights, mu, unloading["froude"]))
    assert 105.0 < expected < 112.0          # 90 + 19.8, a little less at Fr 0.03
    assert abs(unloading["final_discharge_angle_deg"] - expected) <= fl.BIN_WIDTH_DEG, unloading
