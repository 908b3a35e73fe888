"""Sweep overrides (taichi_dem/app/overrides.py) and the sweep's planning: no simulation runs
here. Parsing of --set values, cross product against --zip, keys applied to the TOML document
before the loader validates it (so a wrong key or value names the file and the key), the TOML
round trip of every demo scene, and the CLI's exit 2 without a traceback."""
import tomllib
from pathlib import Path

import pytest

from taichi_dem.app import overrides as ov
from taichi_dem.app import sweep, tradeoffs
from taichi_dem.app.cli import main
from taichi_dem.errors import SceneError
from taichi_dem.scene.loader import load_scene, parse_scene

HERE = Path(__file__).resolve().parent
BOX = HERE / "sweep_box.toml"
DEMOS = HERE.parents[1] / "demos"


def test_values_split_at_top_level_commas_and_parse_as_toml():
    s = ov.parse_set('simulation.gravity=[0, 0, -9.81],[0,0,-1.62]')
    assert s.key == "simulation.gravity"
    assert s.values == ([0, 0, -9.81], [0, 0, -1.62])
    s = ov.parse_set('factories.0.mass_rate="6.5 t/h",13 t/h , 0.5')
    assert s.values == ("6.5 t/h", "13 t/h", 0.5)
    s = ov.parse_set("simulation.precision=f32,f64")
    assert s.values == ("f32", "f64")
    s = ov.parse_set("thermal.conduction=true,false")
    assert s.values == (True, False)
    s = ov.parse_set('a.b="x, y",{ c = 1, d = 2 }')
    assert s.values == ("x, y", {"c": 1, "d": 2})


@pytest.mark.parametrize("arg", ["friction", "=0.3", "a..b=1", "a.b=1,,2", "a.b="])
def test_malformed_set_is_a_scene_error(arg):
    with pytest.raises(SceneError):
        ov.parse_set(arg)


def test_cross_product_and_zip():
    a = ov.parse_set("x.a=1,2,3")
    b = ov.parse_set("x.b=10,20")
    cross = ov.combinations([a, b])
    assert cross == [{"x.a": 1, "x.b": 10}, {"x.a": 1, "x.b": 20}, {"x.a": 2, "x.b": 10},
                     {"x.a": 2, "x.b": 20}, {"x.a": 3, "x.b": 10}, {"x.a": 3, "x.b": 20}]
    c = ov.parse_set("x.c=7,8,9")
    assert ov.combinations([a, c], zip_=True) == [{"x.a": 1, "x.c": 7}, {"x.a": 2, "x.c": 8},
                                                  {"x.a": 3, "x.c": 9}]
    with pytest.raises(SceneError, match="same number of values"):
        ov.combinations([a, b], zip_=True)
    with pytest.raises(SceneError, match="given twice"):
        ov.combinations([a, ov.parse_set("x.a=5")])
    assert ov.combinations([]) == [{}]


def test_apply_sets_nested_keys_and_creates_missing_leaves():
    doc = tomllib.loads(BOX.read_text())
    new = ov.apply(doc, {"interactions.1.friction": 0.9, "simulation.skin": 0.002,
                         "materials.glass.youngs_modulus": 1e6}, "box.toml")
    assert new["interactions"][1]["friction"] == 0.9
    assert new["interactions"][0]["friction"] == 0.5
    assert new["simulation"]["skin"] == 0.002
    assert new["materials"]["glass"]["youngs_modulus"] == 1e6
    assert doc["interactions"][1]["friction"] == 0.5          # the original is untouched
    scene = parse_scene(ov.to_text(new), source=str(BOX))
    assert scene.simulation.skin == 0.002
    assert scene.materials["glass"].youngs_modulus == 1e6


@pytest.mark.parametrize("key,value,words", [
    ("interactions.5.friction", 0.3, ["interactions.5.friction", "past the end", "2 entries"]),
    ("interactions.first.friction", 0.3, ["index it with a number"]),
    ("simulation.seed.x", 1, ["not a table"]),
])
def test_structural_errors_name_file_and_key(key, value, words):
    with pytest.raises(SceneError) as e:
        ov.apply(tomllib.loads(BOX.read_text()), {key: value}, str(BOX))
    assert e.value.file == str(BOX)
    for w in words:
        assert w in str(e.value)


