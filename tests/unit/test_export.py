"""``taichi-dem export`` (issue 33 item 4, CSV part): a results file's series and a frame as
CSV, read back with the csv module and compared with the file's own arrays."""
import csv
import io

import h5py
import numpy as np
import pytest

from taichi_dem.app.cli import main
from taichi_dem.app import export


@pytest.fixture
def results(tmp_path):
    """A results file in the layout the recorder writes (CONTRACT.md), small and synthetic."""
    path = tmp_path / "run.h5"
    t = np.array([0.0, 0.5, 1.0])
    with h5py.File(path, "w") as f:
        s = f.create_group("series")
        s.create_dataset("time", data=t).attrs["units"] = "s"
        s.create_dataset("particles/mean_temperature",
                         data=[np.nan, 700.5, 690.25]).attrs["units"] = "K"
        s.create_dataset("bodies/drum/force", data=np.arange(9.0).reshape(3, 3)).attrs["units"] = "N"
        s.create_dataset("late", data=[1.0])          # sampled fewer times: left out
        for k, time in enumerate((0.0, 1.0)):
            g = f.create_group(f"frames/{k}")
            g.attrs["time"] = time
            g.create_dataset("id", data=np.array([3, 7]))
            g.create_dataset("position", data=np.array([[0.1, 0.2, 0.3], [1.0, 2.0, 3.0 + k]]))
            g["position"].attrs["units"] = "m"
            g.create_dataset("radius", data=np.array([0.01, 0.02]))
    return path


def test_series_as_csv_with_units(results, tmp_path):
    out = tmp_path / "s.csv"
    assert main(["export", str(results), "--series", "--out", str(out)]) == 0
    rows = list(csv.reader(out.open()))
    # time first, then the series by name
    assert rows[0] == ["time [s]", "bodies/drum/force[0] [N]", "bodies/drum/force[1] [N]",
                       "bodies/drum/force[2] [N]", "particles/mean_temperature [K]"]
    values = np.array([[float(x) for x in r] for r in rows[1:]])
    assert values.shape == (3, 5)
    assert np.isnan(values[0, 4]) and values[2, 4] == 690.25       # exact, NaN kept
    assert np.array_equal(values[:, 1:4], np.arange(9.0).reshape(3, 3))


def test_the_last_frame_as_csv(results):
    buf = io.StringIO()
    assert export.export_frame(results, -1, buf) == 2
    rows = list(csv.reader(buf.getvalue().splitlines()))
    # a plain header (no comment line): the frame's number and time on every row
    assert rows[0] == ["frame", "time [s]", "id", "position[0] [m]", "position[1] [m]",
                       "position[2] [m]", "radius"]
    assert [float(x) for x in rows[2]] == [1, 1.0, 7, 1.0, 2.0, 4.0, 0.02]


@pytest.mark.parametrize("args, words", [
    (["--frame", "5"], "no such frame"),
    (["--frame", "-3"], "no such frame"),
])
def test_a_missing_frame_is_refused(results, args, words, capsys):
    assert main(["export", str(results), *args]) == 2
    assert words in capsys.readouterr().err


def test_not_a_results_file_is_refused(tmp_path, capsys):
    bad = tmp_path / "x.h5"
    bad.write_text("not hdf5")
    assert main(["export", str(bad), "--series"]) == 2
    assert "not an HDF5 results file" in capsys.readouterr().err
    assert main(["export", str(tmp_path / "none.h5"), "--series"]) == 2


def test_xdmf_describes_every_frame_for_paraview(results, tmp_path):
    import xml.etree.ElementTree as ET
    assert main(["export", str(results), "--xdmf"]) == 0
    path = results.with_suffix(".xdmf")
    root = ET.parse(path).getroot()
    grids = root.findall("./Domain/Grid/Grid")
    assert root.find("./Domain/Grid").get("CollectionType") == "Temporal"
    assert [float(g.find("Time").get("Value")) for g in grids] == [0.0, 1.0]
    with h5py.File(results, "r") as f:
        for g in grids:
            topology = g.find("Topology")
            assert topology.get("TopologyType") == "Polyvertex"
            assert topology.get("NumberOfElements") == "2"
            items = g.findall(".//DataItem")
            names = {a.get("Name") for a in g.findall("Attribute")}
            assert names == {"id", "radius"}                 # no unit attribute: bare names
            for item in items:
                file_name, dataset = item.text.split(":")
                assert file_name == "run.h5"                 # relative: beside the XDMF file
                data = f[dataset]
                assert item.get("Dimensions") == " ".join(map(str, data.shape))
                assert int(item.get("Precision")) == data.dtype.itemsize
        # the geometry is each frame's positions
        assert grids[1].find("./Geometry/DataItem").text == "run.h5:/frames/1/position"


