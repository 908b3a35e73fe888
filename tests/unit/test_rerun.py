"""The rerun recorder: what a .rrd holds, read back with rerun's own reader (rerun.chunk)."""
import subprocess
import sys
from collections import defaultdict

import numpy as np
import pyarrow as pa
import pytest

rr = pytest.importorskip("rerun")
from rerun.chunk import RrdReader  # noqa: E402

import taichi_dem as td  # noqa: E402
from taichi_dem.bodies.kinematics import rotation_matrix  # noqa: E402
from taichi_dem.recorders.rerun import RerunRecorder, colormap  # noqa: E402

from conftest import PLATE_SCENE  # noqa: E402


# the conftest paddle scene with the axis point off the origin
PLATE_SCENE = PLATE_SCENE.replace("axis_point = [0, 0, 0]", "axis_point = [0, 0.01, 0]")


def read_rrd(path):
    """{entity: {"static": set of components, "temporal": set, "sim_time": [times]}} and the
    chunks, per entity, as pyarrow tables of their temporal rows."""
    reader = RrdReader(path)
    assert len(reader.recordings()) == 1
    entities = defaultdict(lambda: {"static": set(), "temporal": set(), "sim_time": [],
                                    "batches": []})
    for chunk in reader.stream().to_chunks():
        e = entities[chunk.entity_path.lstrip("/")]
        batch = chunk.to_record_batch()
        names = [n for n in batch.schema.names if ":" in n]
        if chunk.is_static:
            e["static"].update(names)
            e["static_batch"] = batch
        else:
            e["temporal"].update(names)
            assert "sim_time" in chunk.timeline_names
            e["sim_time"] += [ns * 1e-9 for ns in sim_time_ns(batch)]
            e["batches"].append(batch)
    return reader, entities


def sim_time_ns(batch):
    """The sim_time column (a duration) as integer nanoseconds."""
    return batch.column("sim_time").cast(pa.int64()).to_pylist()


def test_rrd_content_particles_bodies_series(tmp_path):
    path = tmp_path / "plate.rrd"
    rec = RerunRecorder(str(path))
    with td.Simulation.from_text(PLATE_SCENE) as sim:
        sim.add_observer(rec)
        sim.run(0.1)
        n_samples = len(sim.series["time"])
        final_time = float(sim.series["time"][-1])           # the last sample
        final_angle = sim.engine.kinematics.angle(0, final_time)
        body = sim.scene.bodies[0]
        n_vertices = len(body.vertices)
        n_particles = sim.particle_count
    assert rec.samples == n_samples and n_samples > 2
    assert path.stat().st_size > 0

    reader, ent = read_rrd(path)
    assert len(reader.blueprints()) == 1

    p = ent["particles"]
    assert {"Points3D:positions", "Points3D:radii", "Points3D:colors"} <= p["temporal"]
    assert len(p["sim_time"]) == n_samples
    assert max(p["sim_time"]) == pytest.approx(final_time, abs=1e-9)
    last = max(p["batches"], key=lambda b: max(sim_time_ns(b)))
    positions = last.column("Points3D:positions").to_pylist()[-1]
    radii = last.column("Points3D:radii").to_pylist()[-1]
    assert len(positions) == n_particles and radii == pytest.approx([0.004] * n_particles)

    b = ent["bodies/paddle"]
    assert {"Mesh3D:vertex_positions", "Mesh3D:triangle_indices"} <= b["static"]
    assert len(b["static_batch"].column("Mesh3D:vertex_positions").to_pylist()[0]) == n_vertices
    assert {"Transform3D:translation", "Transform3D:rotation_axis_angle"} <= b["temporal"]
    assert len(b["sim_time"]) == n_samples
    # the last transform turns the t = 0 mesh by the body's current angle about its axis
    last = max(b["batches"], key=lambda x: max(sim_time_ns(x)))
    aa = last.column("Transform3D:rotation_axis_angle").to_pylist()[-1][0]
    tr = np.array(last.column("Transform3D:translation").to_pylist()[-1][0])
    axis, angle = np.array(aa["axis"]), aa["angle"]
    assert angle == pytest.approx(final_angle, rel=1e-5) and final_angle != 0.0
    moved = tr + body.vertices @ rotation_matrix(axis, angle).T
    expected = (body.vertices - body.motion.axis_point) @ rotation_matrix(
        body.motion.axis_direction, final_angle).T + body.motion.axis_point
    assert np.allclose(moved, expected, atol=1e-6)

    for name in ("series/particles/kinetic_energy", "series/particles/count",
                 "series/bodies/paddle/axial_torque", "series/bodies/paddle/force/x",
                 "series/bodies/paddle/force/z", "colour_scale/min", "colour_scale/max"):
        assert ent[name]["temporal"] == {"Scalars:scalars"}, name
        assert len(ent[name]["sim_time"]) == n_samples, name
    assert "series/time" not in ent
    assert "TextDocument:text" in ent["colour_scale/legend"]["temporal"]

    # the store's schema says the same (archetypes by name)
    schema = reader.store().schema()
    assert schema.index_columns()[0].name == "sim_time"
    archetypes = {(c.entity_path, c.archetype) for c in schema.component_columns()}
    assert ("/particles", "rerun.archetypes.Points3D") in archetypes
    assert ("/bodies/paddle", "rerun.archetypes.Mesh3D") in archetypes
    assert ("/bodies/paddle", "rerun.archetypes.Transform3D") in archetypes
    assert ("/series/particles/kinetic_energy", "rerun.archetypes.Scalars") in archetypes