@pytest.mark.parametrize("key,value,loader_key,words", [
    ("interactions.0.friciton", 0.3, "interactions[0].friciton", ["did you mean 'friction'"]),
    ("simulation.rayleigh_fraction", 3.0, "simulation.rayleigh_fraction", ["must be in (0, 1]"]),
    ("materials.glass.youngs_modulus", "hard", "materials.glass.youngs_modulus", []),
    ("mobility.mode", "frozen", "mobility.mode", ["at_rest"]),
])
def test_loader_errors_name_file_key_and_the_set(key, value, loader_key, words):
    """The loader validates the overridden document: its message names the scene file, the
    key (the loader's spelling) and which --set caused it."""
    combos = [{key: value}]
    with pytest.raises(SceneError) as e:
        sweep.plan(str(BOX), combos)
    err = e.value
    assert err.file == str(BOX)
    assert err.key == loader_key
    assert f"--set {key}=" in err.reason
    for w in words:
        assert w in err.reason


def test_plan_seeds_ids_and_duration():
    combos = ov.combinations([ov.parse_set("interactions.0.friction=0.3,0.5")])
    specs = sweep.plan(str(BOX), combos, seeds=3, duration=0.02)
    assert [(s.overrides["interactions.0.friction"], s.seed) for s in specs] == [
        (0.3, 1), (0.3, 2), (0.3, 3), (0.5, 1), (0.5, 2), (0.5, 3)]
    assert len({s.id for s in specs}) == 6
    assert all(s.until == 0.02 for s in specs)
    scene = parse_scene(specs[4].text, source=str(BOX))
    assert scene.simulation.seed == 2
    assert scene.interactions[frozenset(("glass",))].friction == 0.5
    # the same plan again gives the same ids (a restarted sweep finds its runs)
    assert [s.id for s in sweep.plan(str(BOX), combos, seeds=3, duration=0.02)] == [s.id for s in specs]
    # another duration is another run
    assert sweep.plan(str(BOX), combos[:1], duration=0.03)[0].id != specs[0].id
    with pytest.raises(SceneError, match="--seeds"):
        sweep.plan(str(BOX), [{"simulation.seed": 4}], seeds=2)


def _same(a, b) -> bool:
    """Field-by-field equality (some scene dataclasses compare by identity; arrays inside)."""
    import dataclasses
    import numpy as np
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(_same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, (tuple, list)):
        return isinstance(b, (tuple, list)) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and np.array_equal(a, b)
    return a == b


@pytest.mark.parametrize("demo", sorted(p.name for p in DEMOS.glob("*.toml")))
def test_every_demo_scene_survives_the_toml_round_trip(demo):
    """Overrides go through tomli-w: the re-written text must load to the same scene."""
    path = DEMOS / demo
    a = load_scene(path)
    b = parse_scene(ov.to_text(tomllib.loads(path.read_text())), source=str(path))
    for field in ("simulation", "domain", "materials", "interactions", "fills", "walls",
                  "factories", "outlets", "sensors", "settings", "output", "bodies"):
        assert _same(getattr(a, field), getattr(b, field)), field
    assert not _same(a.simulation, parse_scene(ov.overridden_text(
        path.read_text(), {"simulation.seed": 77}, str(path)), source=str(path)).simulation)


