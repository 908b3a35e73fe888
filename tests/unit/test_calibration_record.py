"""[materials.NAME.calibration] (issue 44 item 2): a scene that claims a calibrated material
says what it was calibrated against; ``check`` prints the record and notes where the scene
departs from it (another sphere size, a calibrated value changed, a record that missed its
targets); bad records are refused with the file, key and reason, as the schema refuses them."""
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from taichi_dem.errors import SceneError
from taichi_dem.scene import schema
from taichi_dem.scene.loader import load_scene
from taichi_dem.scene.sections.calibration import calibration_notes, describe_calibration

ROOT = Path(__file__).resolve().parents[2]
RECORD = ROOT / "docs" / "calibration" / "calibrated_material.toml"
SLICE = (ROOT / "demos" / "cooler_slice.toml").read_text()
VALIDATOR = schema.validator()


def _scene(tmp_path, text: str, name: str = "scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _with_record(text: str, block: str) -> str:
    """The slice with its calibration table replaced by ``block``."""
    start = text.index("[materials.ash.calibration]")
    end = text.index("[materials.steel]")
    return text[:start] + block + "\n\n" + text[end:]


def _schema_valid(path) -> bool:
    return VALIDATOR.is_valid(schema.json_compatible(tomllib.loads(Path(path).read_text())))


def test_the_slices_hold_the_calibrated_record_and_depart_from_nothing():
    """Every 15 mm seed-cooler scene claims the calibrated ash and gives its values."""
    for name in ("cooler_slice", "cooler_slice_optimised", "cooler_slice_screw",
                 "paddle_cooler_full"):
        scene = load_scene(str(ROOT / "demos" / f"{name}.toml"))
        c = scene.materials["ash"].calibration
        assert c is not None and c.within_scatter is True, name
        assert c.sphere_radius == (0.0075,)
        assert calibration_notes(scene) == [], name
    text = "\n".join(describe_calibration(scene))
    # the record's test, target and what was achieved, the values and the size
    record = tomllib.loads(RECORD.read_text())["materials"]["ash"]["calibration"]
    test = record["tests"][0]
    assert f"target {test['target']:.4g} +- {test['target_sd']:.2g} deg" in text
    assert f"achieved {test['achieved_mean']:.4g}" in text and "within the measured scatter" in text
    assert "ash-ash rolling_friction = 1.38" in text and "ash-steel rolling_friction = 1.5" in text
    assert "15 mm only" in text


def test_a_departure_from_the_record_is_noted(tmp_path):
    """Another sphere size and a changed calibrated value: each a note naming the key and
    both values, printed by check on stderr."""
    block = f'[materials.ash.calibration]\nrecord = "{RECORD}"'
    text = _with_record(SLICE, block).replace("radius = 0.0075", "radius = 0.01")
    i = text.index('pair = ["ash", "steel"]')
    text = text[:i] + text[i:].replace("rolling_friction = 1.5", "rolling_friction = 0.3", 1)
    path = _scene(tmp_path, text)
    notes = calibration_notes(load_scene(str(path)))
    reasons = " | ".join(r for _, r in notes)
    assert all(k == "materials.ash.calibration" for k, _ in notes)
    assert "calibrated for spheres of diameter 15 mm; this scene's 20 mm spheres" in reasons
    assert "ash-steel rolling_friction = 1.5, and the scene gives 0.3" in reasons
    assert "ash-ash" not in reasons                 # the ash-ash values are the record's
    out = subprocess.run([sys.executable, "-m", "taichi_dem", "check", str(path)],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "this scene's 20 mm spheres" in out.stderr and "material ash: calibrated" in out.stdout


def test_an_inline_record_and_a_missed_target(tmp_path):
    block = """[materials.ash.calibration]
date = "2026-01-01"
sphere_radius = [0.0075]
within_scatter = false
tests = [{ name = "bulk_density", unit = "kg/m3", target = 522.0, target_sd = 10.0, achieved_mean = 560.0, achieved = [555.0, 565.0], within_scatter = false }]
parameters = [{ key = "interactions.0.friction", value = 0.8, pair = ["ash", "ash"], field = "friction" }]"""
    path = _scene(tmp_path, _with_record(SLICE, block))
    assert _schema_valid(path)
    scene = load_scene(str(path))
    c = scene.materials["ash"].calibration
    assert c.tests[0].runs == 2 and c.tests[0].achieved_mean == 560.0
    text = "\n".join(describe_calibration(scene))
    assert "NOT within the measured scatter" in text
    notes = " | ".join(r for _, r in calibration_notes(scene))
    assert "missed a target" in notes and "friction" not in notes     # 0.8 is the scene's


def test_calibrated_against_in_words(tmp_path):
    block = ('[materials.ash.calibration]\nagainst = "by hand: a 1 m drum\'s dynamic angle, '
             '35 deg at 5 rpm, 2 runs"')
    path = _scene(tmp_path, _with_record(SLICE, block))
    assert _schema_valid(path)
    text = "\n".join(describe_calibration(load_scene(str(path))))
    assert "against: by hand" in text


@pytest.mark.parametrize("block, key, reason", [
    ("[materials.ash.calibration]\ndate = \"today\"", "materials.ash.calibration",
     "says nothing of what the material was calibrated against"),
    ('[materials.ash.calibration]\nrecord = "nowhere.toml"', "materials.ash.calibration.record",
     "file not found"),
    (f'[materials.ash.calibration]\nrecord = "{RECORD}"\ntests = [{{ name = "x" }}]',
     "materials.ash.calibration.tests", "the record comes from that file"),
    ('[materials.ash.calibration]\nagainst = "x"\nmaterial = "ash"',
     "materials.ash.calibration.material", "only with record"),
    ('[materials.ash.calibration]\nagainst = "x"\nsphere_radius = [-0.01]',
     "materials.ash.calibration.sphere_radius[0]", "must be > 0"),
    ('[materials.ash.calibration]\ntests = 3', "materials.ash.calibration.tests",
     "expected an array of tables"),
    ('[materials.ash.calibration]\ntests = [{ unit = "deg" }]',
     "materials.ash.calibration.tests[0].name", "required key is missing"),
    ('[materials.ash.calibration]\ntests = [{ name = "a", target = "high" }]',
     "materials.ash.calibration.tests[0].target", "expected a finite number"),
    ('[materials.ash.calibration]\nagainst = "x"\nparameters = [{ key = "k", value = 1, '
     'pair = ["ash"] }]', "materials.ash.calibration.parameters[0].pair",
     "expected 2 items, got 1"),
    ('[materials.ash.calibration]\nagainst = "x"\nparameters = [{ key = "k", value = 1, '
     'colour = 2 }]', "materials.ash.calibration.parameters[0].colour", "unknown key"),
    ('[materials.ash.calibration]\nagainst = "x"\ndesign = { points = 2.5 }',
     "materials.ash.calibration.design.points", "expected an integer"),
    ('[materials.ash.calibration]\nagainst = "x"\nspin = 1', "materials.ash.calibration.spin",
     "unknown key"),
])
def test_bad_records_are_refused_as_the_schema_refuses_them(tmp_path, block, key, reason):
    path = _scene(tmp_path, _with_record(SLICE, block))
    with pytest.raises(SceneError) as e:
        load_scene(str(path))
    assert e.value.key == key and reason in e.value.reason, str(e.value)
    if reason != "file not found":              # what a file holds: no schema can say
        assert not _schema_valid(path)


def test_a_record_file_without_the_material(tmp_path):
    other = tmp_path / "other.toml"
    other.write_text("[materials.sand]\ndensity = 2600.0\n")
    path = _scene(tmp_path, _with_record(SLICE, '[materials.ash.calibration]\n'
                                                'record = "other.toml"'))
    with pytest.raises(SceneError) as e:
        load_scene(str(path))
    assert "holds no [materials.ash.calibration]" in e.value.reason
    # a record file's own bad value is named in that file
    other.write_text('[materials.ash.calibration]\ntests = [{ name = "a", target = true }]\n')
    with pytest.raises(SceneError) as e:
        load_scene(str(path))
    assert e.value.file == str(other) and e.value.key == "materials.ash.calibration.tests[0].target"


def test_the_demos_inline_record_is_the_published_one():
    """The 15 mm scenes carry the record inline (a wheel's demos have no docs/ beside them):
    it must say what docs/calibration/calibrated_material.toml says, to its 4 digits."""
    full = tomllib.loads(RECORD.read_text())["materials"]["ash"]["calibration"]
    for name in ("cooler_slice", "cooler_slice_optimised", "cooler_slice_screw",
                 "paddle_cooler_full"):
        short = tomllib.loads((ROOT / "demos" / f"{name}.toml").read_text())[
            "materials"]["ash"]["calibration"]
        for key in ("date", "command", "spec", "sphere_radius", "within_scatter"):
            assert short[key] == full[key], (name, key)
        for a, b in zip(short["tests"], full["tests"]):
            for key in ("target", "target_sd", "achieved_mean", "achieved_sd", "achieved_sem"):
                assert a[key] == pytest.approx(b[key], rel=5e-4), (name, key)
            assert a["achieved"] == pytest.approx(b["achieved"], abs=5e-3)
        assert [(p["pair"], p["field"], p["value"]) for p in short["parameters"]] == \
            [(p["pair"], p["field"], p["value"]) for p in full["parameters"]]
        assert [(f["pairs"], f["value"]) for f in short["factors"]] == \
            [(f["pairs"], f["value"]) for f in full["factors"]]
