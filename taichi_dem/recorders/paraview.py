"""A ParaView view that comes with the results: ``<stem>_paraview.py`` beside ``<stem>.xdmf``
(recorders/xdmf.py), written with it when a run's recorder closes and by ``taichi-dem export
RESULTS.h5 --xdmf``.

The script is a ParaView Python state: loaded in ParaView (File > Load State, or
``paraview --script=...``, or ``pvpython``) it opens the XDMF, draws the particles as spheres of
their own radius (a sphere glyph scaled by each particle's ``radius [m]``), coloured by their
temperature (or speed), and each body as a translucent surface, over every frame. ParaView is
not a pip package, so the same file also runs under plain Python with VTK (``pip install vtk``):
``python <stem>_paraview.py --png view.png [--time T]`` draws one frame with the same pipeline
(VTK's XDMF reader, the one ParaView uses), which is how the tests check it.
Standard library and h5py only here; the script imports ParaView or VTK when it runs.
"""
from __future__ import annotations

from pathlib import Path

from ..scene import catalog

MARK = "# taichi-dem ParaView view"

_TEMPLATE = '''#!/usr/bin/env python3
"""ParaView view of the taichi-dem results {h5!r} (frames described by {xdmf!r}).

In ParaView 5.10 or later: File > Load State... and this file (a Python state), or
`paraview --script={script}`, or `pvpython {script}`: the particles as spheres of their own
radius coloured by {colour_words}, the bodies as translucent surfaces, over every frame.
Without ParaView, with VTK (pip install vtk): `python {script} --png view.png [--time T]`
draws one frame (default the last) into a PNG.
Keep this file beside {xdmf} and {h5}.
"""
{mark}
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
XDMF = os.path.join(HERE, {xdmf!r})
RADIUS = {radius!r}           # the point array of each particle's radius, m
COLOUR = {colour!r}           # (array, component) the spheres are coloured by, or None
BODIES = {bodies!r}
# a sphere glyph has radius 0.5: scaled by 2 x radius it is the particle
SCALE = 2.0


def paraview_view():
    """Build the view in ParaView (paraview.simple)."""
    from paraview import simple as pv
    reader = pv.OpenDataFile(XDMF)
    view = pv.GetActiveViewOrCreate("RenderView")
    particles = pv.ExtractBlock(Input=reader, Selectors=["//particles"])
    spheres = pv.Glyph(Input=particles, GlyphType="Sphere")
    spheres.ScaleArray = ["POINTS", RADIUS]
    spheres.ScaleFactor = SCALE
    spheres.GlyphMode = "All Points"
    spheres.OrientationArray = ["POINTS", "No orientation array"]   # spheres: not turned
    pv.RenameSource("particles (spheres)", spheres)
    shown = pv.Show(spheres, view)
    if COLOUR is not None:
        pv.ColorBy(shown, ("POINTS",) + tuple(COLOUR))
        shown.RescaleTransferFunctionToDataRange(True, False)
        shown.SetScalarBarVisibility(view, True)
    for name in BODIES:
        body = pv.ExtractBlock(Input=reader, Selectors=["//" + name])
        pv.RenameSource(name, body)
        surface = pv.Show(body, view)
        surface.Opacity = 0.35
    pv.GetAnimationScene().UpdateAnimationUsingDataTimeSteps()
    view.ResetCamera()
    pv.Render()


def _blocks(data, out):
    """{{name: block}} of a (nested) multiblock, or the particles when it is one grid."""
    if not data.IsA("vtkMultiBlockDataSet"):
        out.setdefault("particles", data)
        return out
    for i in range(data.GetNumberOfBlocks()):
        name = data.GetMetaData(i).Get(data.NAME()) or ""
        name = name.split("[")[0].strip()
        block = data.GetBlock(i)
        if block is None:
            continue
        if block.IsA("vtkMultiBlockDataSet") and name not in ("particles",) + tuple(BODIES):
            _blocks(block, out)
        else:
            out[name] = block
    return out


def vtk_view(png=None, time=None, size=(1200, 900)):
    """The same view with VTK: the frame nearest ``time`` (s; default the last) drawn into
    ``png`` when given. Returns {{"time": s, "spheres": the glyphs' polydata, "particles": N,
    "bodies": {{name: triangles}}}}."""
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
    from vtkmodules.vtkFiltersCore import vtkGlyph3D
    from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter
    from vtkmodules.vtkFiltersSources import vtkSphereSource
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
    reader = vtkXdmfReader()
    reader.SetFileName(XDMF)
    reader.UpdateInformation()
    steps = list(reader.GetOutputInformation(0).Get(
        vtkStreamingDemandDrivenPipeline.TIME_STEPS()) or [0.0])
    t = steps[-1] if time is None else min(steps, key=lambda s: abs(s - float(time)))
    reader.UpdateTimeStep(t)
    blocks = _blocks(reader.GetOutputDataObject(0), {{}})
    particles = blocks.get("particles")
    n = particles.GetNumberOfPoints() if particles is not None and \\
        not particles.IsA("vtkMultiBlockDataSet") else 0
    sphere = vtkSphereSource()
    sphere.SetRadius(0.5)
    sphere.SetThetaResolution(16)
    sphere.SetPhiResolution(13)      # (rings 180/12 deg apart: one on the equator)
    glyphs = vtkGlyph3D()
    glyphs.SetSourceConnection(sphere.GetOutputPort())
    if n:
        particles.GetPointData().SetActiveScalars(RADIUS)
        glyphs.SetInputData(particles)
        glyphs.SetScaleModeToScaleByScalar()
        glyphs.SetScaleFactor(SCALE)
        glyphs.OrientOff()          # (by default a glyph turns to the velocity)
        glyphs.SetColorModeToColorByScalar()
        glyphs.Update()
    surfaces = {{}}
    for name in BODIES:
        if name in blocks:
            surface = vtkDataSetSurfaceFilter()
            surface.SetInputData(blocks[name])
            surface.Update()
            surfaces[name] = surface.GetOutput()
    if png:
        _render(png, glyphs.GetOutput() if n else None, surfaces, size)
    return {{"time": t, "spheres": glyphs.GetOutput() if n else None, "particles": n,
            "bodies": {{k: v.GetNumberOfCells() for k, v in surfaces.items()}}}}


def _render(png, spheres, surfaces, size):
    """Draw the spheres (coloured by COLOUR) and the surfaces off screen into ``png``."""
    from vtkmodules.vtkIOImage import vtkPNGWriter
    from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderWindow,
                                             vtkRenderer, vtkWindowToImageFilter)
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the render window's back end)
    renderer = vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    if spheres is not None:
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(spheres)
        if COLOUR is not None and spheres.GetPointData().GetArray(COLOUR[0]) is not None:
            array = spheres.GetPointData().GetArray(COLOUR[0])
            mapper.SetScalarModeToUsePointFieldData()
            mapper.SelectColorArray(COLOUR[0])
            if array.GetNumberOfComponents() > 1:
                mapper.GetLookupTable().SetVectorModeToMagnitude()
            mapper.SetScalarRange(array.GetRange(-1 if array.GetNumberOfComponents() > 1 else 0))
            mapper.ScalarVisibilityOn()
        else:
            mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        renderer.AddActor(actor)
    for surface in surfaces.values():
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(surface)
        mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetOpacity(0.35)
        actor.GetProperty().SetColor(0.6, 0.6, 0.65)
        renderer.AddActor(actor)
    renderer.ResetCamera()
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(*size)
    window.Render()
    image = vtkWindowToImageFilter()
    image.SetInput(window)
    image.Update()
    writer = vtkPNGWriter()
    writer.SetFileName(str(png))
    writer.SetInputConnection(image.GetOutputPort())
    writer.Write()


def main(argv):
    try:
        import paraview.simple  # noqa: F401
    except ImportError:
        pass
    else:
        paraview_view()
        return 0
    import argparse
    parser = argparse.ArgumentParser(description="Draw one frame of " + XDMF + " with VTK.")
    parser.add_argument("--png", default=None, help="the picture to write")
    parser.add_argument("--time", type=float, default=None, help="the frame's time, s "
                        "(default the last)")
    args = parser.parse_args(argv)
    view = vtk_view(args.png, args.time)
    print("t = %g s: %d particles as spheres, bodies %s%s" % (
        view["time"], view["particles"], ", ".join(view["bodies"]) or "none",
        ("; drew " + args.png) if args.png else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
'''


