"""HDF5 results as CONTRACT.md names them, committed whole at every output interval (written
to a mirror, then moved into place) so a run killed at any moment keeps what it wrote."""
from __future__ import annotations

import os
import shutil
import sys

import h5py
import numpy as np

from .._version import __version__
from ..files import remove_stale_side_files, side_path
from ..scene import catalog
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
    # the effects' own (scene/catalog.py frame_fields: the heat transfer's temperature, the
    # drying's moisture), where the particles carry them
    **catalog.frame_fields(),
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
    """Writes /series/<name> (extendable along time) and /frames/<k>/... groups.

    What a sample writes (``append_series``, ``append_residence``, ``append_frame``,
    ``write_bodies``) waits until ``flush``, which commits it whole: the file at ``path`` is
    never written in place. A flush applies the sample to a mirror of the results (a hidden
    file beside them, ``.<name>.<pid>.mirror``), moves the mirror over the results with
    ``os.replace`` (atomic on POSIX), then applies the same sample to the previous file (kept
    by a hard link) so that it is the next mirror. A run killed at any moment, even inside
    HDF5's own writes, leaves the results as of one sample or the next, each whole; each
    sample's data is written twice. (No fsync: this guards against the process being killed,
    not against the machine losing power.)"""

    def __init__(self, path: str, *, scene_text: str, dt: float, arch: str, precision: str):
        from ..errors import SceneError
        from ..scene.sections.consistency import foreign_file_problem
        problem = foreign_file_problem(path, "results")     # never overwrite a file not ours
        if problem:
            raise SceneError(path, "h5", problem)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self._start(path)
        # created whole, then moved into place
        tmp = side_path(path, "tmp")
        with h5py.File(tmp, "w") as f:
            a = f.attrs
            a["taichi_dem_version"] = __version__
            a["scene"] = scene_text
            a["dt"] = dt
            a["arch"] = arch
            a["precision"] = precision
            f.create_group("series")
            f.create_group("frames")
        os.replace(tmp, path)

    def _start(self, path: str) -> None:
        self.path = path
        self.frame_count = 0
        self._pending: list = []          # what the next flush commits: functions of a file
        self._mirror = side_path(path, "mirror")
        self._mirror_ok = False           # the mirror holds what the results hold
        self._open = True
        remove_stale_side_files(path, SIDE_TAGS)

    @classmethod
    def continue_at(cls, path: str, time: float, dt: float, series: dict, *, scene_text: str,
                    arch: str, precision: str) -> "HDF5Recorder":
        """Continue the results file ``path`` of a run resumed at ``time`` (s): /series is
        rewritten from ``series`` (the checkpoint's samples up to ``time``; it replaces rows a
        killed or longer run wrote after it) and frames later than ``time`` are deleted. A
        missing file is created, with the series so far and frames from ``time`` on."""
        if not os.path.exists(path):
            rec = cls(path, scene_text=scene_text, dt=dt, arch=arch, precision=precision)
            kept = 0
        else:
            from ..errors import SceneError
            from ..scene.sections.consistency import foreign_file_problem
            problem = foreign_file_problem(path, "results")   # never rewrite a file not ours
            if problem:
                raise SceneError(path, "h5", problem)
            rec = cls.__new__(cls)
            rec._start(path)
            with h5py.File(path, "r") as f:
                frames = f.get("frames", {})
                kept = max((int(k) + 1 for k, g in frames.items()
                            if float(g.attrs.get("time", 0.0)) <= time + 0.5 * dt), default=0)
        rec.frame_count = kept
        rows = {name: np.asarray(v, dtype=np.float64) for name, v in series.items()}

        def rewind(f):
            frames = f.require_group("frames")
            for k in [k for k, g in frames.items()
                      if float(g.attrs.get("time", 0.0)) > time + 0.5 * dt]:
                del frames[k]
            if "series" in f:
                del f["series"]
            group = f.create_group("series")
            for name, data in rows.items():
                ds = group.create_dataset(name, data=data, maxshape=(None,) + data.shape[1:],
                                          chunks=(256,) + data.shape[1:])
                _label(ds, name)

        rec._pending.append(rewind)
        rec.flush()
        return rec

    def append_series(self, values: dict[str, np.ndarray | float]):
        """Append one sample of each series (name relative to /series, e.g. "time")."""
        values = {name: np.array(value, dtype=np.float64) for name, value in values.items()}

        def write(f):
            series = f.require_group("series")
            for name, value in values.items():
                if name not in series:
                    ds = series.create_dataset(name, shape=(0,) + value.shape,
                                               maxshape=(None,) + value.shape,
                                               dtype=np.float64, chunks=(256,) + value.shape)
                    _label(ds, name)
                ds = series[name]
                ds.resize(ds.shape[0] + 1, axis=0)
                ds[-1] = value

        self._pending.append(write)

    def append_residence(self, name: str, records: np.ndarray):
        """Append (id, t_in s, t_out s) rows under /residence/<name>/id, t_in, t_out."""
        records = np.array(records)

        def write(f):
            g = f.require_group("residence").require_group(name)
            for col, key, dtype in ((0, "id", np.int64), (1, "t_in", np.float64),
                                    (2, "t_out", np.float64)):
                if key not in g:
                    g.create_dataset(key, shape=(0,), maxshape=(None,), dtype=dtype,
                                     chunks=(4096,))
                    g[key].attrs["units"] = RESIDENCE_UNITS[key]
                ds = g[key]
                n = ds.shape[0]
                ds.resize(n + len(records), axis=0)
                ds[n:] = records[:, col].astype(dtype)

        self._pending.append(write)

    def write_bodies(self, bodies, materials=()) -> None:
        """The bodies' meshes as the scene gives them (t = 0): /bodies/<name>/vertices (V, 3; m)
        and faces (F, 3; vertex indices), with the axis they turn about as attributes; and the
        material names (root attribute ``materials``, in the order of the frames' ``material``
        index). Written once; a continued file keeps what it has."""
        materials = [str(m) for m in materials]
        meshes = [(b.name, np.asarray(b.vertices, np.float64), np.asarray(b.faces, np.int32),
                   np.asarray(b.motion.axis_point, float),
                   np.asarray(b.motion.axis_direction, float), moves(b)) for b in bodies]

        def write(f):
            if materials and "materials" not in f.attrs:
                f.attrs["materials"] = materials
            if "bodies" in f or not meshes:
                return
            group = f.create_group("bodies")
            for name, vertices, faces, axis_point, axis_direction, moving in meshes:
                g = group.create_group(name)
                g.create_dataset("vertices", data=vertices)
                g.create_dataset("faces", data=faces)
                for key in g:
                    g[key].attrs["units"] = BODY_DATASETS[key][0]
                g.attrs["axis_point"] = axis_point
                g.attrs["axis_direction"] = axis_direction
                g.attrs["moves"] = moving

        self._pending.append(write)

    def append_frame(self, time: float, arrays: dict[str, np.ndarray],
                     poses: dict[str, tuple[np.ndarray, np.ndarray]] | None = None):
        """One frame: per-particle ``arrays`` (/frames/<k>/<name>) and each body's pose
        (/frames/<k>/bodies/<name>/rotation (3, 3) and translation (3,; m): a scene vertex x0 is
        at rotation @ x0 + translation), with, for a body that moves, its vertices at that
        pose (V, 3; m) so a viewer draws it without computing."""
        key = str(self.frame_count)
        arrays = {name: np.asarray(arr) for name, arr in arrays.items()}
        poses = {name: (np.array(r, np.float64), np.array(t, np.float64))
                 for name, (r, t) in (poses or {}).items()}

        def write(f):
            g = f.require_group("frames").create_group(key)
            g.attrs["time"] = time
            g.attrs["time_units"] = "s"
            for name, arr in arrays.items():
                ds = g.create_dataset(name, data=arr)
                if name in FRAME_UNITS:
                    ds.attrs["units"] = FRAME_UNITS[name]
            if poses:
                posed = g.create_group("bodies")
                meshes = f.get("bodies")
                for name, (rotation, translation) in poses.items():
                    b = posed.create_group(name)
                    b.create_dataset("rotation", data=rotation)
                    b.create_dataset("translation", data=translation)
                    if meshes is not None and name in meshes and meshes[name].attrs.get("moves"):
                        x0 = meshes[name]["vertices"][()]
                        b.create_dataset("vertices", data=x0 @ rotation.T + translation)
                    for k in b:
                        b[k].attrs["units"] = FRAME_BODY_DATASETS[k][0]

        self._pending.append(write)
        self.frame_count += 1

    def flush(self):
        """Commit what was written since the last flush, whole (the class docstring)."""
        if not self._pending:
            return
        writes, self._pending = self._pending, []
        if not (self._mirror_ok and os.path.exists(self._mirror)):
            shutil.copyfile(self.path, self._mirror)
        self._mirror_ok = False
        _apply(self._mirror, writes)
        previous = side_path(self.path, "previous")
        try:
            if os.path.lexists(previous):
                os.unlink(previous)
            os.link(self.path, previous)      # the results as they were: the next mirror
        except OSError:                        # no hard links here: copied at the next flush
            previous = None
        os.replace(self._mirror, self.path)    # the commit
        if previous is not None:
            _apply(previous, writes)
            os.replace(previous, self._mirror)
            self._mirror_ok = True

    def close(self):
        """Commit and close; with frames in the file, write its XDMF description beside it (same
        stem, .xdmf: ParaView opens the frames from it, recorders/xdmf.py) and the ParaView
        view script (<stem>_paraview.py: spheres and bodies, recorders/paraview.py)."""
        if self._open:
            self.flush()
            self._open = False
            for tag in ("mirror", "previous"):
                try:
                    os.unlink(side_path(self.path, tag))
                except OSError:
                    pass
            if self.frame_count:
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


# the side files a results writer keeps beside the results (HDF5Recorder)
SIDE_TAGS = ("tmp", "mirror", "previous")


def _apply(path: str, writes) -> None:
    """Open ``path``, apply each of ``writes`` (functions of an open h5py.File), close."""
    with h5py.File(path, "a") as f:
        for write in writes:
            write(f)
