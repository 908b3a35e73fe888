"""HDF5 results as CONTRACT.md names them, appended and flushed at every output interval so a
killed run keeps what it wrote."""
from __future__ import annotations

import os

import h5py
import numpy as np

from .. import __version__


class HDF5Recorder:
    """Writes /series/<name> (extendable along time) and /frames/<k>/... groups."""

    def __init__(self, path: str, *, scene_text: str, dt: float, arch: str, precision: str):
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

    def append_series(self, values: dict[str, np.ndarray | float]):
        """Append one sample of each series (name relative to /series, e.g. "time")."""
        for name, value in values.items():
            value = np.asarray(value, dtype=np.float64)
            if name not in self.series:
                self.series.create_dataset(name, shape=(0,) + value.shape,
                                           maxshape=(None,) + value.shape, dtype=np.float64,
                                           chunks=(256,) + value.shape)
            ds = self.series[name]
            ds.resize(ds.shape[0] + 1, axis=0)
            ds[-1] = value

    def append_residence(self, name: str, records: np.ndarray):
        """Append (id, t_in s, t_out s) rows under /residence/<name>/id, t_in, t_out."""
        g = self.file.require_group("residence").require_group(name)
        for col, key, dtype in ((0, "id", np.int64), (1, "t_in", np.float64), (2, "t_out", np.float64)):
            if key not in g:
                g.create_dataset(key, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(4096,))
            ds = g[key]
            n = ds.shape[0]
            ds.resize(n + len(records), axis=0)
            ds[n:] = records[:, col].astype(dtype)

    def append_frame(self, time: float, arrays: dict[str, np.ndarray]):
        g = self.frames.create_group(str(self.frame_count))
        g.attrs["time"] = time
        for name, arr in arrays.items():
            g.create_dataset(name, data=arr)
        self.frame_count += 1

    def flush(self):
        self.file.flush()

    def close(self):
        if self.file:
            self.file.close()
            self.file = None