@pytest.mark.parametrize("args,words", [
    (["--set", "interactions.0.friciton=0.3,0.5"], ["sweep_box.toml", "interactions[0].friciton",
                                                   "did you mean 'friction'"]),
    (["--set", "interactions.7.friction=0.3"], ["sweep_box.toml", "interactions.7.friction",
                                               "past the end"]),
    (["--set", "simulation.precision=f16"], ["simulation.precision", "\"f32\" or \"f64\""]),
    (["--set", "friction"], ["expected KEY=V1,V2"]),
    (["--set", "interactions.0.friction=0.3,0.5", "--set", "simulation.end_time=0.01", "--zip"],
     ["--zip needs the same number of values"]),
    (["--seeds", "0"], ["--seeds", "must be >= 1"]),
])
def test_cli_bad_input_exits_2_without_traceback(args, words, capsys, tmp_path):
    """Validation happens before any cluster starts: bad input is exit 2, one message."""
    code = main(["sweep", str(BOX), "--out", str(tmp_path / "s"), "--quiet"] + args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert err.startswith("taichi-dem: ")
    for w in words:
        assert w in err


def test_tradeoffs_unknown_knob_exits_2(capsys, tmp_path):
    code = main(["tradeoffs", str(BOX), "--knobs", "timestep,colour", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and "colour" in err and "unknown knob" in err and "Traceback" not in err


def test_tradeoff_planning_timestep_modulus_and_hooks():
    """Knob variants as planned: dt multiples of the automatic dt, softened moduli with and
    without the conduction correction in a thermal scene, the hooks skipped with reasons."""
    import sys
    sys.path.insert(0, str(HERE))
    from resume_scene import scene_text
    ref, variants, skipped = tradeoffs.plan_study(str(BOX), ["timestep", "mobility", "time_scale"],
                                                  seeds=1, duration=0.02)
    info = tradeoffs.step_info(parse_scene(ref[0].text, source=str(BOX)))
    timestep = [v for v in variants if v.labels["knob"] == "timestep"]
    dts = [parse_scene(v.text, source=str(BOX)).simulation.dt for v in timestep]
    assert dts == pytest.approx([f * info["dt"] for f in (0.5, 1.5, 2.0, 2.4)], rel=1e-12)
    assert all(parse_scene(v.text, source=str(BOX)).simulation.precision == "f64" for v in variants)
    # mobility (issue 12) is a knob now: its variant enables it
    assert "mobility: enabled" not in skipped
    mobility = [v for v in variants if v.labels["knob"] == "mobility"]
    assert len(mobility) == 1 and parse_scene(mobility[0].text, source=str(BOX)).settings.get("mobility") is not None
    assert "no [thermal]" in skipped["time_scale"]

    import os
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "hot.toml")
        Path(path).write_text(scene_text(precision="f32", speed="10 rpm", count=100))
        _, variants, skipped = tradeoffs.plan_study(path, ["modulus", "time_scale"], 1, 0.02)
        settings = [v.labels["setting"] for v in variants]
        assert settings == ["E/10, corrected", "E/10, uncorrected", "E/100, corrected",
                            "E/100, uncorrected", "E/1000, corrected", "E/1000, uncorrected",
                            "x10", "x100"]
        # thermal.time_scale (issue 10) is a knob of thermal scenes now
        assert not any(k.startswith("time_scale") for k in skipped)
        for v in variants[6:]:
            assert parse_scene(v.text, source=path).settings.get("thermal").time_scale in (10.0, 100.0)
        for v in variants[:6]:
            s = parse_scene(v.text, source=path)
            glass = s.materials["glass"]
            factor = int(v.labels["setting"].split(",")[0][2:])
            assert glass.youngs_modulus == pytest.approx(1e7 / factor)
            assert s.materials["steel"].youngs_modulus == 2e11        # walls not softened
            if "uncorrected" in v.labels["setting"]:
                assert s.settings.get("thermal").contact_radius_correction == "none"
            else:
                assert glass.real_youngs_modulus == pytest.approx(1e7)


def test_explicit_dt_follows_softening_and_coarse_graining():
    """The cooler gives dt = 1.2e-4 s explicitly: a softer modulus scales it as the Hertz
    contact time (factor^0.4), coarser particles by the radius factor; with an automatic dt
    (the box) no dt is set."""
    cooler = str(DEMOS / "paddle_cooler.toml")
    _, variants, skipped = tradeoffs.plan_study(cooler, ["modulus", "size"], 1, 1.0)
    assert not skipped
    got = {v.labels["setting"]: parse_scene(v.text, source=cooler) for v in variants}
    assert got["E/100, corrected"].simulation.dt == pytest.approx(1.2e-4 * 100 ** 0.4)
    assert got["E/10, uncorrected"].simulation.dt == pytest.approx(1.2e-4 * 10 ** 0.4)
    assert got["radius x2"].simulation.dt == pytest.approx(2.4e-4)
    assert got["radius x2"].factories[0].radius.mean == pytest.approx(0.03)
    # the cooler gives no real_youngs_modulus: the correction refers to the reference's E
    ref_e = load_scene(cooler).materials["ash"].youngs_modulus
    assert got["E/100, corrected"].materials["ash"].real_youngs_modulus == pytest.approx(ref_e)
    assert got["E/100, corrected"].materials["ash"].youngs_modulus == pytest.approx(ref_e / 100)
    assert got["E/100, uncorrected"].settings.get("thermal").contact_radius_correction == "none"
    _, variants, _ = tradeoffs.plan_study(str(BOX), ["modulus", "size"], 1, 0.02)
    assert all("simulation.dt" not in v.overrides for v in variants)
