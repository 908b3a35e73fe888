"""``taichi-dem export``: a results file's series or one particle frame as CSV (issue 33 item
4), for a spreadsheet, pandas or EDEM Analyst habits; or, with ``--xdmf``, an XDMF file that
opens its frames in ParaView (recorders/xdmf.py).

- ``--series``: one row per output sample, a column per /series dataset (a vector series gives
  one column per component, ``name[0]`` ...); the header names each column with its unit,
  ``bodies/drum/axial_torque [N m]``.
- ``--frame K``: one row per particle of frame K (negative counts from the last: -1 the last),
  a plain header, then the frame's number and time (``frame``, ``time [s]``) and a column per
  dataset (``position[0] [m]`` ...), the material by its name; the default file is
  ``<results stem>_frame<N>.csv``, N the frame's own number (also for -1).

Refusals (exit 2, ``file: key: reason``): a file that is not a results file, a frame that is
not there. Pure h5py and the standard library's csv.
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

from ..errors import SceneError


def _columns(group, names) -> tuple[list[str], list[np.ndarray]]:
    """(header, columns) of the datasets ``names`` of ``group``: each 1-D dataset a column,
    each (n, k) one column per component; the unit in brackets when the dataset has one."""
    header, columns = [], []
    for name in names:
        data = np.asarray(group[name][()])
        unit = group[name].attrs.get("units")
        label = (lambda n: f"{n} [{unit}]") if unit else (lambda n: n)
        if data.ndim == 1:
            header.append(label(name))
            columns.append(data)
        elif data.ndim == 2:
            for k in range(data.shape[1]):
                header.append(label(f"{name}[{k}]"))
                columns.append(data[:, k])
    return header, columns


def _series_names(series) -> list[str]:
    import h5py
    names = []
    series.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
    # time first, then the rest by name (the order HDF5 lists them)
    return (["time"] if "time" in names else []) + [n for n in names if n != "time"]


def export_series(h5_path, out) -> int:
    """Write the /series of ``h5_path`` as CSV to the text stream ``out``; returns the rows."""
    import h5py
    with h5py.File(h5_path, "r") as f:
        if "series" not in f:
            raise SceneError(str(h5_path), "series", "not a taichi-dem results file (no /series)")
        series = f["series"]
        names = _series_names(series)
        rows = len(series["time"]) if "time" in series else 0
        # a series sampled fewer times than time (one added mid-run) is left out
        names = [n for n in names if series[n].shape and series[n].shape[0] == rows]
        header, columns = _columns(series, names)
    writer = csv.writer(out)
    writer.writerow(header)
    for i in range(rows):
        writer.writerow([repr(float(c[i])) for c in columns])
    return rows


def frame_number(h5_path, index: int) -> int:
    """The number of frame ``index`` (negative: from the last) of ``h5_path``; SceneError
    when the file holds no such frame."""
    import h5py
    with h5py.File(h5_path, "r") as f:
        if "frames" not in f or not len(f["frames"]):
            raise SceneError(str(h5_path), "frames", "the results file holds no particle frames")
        keys = sorted(f["frames"], key=int)
    if not -len(keys) <= index < len(keys):
        raise SceneError(str(h5_path), f"frames/{index}",
                         f"no such frame: the file holds {len(keys)} (0 - {len(keys) - 1}, "
                         f"or -1 for the last)")
    return int(keys[index])


def export_frame(h5_path, index: int, out) -> int:
    """Write frame ``index`` (negative: from the last) of ``h5_path`` as CSV; returns the
    particles written."""
    import h5py
    number = frame_number(h5_path, index)
    with h5py.File(h5_path, "r") as f:
        frame = f["frames"][str(number)]
        names = [str(m) for m in f.attrs.get("materials", [])]
        time = float(frame.attrs.get("time", float("nan")))
        order = [n for n in ("id", "position", "velocity", "angular_velocity", "radius",
                             "temperature", "mass", "moisture", "material") if n in frame]
        order += [n for n in frame if n not in order]
        # per-particle datasets only (a frame's bodies/ group holds the bodies' poses)
        count = frame["id"].shape[0] if "id" in frame else None
        order = [n for n in order if isinstance(frame[n], h5py.Dataset)
                 and (count is None or (frame[n].shape and frame[n].shape[0] == count))]
        header, columns = _columns(frame, order)
    count = len(columns[0]) if columns else 0
    if "material" in header and names:
        # the material by its name (the frames hold its index into the root's ``materials``)
        k = header.index("material")
        columns[k] = np.array([names[int(m)] if 0 <= int(m) < len(names) else str(int(m))
                               for m in columns[k]], dtype=object)
    writer = csv.writer(out)
    writer.writerow(["frame", "time [s]"] + header)
    for i in range(count):
        writer.writerow([str(number), repr(time)]
                        + [c[i] if c.dtype == object else repr(c[i].item()) for c in columns])
    return count


def add_arguments(p) -> None:
    """The ``taichi-dem export`` arguments."""
    p.add_argument("results", help="a results file written by run/demo/resume (--h5)")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--series", action="store_true",
                      help="every /series dataset, one row per sample, units in the header")
    what.add_argument("--frame", type=int, metavar="K",
                      help="particle frame K (-1: the last), one row per particle")
    what.add_argument("--xdmf", action="store_true",
                      help="an XDMF file describing every frame, for ParaView (the data stay "
                           "in the results file: keep the two together)")
    p.add_argument("--out", default=None,
                   help="the CSV file (default: <results stem>_series.csv or "
                        "<results stem>_frame<K>.csv beside the results; '-' for stdout), or "
                        "the XDMF file (default: <results stem>.xdmf beside the results)")


def cmd_export(args) -> int:
    """``taichi-dem export``."""
    path = Path(args.results)
    if not path.is_file():
        raise SceneError(str(path), "", "no such results file")
    try:
        import h5py
        h5py.File(path, "r").close()
    except OSError:
        raise SceneError(str(path), "", "not an HDF5 results file") from None
    if args.xdmf:
        from ..recorders.xdmf import write_xdmf
        from ..recorders.paraview import write_paraview_script
        target, frames = write_xdmf(path, None if args.out in (None, "-") else args.out)
        view = write_paraview_script(path, target)
        print(f"wrote {target} ({frames} frames; open it in ParaView beside {path.name})"
              + (f" and {view.name} (in ParaView: File > Load State; or `python {view.name} "
                 "--png view.png` with VTK)" if view else ""), file=sys.stderr)
        return 0
    if args.out == "-":
        stream, target = sys.stdout, None
    else:
        suffix = ("_series.csv" if args.series
                  else f"_frame{frame_number(path, args.frame)}.csv")
        target = Path(args.out) if args.out else path.with_name(path.stem + suffix)
        stream = open(target, "w", newline="")
    try:
        n = (export_series(path, stream) if args.series
             else export_frame(path, args.frame, stream))
    except BrokenPipeError:         # stdout piped into `head`: it stopped reading, not an error
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    finally:
        if target is not None:
            stream.close()
    if target is not None:
        print(f"wrote {target} ({n} rows)", file=sys.stderr)
    return 0
