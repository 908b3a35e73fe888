"""The size study of the seed's cooler (issue 44 item 3, bench/size_convergence.py): each size's
slice is the published 15 mm slice with only the sphere radius, the time step and the values
its own calibration chose changed, carries that calibration's record, and is read by the size
verdict the way its docstring says."""
import importlib.util
import math
import tomllib
from pathlib import Path

import pytest

from taichi_dem.scene.loader import load_scene
from taichi_dem.scene.sections.calibration import calibration_notes

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("size_convergence", ROOT / "bench" / "size_convergence.py")
sc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sc)
SIZES = [mm for mm in (10, 20) if (sc.CALIBRATIONS / f"{mm}mm" / "calibrated_material.toml").is_file()]


@pytest.mark.parametrize("mm", SIZES)
def test_the_committed_scene_is_what_the_script_writes(mm):
    assert (sc.SCENES / f"cooler_slice_{mm}mm.toml").read_text() == sc.slice_scene(mm)


@pytest.mark.parametrize("mm", SIZES)
def test_a_size_changes_only_radius_step_and_calibrated_values(mm):
    base = tomllib.loads(sc.BASE.read_text())
    sized = tomllib.loads(sc.slice_scene(mm))
    cal = sc.calibrated(mm)
    assert sized["particles"][0]["radius"] == pytest.approx(mm / 2000)
    # the step scales with the radius (the Hertz contact time ~ R), to 3 digits
    assert sized["simulation"]["dt"] == pytest.approx(7e-5 * mm / 15, rel=2e-3)
    assert sized["materials"]["ash"]["calibration"] == cal["materials"]["ash"]["calibration"]
    for pair in sized["interactions"]:
        mine = next(i for i in cal["interactions"] if sorted(i["pair"]) == sorted(pair["pair"]))
        for k in ("friction", "rolling_friction", "model", "restitution"):
            assert pair[k] == mine[k], (pair["pair"], k)
    # everything else is the 15 mm slice's
    for section in ("simulation", "particles", "materials", "interactions"):
        sized.pop(section), base.pop(section)
    assert sized == base


@pytest.mark.parametrize("mm", SIZES)
def test_the_scene_loads_and_its_record_is_for_its_size(mm):
    scene = load_scene(str(sc.SCENES / f"cooler_slice_{mm}mm.toml"))
    notes = calibration_notes(scene)
    assert not any("another material" in reason for _, reason in notes), notes      # its size
    assert not any("does not hold" in reason for _, reason in notes), notes         # its values
    # a record that missed its target says so in the scene that carries it
    missed = not sc.calibration_json(mm)["within_scatter"]
    assert missed == any("not calibrated" in reason for _, reason in notes), notes


def test_the_verdict():
    # 15 -> 10 mm moves 1.0 against a combined noise of 0.5: 2.0 standard errors, on the line:
    # within the noise; the value's error is the step, 1.0 of 11.0 (9 %): converged
    v = sc.verdict({20: (8.0, 0.3), 15: (10.0, 0.3), 10: (11.0, 0.4)})
    assert v["step_sigmas"] == pytest.approx(2.0)
    assert v["status"] == "converged" and v["converged"]
    assert v["value"] == 11.0 and v["error"] == pytest.approx(1.0)
    assert v["step_20_15_relative"] == pytest.approx(0.25)
    # beyond two standard errors: not converged, no value
    v = sc.verdict({15: (10.0, 0.3), 10: (11.2, 0.4)})
    assert v["status"] == "not converged" and not v["converged"]
    assert "value" not in v and "extrapolated" not in v
    assert v["step_15_10_relative"] == pytest.approx(0.12)
    # a noisy 10 mm value on the 15 mm one: its own noise is the error, 8 % of it: converged
    v = sc.verdict({15: (10.0, 0.3), 10: (10.1, 0.8)})
    assert v["converged"] and v["error"] == pytest.approx(0.8)
    # the same step under twice the noise (16 %): it shows nothing either way
    v = sc.verdict({15: (10.0, 0.6), 10: (10.1, 1.6)})
    assert v["status"] == "within the noise" and not v["converged"]
    assert v["value"] == 10.1 and v["error"] == pytest.approx(1.6)
    # steps of one sign that shrink: 8 -> 10 -> 10.8 (2.8 standard errors), r = 0.4: the rest
    # 0.8 * 0.4 / 0.6
    v = sc.verdict({20: (8.0, 0.2), 15: (10.0, 0.2), 10: (10.8, 0.2)})
    assert v["status"] == "not converged"
    assert v["extrapolated"] == pytest.approx(10.8 + 0.8 * 0.4 / 0.6)
    assert v["extrapolated_error"] == pytest.approx(0.8 * 0.4 / 0.6)
    # a series shrinking slower than by half (r = 0.6) extrapolates noise: none
    assert "extrapolated" not in sc.verdict({20: (8.0, 0.3), 15: (10.0, 0.3), 10: (11.2, 0.4)})
    # a step that grows, or turns back, is no series to sum
    assert "extrapolated" not in sc.verdict({20: (9.5, 0.1), 15: (10.0, 0.1), 10: (11.2, 0.1)})
    assert "extrapolated" not in sc.verdict({20: (12.0, 0.1), 15: (10.0, 0.1), 10: (11.2, 0.1)})
    assert "step_sigmas" not in sc.verdict({20: (1.0, 0.1), 15: (1.0, 0.1)})
    assert math.isnan(sc.value({}, "axial_speed", 1.0)[0])