def paraview_script_text(h5_path, xdmf_path) -> str:
    """The view script's text for the results ``h5_path`` described by ``xdmf_path``: its
    bodies and its colour (the effects' colour field, the temperature, else speed) read from the
    file."""
    import h5py
    h5_path, xdmf_path = Path(h5_path), Path(xdmf_path)
    with h5py.File(h5_path, "r") as f:
        bodies = sorted(f["bodies"]) if "bodies" in f else []
        arrays = set()
        for key in f["frames"] if "frames" in f else ():
            arrays |= set(f["frames"][key])
    # the first field the effects colour particles by (scene/catalog.py colour_fields: the
    # temperature), named with its unit as the XDMF names it; else the speed
    fields = catalog.frame_fields()
    chosen = next((name for name in catalog.colour_fields() if name in arrays), None)
    if chosen is not None:
        unit = fields[chosen][0]
        colour = (f"{chosen} [{unit}]" if unit != "1" else chosen, "")
        words = chosen
    elif "velocity" in arrays:
        colour, words = ("velocity [m/s]", "Magnitude"), "speed"
    else:
        colour, words = None, "nothing (one colour)"
    script = xdmf_path.with_name(xdmf_path.stem + "_paraview.py")
    return _TEMPLATE.format(h5=h5_path.name, xdmf=xdmf_path.name, script=script.name,
                            colour_words=words, mark=MARK, radius="radius [m]",
                            colour=colour, bodies=bodies)


def write_paraview_script(h5_path, xdmf_path) -> Path | None:
    """Write ``<xdmf stem>_paraview.py`` beside ``xdmf_path``; returns its path, or None when
    a file of that name that this module did not write is there (it is left alone)."""
    xdmf_path = Path(xdmf_path)
    target = xdmf_path.with_name(xdmf_path.stem + "_paraview.py")
    if target.exists() and MARK not in target.read_text(errors="replace")[:4000]:
        return None
    target.write_text(paraview_script_text(h5_path, xdmf_path))
    return target
