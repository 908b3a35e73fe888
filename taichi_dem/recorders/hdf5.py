"""HDF5 results as CONTRACT.md names them, appended and flushed at every output interval so a
killed run keeps what it wrote."""
from __future__ import annotations

import os
import sys

import h5py
import numpy as np

from .._version import __version__
from ..sensors.units import unit_of


def _label(ds, name: str) -> None:
    """A series dataset's ``units`` attribute (SI; "1" for counts and ratios), when declared."""
    unit = unit_of(name)
    if unit is not None:
        ds.attrs["units"] = unit


# the per-particle frame datasets, /frames/<k>/<name>: name -> (unit, shape, description);
# N is the number of particles alive at the sample, in id order (the reference in docs/ is
# generated from this declaration)
FRAME_DATASETS = {
    "id": ("1", "(N,)", "the particle's id (integer), ascending"),
    "position": ("m", "(N, 3)", "centre position"),
    "velocity": ("m/s", "(N, 3)", "translational velocity"),
    "angular_velocity": ("rad/s", "(N, 3)", "angular velocity"),
    "radius": ("m", "(N,)", "radius"),
    "mass": ("kg", "(N,)", "mass"),
    "temperature": ("K", "(N,)", "temperature; with [thermal] only"),
    "moisture": ("1", "(N,)", "kg water per kg dry solid; with moisture only"),
    "material": ("1", "(N,)", "material index: the position of its name in the root attribute "
                              "materials"),
}
# each body's pose in a frame, /frames/<k>/bodies/<name>/<dataset>, and its mesh as the scene
# gives it, /bodies/<name>/<dataset>: name -> (unit, shape, description); V vertices, F faces
FRAME_BODY_DATASETS = {
    "rotation": ("1", "(3, 3)", "R of the pose: a vertex given at x0 in the scene is at R x0 + T"),
    "translation": ("m", "(3,)", "T of the pose"),
    "vertices": ("m", "(V, 3)", "the vertices at this pose (bodies that move only)"),
}
BODY_DATASETS = {
    "vertices": ("m", "(V, 3)", "the mesh's vertices as the scene gives them (t = 0)"),
    "faces": ("1", "(F, 3)", "triangles as vertex indices"),
}
# the units of the per-particle frame datasets and the residence records (CONTRACT.md)
FRAME_UNITS = {name: unit for name, (unit, _shape, _description) in FRAME_DATASETS.items()}
# the results file's root attributes: name -> description (written by HDF5Recorder.__init__)
ROOT_ATTRIBUTES = {
    "taichi_dem_version": "the taichi_dem version that wrote the file",
    "scene": "the scene file's text (TOML), as run",
    "dt": "the time step, s",
    "arch": "where the kernels ran (cpu, cuda, vulkan, metal)",
    "precision": "floating-point precision of the state: f32 or f64",
    "materials": "the material names, in the order of the frames' material index",
}
RESIDENCE_UNITS = {"id": "1", "t_in": "s", "t_out": "s"}


def moves(body) -> bool:
    """Whether a body turns or translates (its frames then carry its posed vertices)."""
    m = body.motion
    return m.speed is not None or bool(np.any(np.asarray(m.velocity, float) != 0.0))


