"""The ParaView view that comes with a results file (recorders/paraview.py): ``<stem>_paraview.py``
beside the XDMF. ParaView is not installable here, so the script's VTK branch (the same reader
and the same sphere glyphs) is run for real, and its ParaView branch against a stand-in
``paraview.simple`` that records the pipeline it is asked to build.

Known answers: a sphere glyph scaled by 2 x radius is the particle, so the glyphs' bounds are
the particles' extremes, min(x - r) and max(x + r) per axis (the sphere source's 16 x 13
facets put vertices on the six poles: exact to the f32 positions); the drum body comes with its
own number of triangles; a frame before the first particle gives no spheres and no error."""
import importlib.util
import subprocess
import sys
import types

import h5py
import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.recorders.paraview import write_paraview_script
from taichi_dem.recorders.xdmf import write_xdmf


def _load(path):
    spec = importlib.util.spec_from_file_location("view_" + path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def drum(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("paraview")
    h5 = tmp / "drum.h5"
    with td.Simulation.from_text(open("demos/small_drum.toml").read(), h5=str(h5)) as sim:
        sim.run(0.04)
        faces = len(sim.scene.bodies[0].faces)
    with h5py.File(h5, "r") as f:
        last = f["frames"][max(f["frames"], key=int)]
        positions, radius = last["position"][()], last["radius"][()]
    return h5, positions, radius, faces


def test_a_run_writes_the_view_and_vtk_draws_spheres_and_the_drum(drum, tmp_path):
    h5, positions, radius, faces = drum
    script = h5.with_name("drum_paraview.py")
    assert script.is_file()
    view = _load(script)
    png = tmp_path / "view.png"
    out = view.vtk_view(str(png))
    assert out["time"] == pytest.approx(0.04, abs=1e-3)
    assert out["particles"] == len(positions) == 400
    assert out["bodies"] == {"drum": faces}
    bounds = np.array(out["spheres"].GetBounds()).reshape(3, 2)
    lo = (positions - radius[:, None]).min(axis=0)
    hi = (positions + radius[:, None]).max(axis=0)
    np.testing.assert_allclose(bounds[:, 0], lo, atol=1e-6)
    np.testing.assert_allclose(bounds[:, 1], hi, atol=1e-6)
    # the picture is drawn (not a blank window)
    from vtkmodules.vtkIOImage import vtkPNGReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    reader = vtkPNGReader()
    reader.SetFileName(str(png))
    reader.Update()
    pixels = vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars())
    assert pixels.std() > 5.0


def test_the_script_runs_alone_with_vtk(drum, tmp_path):
    h5 = drum[0]
    png = tmp_path / "alone.png"
    run = subprocess.run([sys.executable, str(h5.with_name("drum_paraview.py")), "--png",
                          str(png), "--time", "0"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "t = 0 s: 400 particles as spheres, bodies drum; drew" in run.stdout
    assert png.is_file()


class _Proxy(types.SimpleNamespace):
    """A stand-in ParaView proxy: any property can be set; calls are recorded."""

    def __getattr__(self, name):
        return lambda *a, **k: None


def test_the_paraview_branch_builds_glyphs_and_bodies(drum, monkeypatch):
    calls = []

    def record(kind):
        def make(*args, **kwargs):
            p = _Proxy(kind=kind, kwargs=kwargs)
            calls.append(p)
            return p
        return make

    simple = types.ModuleType("paraview.simple")
    for name in ("OpenDataFile", "ExtractBlock", "Glyph", "Show", "GetActiveViewOrCreate",
                 "GetAnimationScene", "ColorBy", "RenameSource", "Render"):
        setattr(simple, name, record(name))
    package = types.ModuleType("paraview")
    package.simple = simple
    monkeypatch.setitem(sys.modules, "paraview", package)
    monkeypatch.setitem(sys.modules, "paraview.simple", simple)
    view = _load(drum[0].with_name("drum_paraview.py"))
    assert view.main([]) == 0
    opened = [c for c in calls if c.kind == "OpenDataFile"]
    assert len(opened) == 1 and opened[0].kwargs == {}
    selectors = [c.kwargs["Selectors"] for c in calls if c.kind == "ExtractBlock"]
    assert selectors == [["//particles"], ["//drum"]]
    (glyph,) = [c for c in calls if c.kind == "Glyph"]
    assert glyph.kwargs["GlyphType"] == "Sphere"
    assert glyph.ScaleArray == ["POINTS", "radius [m]"] and glyph.ScaleFactor == 2.0
    assert glyph.GlyphMode == "All Points"
    assert glyph.OrientationArray == ["POINTS", "No orientation array"]
    # no temperature in this run: coloured by speed
    assert view.COLOUR == ("velocity [m/s]", "Magnitude")


def test_an_empty_first_frame_and_a_users_file(tmp_path):
    h5 = tmp_path / "fed.h5"
    with h5py.File(h5, "w") as f:
        for k, n in enumerate((0, 3)):
            g = f.create_group(f"frames/{k}")
            g.attrs["time"] = 0.5 * k
            g.create_dataset("position", data=np.arange(3.0 * n).reshape(n, 3))
            g.create_dataset("radius", data=np.full(n, 0.01)).attrs["units"] = "m"
            g.create_dataset("temperature", data=np.full(n, 300.0)).attrs["units"] = "K"
    xdmf, _ = write_xdmf(h5)
    script = write_paraview_script(h5, xdmf)
    view = _load(script)
    assert view.COLOUR == ("temperature [K]", "")
    assert view.vtk_view(time=0.0)["particles"] == 0
    assert view.vtk_view(time=0.5)["particles"] == 3
    # a file of the user's where the script would go is left alone
    script.write_text("print('mine')\n")
    assert write_paraview_script(h5, xdmf) is None
    assert script.read_text() == "print('mine')\n"
