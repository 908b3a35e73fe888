"""A scene with only its values changed compiles nothing new (issue 45 item 1).

bench/compile_probe.py builds a scene in a fresh process per variant against one private
Taichi kernel cache and counts the compiled kernels the cache gains; a kernel that closed over
a scene value (gravity, the domain, a body's speed, a count) would be compiled again and
counted. The scene is a periodic drum slice with a flighted mesh (the most kernels: the pair,
mesh and binning paths, runs of steps), 50 steps so that the lists are built and rebuilt.
Kernels a variant runs that no earlier variant ran (another path: a rebuild on another step)
are told apart by name and not counted as recompiled."""
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import compile_probe  # noqa: E402

VARIANTS = ["simulation.gravity=[-0.8,0.0,-9.7]",        # a kernel constant before
            "bodies.0.motion.rotate.speed=30 rpm",
            "particles.0.count=+20",                        # within the slots' bucket
            "domain.max=[0.02,0.06,0.06]",                   # another grid of cells
            # a small dt: the skin follows it, so smaller cells, more of them, and more
            # triangle items (35 kernels compiled again before the cell arrays and the
            # triangles' list were sized for any skin)
            "simulation.dt=1e-5",
            # another mesh: more triangles within their slots' floor (15 kernels compiled
            # again before the triangles' arrays had bucketed slots)
            "bodies.0.mesh.flights=6"]


@pytest.mark.slow
def test_changed_values_compile_nothing_new():
    with tempfile.TemporaryDirectory() as cache:
        rows = compile_probe.run(str(ROOT / "tests" / "unit" / "slice_drum.toml"), VARIANTS,
                                 50, cache)
    first, warm = rows[0], rows[1]
    assert first["new_kernels"] > 20            # the cache was cold: the probe counts
    assert warm["new_kernels"] == 0
    for row in rows[2:]:
        assert row["recompiled"] == 0, (row["variant"], row["new_kernels"], row["first_used"])


@pytest.mark.slow
def test_a_changed_thermal_time_scale_or_gas_compiles_nothing_new(tmp_path):
    """The thermal time scale S (and with it the thermal step S dt) is read at run time: the
    temperature update, its stability sum and the radiation's booking compiled it in before
    (2 kernels of the main demo compiled again for S = 2); so is the fixed gas of the
    convection (its temperature compiled in before). The scene: the resume tests' small hot
    bed with its paddle, the gas and the wall conduction."""
    sys.path.insert(0, str(ROOT / "tests" / "unit"))
    from resume_scene import scene_text
    scene = tmp_path / "hot.toml"
    scene.write_text(scene_text("f32", count=100))
    with tempfile.TemporaryDirectory() as cache:
        rows = compile_probe.run(str(scene), ["thermal.time_scale=4.0", "thermal.time_scale=12.5",
                                              "thermal.gas.temperature=320.0"], 30, cache)
    assert rows[0]["new_kernels"] > 20 and rows[1]["new_kernels"] == 0
    for row in rows[2:]:
        assert row["recompiled"] == 0, (row["variant"], row["new_kernels"], row["first_used"])


@pytest.mark.slow
def test_changed_drying_and_plug_flow_gas_values_compile_nothing_new():
    """The dryer demo (drying, radiation, the axial plug-flow gas with its drag): the drying
    constants and the gas stream's values are read at run time (one kernel each compiled again
    before: the gather, the gas's exchange)."""
    with tempfile.TemporaryDirectory() as cache:
        rows = compile_probe.run(str(ROOT / "demos" / "dryer_drum.toml"),
                                 ["thermal.evaporation_temperature=360.0",
                                  "thermal.latent_heat=2.3e6",
                                  "thermal.gas.inlet_temperature=700 C",
                                  "thermal.gas.mass_flow=0.3 kg/s",
                                  "thermal.time_scale=2.0"], 20, cache)
    assert rows[0]["new_kernels"] > 20 and rows[1]["new_kernels"] == 0
    for row in rows[2:]:
        assert row["recompiled"] == 0, (row["variant"], row["new_kernels"], row["first_used"])


@pytest.mark.slow
def test_a_changed_critical_moisture_or_radiation_temperature_compiles_nothing_new(tmp_path):
    """The dryer demo with a falling-rate period (critical moisture 0.01) and radiation to an
    enclosure at 900 K: the critical moisture and the enclosure's temperature are read at run
    time (each compiled the gather again before). Whether there is a falling rate at all
    (X_cr > 0) is still compiled in."""
    import tomllib
    from taichi_dem.app import overrides
    demo = ROOT / "demos" / "dryer_drum.toml"
    doc = overrides.apply(tomllib.loads(demo.read_text()),
                          {"thermal.critical_moisture": 0.01, "thermal.radiation_to": 900.0},
                          str(demo))
    scene = tmp_path / "dryer_falling_rate.toml"
    scene.write_text(overrides.to_text(doc))
    with tempfile.TemporaryDirectory() as cache:
        rows = compile_probe.run(str(scene), ["thermal.critical_moisture=0.02",
                                              "thermal.radiation_to=1000.0"], 20, cache)
    assert rows[0]["new_kernels"] > 20 and rows[1]["new_kernels"] == 0
    for row in rows[2:]:
        assert row["recompiled"] == 0, (row["variant"], row["new_kernels"], row["first_used"])