def test_decimation_and_side_by_side(tmp_path, small_scene_text):
    text = small_scene_text(count=60)
    a, b = tmp_path / "a.rrd", tmp_path / "b.rrd"
    with td.Simulation.from_text(text) as s1, td.Simulation.from_text(text) as s2:
        x0 = s2.particles()["position"][:, 0]
        n1 = s1.particle_count
        s1.add_observer(RerunRecorder(str(a), every_nth=3))
        s2.add_observer(RerunRecorder(str(b), region=((-1, -1, -1), (0.0, 1, 1))))
    _, ea = read_rrd(a)
    _, eb = read_rrd(b)
    first = ea["particles"]["batches"][0].column("Points3D:positions").to_pylist()[0]
    assert len(first) == len(range(0, n1, 3))
    first = eb["particles"]["batches"][0].column("Points3D:positions").to_pylist()[0]
    assert len(first) == int(np.count_nonzero(x0 <= 0.0)) and 0 < len(first) < n1
    assert RrdReader(a).recordings()[0].recording_id != RrdReader(b).recordings()[0].recording_id


def test_colormap_ends():
    c = colormap(np.array([0.0, 0.5, 1.0, 2.0, -1.0]), 0.0, 1.0)
    assert c.dtype == np.uint8 and c.shape == (5, 3)
    assert tuple(c[0]) == (68, 1, 84) and tuple(c[2]) == (253, 231, 37)
    assert tuple(c[3]) == tuple(c[2]) and tuple(c[4]) == tuple(c[0])
    assert colormap(np.array([3.0]), 3.0, 3.0).shape == (1, 3)


def test_cli_run_rrd(tmp_path, small_scene_text):
    scene = tmp_path / "scene.toml"
    scene.write_text(small_scene_text(count=40))
    rrd = tmp_path / "out" / "scene.rrd"
    done = subprocess.run([sys.executable, "-m", "taichi_dem", "run", str(scene), "--until", "0.01",
                           "--rrd", str(rrd), "--every-nth", "2", "--quiet"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert rrd.exists() and rrd.stat().st_size > 0
    assert "rerun:" in done.stdout
    _, ent = read_rrd(rrd)
    assert len(ent["particles"]["sim_time"]) == 3          # t = 0, 0.005, 0.01
    assert "series/walls/floor/force/z" in ent


def test_coloured_by_temperature_when_thermal(tmp_path):
    """With particles/mean_temperature in the sample and per-particle temperatures from
    sim.particles(), the colours follow temperature and the legend says so."""
    import types
    n = 10
    p = dict(id=np.arange(n), position=np.random.default_rng(0).random((n, 3)),
             velocity=np.zeros((n, 3)), angular_velocity=np.zeros((n, 3)),
             radius=np.full(n, 0.01), mass=np.ones(n), fixed=np.zeros(n, bool),
             temperature=np.linspace(300.0, 400.0, n))
    sim = types.SimpleNamespace(particles=lambda: p, scene=types.SimpleNamespace(bodies=[]),
                                engine=types.SimpleNamespace(), time=0.0)
    path = tmp_path / "hot.rrd"
    rec = RerunRecorder(str(path))
    rec(sim, {"time": 0.0, "particles/mean_temperature": 350.0})
    rec.close()
    _, ent = read_rrd(path)
    text = ent["colour_scale/legend"]["batches"][0].column("TextDocument:text").to_pylist()[0][0]
    assert "temperature" in text and "300 K" in text and "400 K" in text
    colours = ent["particles"]["batches"][0].column("Points3D:colors").to_pylist()[0]
    rgb = [((c >> 24) & 255, (c >> 16) & 255, (c >> 8) & 255) for c in colours]
    assert rgb[0] == (68, 1, 84) and rgb[-1] == (253, 231, 37)
    assert ent["series/particles/mean_temperature"]["temporal"] == {"Scalars:scalars"}
