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
    lines = buf.getvalue().splitlines()
    assert lines[0] == "# frame 1, time 1.0 s"
    rows = list(csv.reader(lines[1:]))
    assert rows[0] == ["id", "position[0] [m]", "position[1] [m]", "position[2] [m]", "radius"]
    assert [float(x) for x in rows[2]] == [7, 1.0, 2.0, 4.0, 0.02]


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
        grid = reader.GetOutputDataObject(0)
        points = vtk_to_numpy(grid.GetPoints().GetData())
        np.testing.assert_array_equal(points, last["position"][()])
        data = grid.GetPointData()
        arrays = {data.GetArrayName(i) for i in range(data.GetNumberOfArrays())}
        assert {"temperature [K]", "velocity [m/s]", "radius [m]"} <= arrays
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("temperature [K]")),
                                      last["temperature"][()])