def test_xdmf_of_a_file_without_frames_is_refused(tmp_path, capsys):
    path = tmp_path / "empty.h5"
    with h5py.File(path, "w") as f:
        f.create_group("series").create_dataset("time", data=[0.0])
    assert main(["export", str(path), "--xdmf"]) == 2
    assert "frames" in capsys.readouterr().err


def _block(data, name):
    """The block ``name`` of a multiblock (a scene with bodies), or the data itself."""
    if not hasattr(data, "GetNumberOfBlocks"):
        return data
    for i in range(data.GetNumberOfBlocks()):
        # VTK names a block after its grid, with the time step's index: "particles[4]"
        if data.GetMetaData(i).Get(data.NAME()).split("[")[0] == name:
            return data.GetBlock(i)
    raise KeyError(name)


def test_a_runs_xdmf_opens_in_vtks_xdmf_reader(tmp_path):
    """The XDMF a run writes beside its results file, read back by VTK's XDMF reader (the
    reader ParaView's "Xdmf Reader" is): every frame a time step, its points the frame's
    positions, its arrays the per-particle datasets."""
    import taichi_dem as td
    from resume_scene import scene_text
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
    h5 = tmp_path / "beads.h5"
    with td.Simulation.from_text(scene_text(), precision="f64", h5=str(h5)) as sim:
        sim.run(0.1)
    xdmf = h5.with_suffix(".xdmf")
    assert xdmf.is_file()                            # written when the recorder closed
    reader = vtkXdmfReader()
    reader.SetFileName(str(xdmf))
    reader.UpdateInformation()
    steps = reader.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    with h5py.File(h5, "r") as f:
        keys = sorted(f["frames"], key=int)
        times = [float(f["frames"][k].attrs["time"]) for k in keys]
        assert list(steps) == pytest.approx(times)
        last = f["frames"][keys[-1]]
        reader.UpdateTimeStep(steps[-1])
        grid = _block(reader.GetOutputDataObject(0), "particles")
        points = vtk_to_numpy(grid.GetPoints().GetData())
        np.testing.assert_array_equal(points, last["position"][()])
        data = grid.GetPointData()
        arrays = {data.GetArrayName(i) for i in range(data.GetNumberOfArrays())}
        assert {"temperature [K]", "velocity [m/s]", "radius [m]"} <= arrays
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("temperature [K]")),
                                      last["temperature"][()])