class HDF5Recorder:
    """Writes /series/<name> (extendable along time) and /frames/<k>/... groups."""

    def __init__(self, path: str, *, scene_text: str, dt: float, arch: str, precision: str):
        from ..errors import SceneError
        from ..scene.sections.consistency import foreign_file_problem
        problem = foreign_file_problem(path, "results")     # never overwrite a file not ours
        if problem:
            raise SceneError(path, "h5", problem)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self.path = path
        self.file = h5py.File(path, "w")
        a = self.file.attrs
        a["taichi_dem_version"] = __version__
        a["scene"] = scene_text
        a["dt"] = dt
        a["arch"] = arch
        a["precision"] = precision
        self.series = self.file.create_group("series")
        self.frames = self.file.create_group("frames")
        self.frame_count = 0

    @classmethod
    def continue_at(cls, path: str, time: float, dt: float, series: dict, *, scene_text: str,
                    arch: str, precision: str) -> "HDF5Recorder":
        """Continue the results file ``path`` of a run resumed at ``time`` (s): /series is
        rewritten from ``series`` (the checkpoint's samples up to ``time``; it replaces rows a
        killed or longer run wrote after it) and frames later than ``time`` are deleted. A
        missing file is created, with the series so far and frames from ``time`` on."""
        if not os.path.exists(path):
            rec = cls(path, scene_text=scene_text, dt=dt, arch=arch, precision=precision)
        else:
            from ..errors import SceneError
            from ..scene.sections.consistency import foreign_file_problem
            problem = foreign_file_problem(path, "results")   # never rewrite a file not ours
            if problem:
                raise SceneError(path, "h5", problem)
            rec = cls.__new__(cls)
            rec.path = path
            rec.file = h5py.File(path, "a")
            rec.frames = rec.file.require_group("frames")
            if "series" in rec.file:
                del rec.file["series"]
            rec.series = rec.file.create_group("series")
            later = [k for k, g in rec.frames.items() if float(g.attrs.get("time", 0.0)) > time + 0.5 * dt]
            for k in later:
                del rec.frames[k]
            rec.frame_count = max((int(k) + 1 for k in rec.frames), default=0)
        for name, rows in series.items():
            data = np.asarray(rows, dtype=np.float64)
            ds = rec.series.create_dataset(name, data=data, maxshape=(None,) + data.shape[1:],
                                           chunks=(256,) + data.shape[1:])
            _label(ds, name)
        rec.flush()
        return rec

    def append_series(self, values: dict[str, np.ndarray | float]):
        """Append one sample of each series (name relative to /series, e.g. "time")."""
        for name, value in values.items():
            value = np.asarray(value, dtype=np.float64)
            if name not in self.series:
                ds = self.series.create_dataset(name, shape=(0,) + value.shape,
                                                maxshape=(None,) + value.shape, dtype=np.float64,
                                                chunks=(256,) + value.shape)
                _label(ds, name)
            ds = self.series[name]
            ds.resize(ds.shape[0] + 1, axis=0)
            ds[-1] = value

    def append_residence(self, name: str, records: np.ndarray):
        """Append (id, t_in s, t_out s) rows under /residence/<name>/id, t_in, t_out."""
        g = self.file.require_group("residence").require_group(name)
        for col, key, dtype in ((0, "id", np.int64), (1, "t_in", np.float64), (2, "t_out", np.float64)):
            if key not in g:
                g.create_dataset(key, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(4096,))
                g[key].attrs["units"] = RESIDENCE_UNITS[key]
            ds = g[key]
            n = ds.shape[0]
            ds.resize(n + len(records), axis=0)
            ds[n:] = records[:, col].astype(dtype)

    def write_bodies(self, bodies, materials=()) -> None:
        """The bodies' meshes as the scene gives them (t = 0): /bodies/<name>/vertices (V, 3; m)
        and faces (F, 3; vertex indices), with the axis they turn about as attributes; and the
        material names (root attribute ``materials``, in the order of the frames' ``material``
        index). Written once; a continued file keeps what it has."""
        if len(materials) and "materials" not in self.file.attrs:
            self.file.attrs["materials"] = [str(m) for m in materials]
        if "bodies" in self.file or not bodies:
            return
        group = self.file.create_group("bodies")
        for body in bodies:
            g = group.create_group(body.name)
            g.create_dataset("vertices", data=np.asarray(body.vertices, np.float64))
            g.create_dataset("faces", data=np.asarray(body.faces, np.int32))
            for key in g:
                g[key].attrs["units"] = BODY_DATASETS[key][0]
            g.attrs["axis_point"] = np.asarray(body.motion.axis_point, float)
            g.attrs["axis_direction"] = np.asarray(body.motion.axis_direction, float)
            g.attrs["moves"] = moves(body)

    def append_frame(self, time: float, arrays: dict[str, np.ndarray],
                     poses: dict[str, tuple[np.ndarray, np.ndarray]] | None = None):
        """One frame: per-particle ``arrays`` (/frames/<k>/<name>) and each body's pose
        (/frames/<k>/bodies/<name>/rotation (3, 3) and translation (3,; m): a scene vertex x0 is
        at rotation @ x0 + translation), with, for a body that moves, its vertices at that
        pose (V, 3; m) so a viewer draws it without computing."""
        g = self.frames.create_group(str(self.frame_count))
        g.attrs["time"] = time
        g.attrs["time_units"] = "s"
        for name, arr in arrays.items():
            ds = g.create_dataset(name, data=arr)
            if name in FRAME_UNITS:
                ds.attrs["units"] = FRAME_UNITS[name]
        if poses:
            posed = g.create_group("bodies")
            meshes = self.file.get("bodies")
            for name, (rotation, translation) in poses.items():
                b = posed.create_group(name)
                b.create_dataset("rotation", data=np.asarray(rotation, np.float64))
                b.create_dataset("translation", data=np.asarray(translation, np.float64))
                if meshes is not None and name in meshes and meshes[name].attrs.get("moves"):
                    x0 = meshes[name]["vertices"][()]
                    b.create_dataset("vertices", data=x0 @ np.asarray(rotation).T + translation)
                for key in b:
                    b[key].attrs["units"] = FRAME_BODY_DATASETS[key][0]
        self.frame_count += 1

    def flush(self):
        self.file.flush()

    def close(self):
        """Close the file; with frames in it, write its XDMF description beside it (same
        stem, .xdmf: ParaView opens the frames from it, recorders/xdmf.py) and the ParaView
        view script (<stem>_paraview.py: spheres and bodies, recorders/paraview.py)."""
        if self.file:
            frames = self.frame_count
            self.file.close()
            self.file = None
            if frames:
                from ..errors import SceneError
                from .paraview import write_paraview_script
                from .xdmf import write_xdmf
                try:
                    xdmf, _ = write_xdmf(self.path)
                except SceneError as err:      # a file of the user's where ours would go
                    print(f"taichi-dem: warning: no XDMF written: {err}", file=sys.stderr)
                else:
                    # the ParaView view beside it (spheres, bodies); a file of the user's
                    # of that name is left alone
                    write_paraview_script(self.path, xdmf)