def test_bodies_at_their_poses_in_frames_and_in_vtks_xdmf_reader(tmp_path):
    """A drum that turns: the results file keeps its mesh once (/bodies/drum) and, per frame,
    its pose (rotation, translation) and its vertices at that pose; the XDMF gives each time a
    spatial collection that VTK's XDMF reader returns as blocks: the drum's triangles at the
    frame's pose and the particles. Also the frames' material index and the root attribute
    naming the materials, and [output] frame_interval (a frame every other sample)."""
    import taichi_dem as td
    from taichi_dem.bodies.kinematics import rotation_matrix
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
    text = open("demos/small_drum.toml").read()
    text = text.replace("[output]", "[output]\nframe_interval = 0.04", 1)
    assert "frame_interval = 0.04" in text and "interval = 0.02" in text
    h5 = tmp_path / "drum.h5"
    with td.Simulation.from_text(text, h5=str(h5)) as sim:
        sim.run(0.1)
        speed = sim.scene.bodies[0].motion.speed.at(0.0)
        axis = np.asarray(sim.scene.bodies[0].motion.axis_direction, float)
        point = np.asarray(sim.scene.bodies[0].motion.axis_point, float)
    with h5py.File(h5, "r") as f:
        assert len(f["series/time"]) == 6                         # t = 0, then every 0.02 s
        keys = sorted(f["frames"], key=int)
        times = [float(f["frames"][k].attrs["time"]) for k in keys]
        assert times == pytest.approx([0.0, 0.04, 0.08], abs=1e-3)   # every other sample
        assert list(f.attrs["materials"]) == sim.tables.names
        last = f["frames"][keys[-1]]
        assert last["material"].shape == last["radius"].shape
        assert set(last["material"][()]) <= set(range(len(sim.tables.names)))
        x0 = f["bodies/drum/vertices"][()]
        rotation = last["bodies/drum/rotation"][()]
        translation = last["bodies/drum/translation"][()]
        # the pose is the turn by speed x t about the drum's axis
        want = rotation_matrix(axis, speed * times[-1])
        np.testing.assert_allclose(rotation, want, atol=1e-12)
        np.testing.assert_allclose(translation, point - want @ point, atol=1e-12)
        posed = last["bodies/drum/vertices"][()]
        np.testing.assert_allclose(posed, x0 @ rotation.T + translation, atol=1e-12)
        assert last["bodies/drum/translation"].attrs["units"] == "m"
        positions = last["position"][()]
    reader = vtkXdmfReader()
    reader.SetFileName(str(h5.with_suffix(".xdmf")))
    reader.UpdateInformation()
    steps = reader.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    assert list(steps) == pytest.approx(times)
    reader.UpdateTimeStep(steps[-1])
    blocks = reader.GetOutputDataObject(0)
    named = {blocks.GetMetaData(i).Get(blocks.NAME()).split("[")[0]: blocks.GetBlock(i)
             for i in range(blocks.GetNumberOfBlocks())}
    assert set(named) == {"drum", "particles"}
    np.testing.assert_allclose(vtk_to_numpy(named["drum"].GetPoints().GetData()), posed)
    assert named["drum"].GetNumberOfCells() == len(sim.scene.bodies[0].faces)
    np.testing.assert_array_equal(vtk_to_numpy(named["particles"].GetPoints().GetData()), positions)
    # the CSV of a frame keeps to the particles (the bodies' group is not a column)
    buf = io.StringIO()
    assert export.export_frame(h5, -1, buf) == len(positions)
    assert "material" in buf.getvalue().splitlines()[0]


def test_frame_csv_names_materials_and_its_file_the_frame(results, tmp_path):
    """The material by its name (the frames hold an index into the root's ``materials``), and
    the default file named by the frame's own number, also when asked for as -1."""
    with h5py.File(results, "a") as f:
        f.attrs["materials"] = ["ash", "steel"]
        for k in ("0", "1"):
            f["frames"][k].create_dataset("material", data=np.array([1, 0], np.int32))
    assert main(["export", str(results), "--frame", "-1"]) == 0
    written = results.with_name("run_frame1.csv")
    rows = list(csv.reader(written.read_text().splitlines()))
    k = rows[0].index("material")
    assert [r[k] for r in rows[1:]] == ["steel", "ash"]


def test_a_frame_before_the_first_particle_reads_as_an_empty_block(tmp_path):
    """A factory-fed run's first frames hold no particle: VTK's XDMF reader (ParaView's)
    failed on a grid of zero points ("Error in Update() of Geometry") and dropped the block.
    Now every time step reads without an error, with a "particles" block, empty at first."""
    import vtk
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
    from taichi_dem.recorders.xdmf import write_xdmf
    h5 = tmp_path / "fed.h5"
    with h5py.File(h5, "w") as f:
        for k, n in enumerate((0, 0, 3)):
            g = f.create_group(f"frames/{k}")
            g.attrs["time"] = 0.5 * k
            g.create_dataset("position", data=np.arange(3 * n, dtype=float).reshape(n, 3))
            g.create_dataset("radius", data=np.full(n, 0.01))
    xdmf, frames = write_xdmf(h5)
    assert frames == 3
    log = tmp_path / "vtk.log"
    window = vtk.vtkFileOutputWindow()
    window.SetFileName(str(log))
    vtk.vtkOutputWindow.SetInstance(window)
    reader = vtkXdmfReader()
    reader.SetFileName(str(xdmf))
    reader.UpdateInformation()
    steps = reader.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    assert list(steps) == [0.0, 0.5, 1.0]
    counts = []
    for t in steps:
        reader.UpdateTimeStep(t)
        block = _block(reader.GetOutputDataObject(0), "particles")
        counts.append(block.GetNumberOfPoints())
    assert counts == [0, 0, 3]
    np.testing.assert_array_equal(vtk_to_numpy(block.GetPoints().GetData()),
                                  np.arange(9.0).reshape(3, 3))
    assert not log.exists() or "ERROR" not in log.read_text(), log.read_text()
