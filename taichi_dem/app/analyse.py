"""``taichi-dem analyse RESULTS.h5 WHAT``: what EDEM Analyst users check a design with, from
the particle frames and records of a results file (no rerun of the simulation):

- ``profile``: bins along an axis (or around it: ``--radial``), averaged over a time window -
  hold-up (kg per bin and kg/m), particle count, the mass-weighted mean velocity along the
  axis, temperature and moisture - as CSV, and a PNG with ``--plot``;
- ``track``: chosen particles' positions, velocities (and temperatures) frame by frame;
- ``residence``: a residence-time sensor's records (id, time in, time out, residence);
- ``video``: an animated GIF (an MP4 where ffmpeg is installed) of the frames, the particles
  drawn to scale in a plane.

Every one takes a selection: ``--material NAME`` and a box ``--region XMIN YMIN ZMIN XMAX YMAX
ZMAX`` (m). Plain numpy, h5py and matplotlib; errors are ``file: key: reason`` (exit 2).
"""
from __future__ import annotations

import csv
import math
import sys
from pathlib import Path
from typing import Optional

import numpy as np

from ..errors import SceneError

KINDS = ("profile", "track", "residence", "video")


# ------------------------------------------------------------------------------ reading
def _open(path):
    import h5py
    try:
        return h5py.File(path, "r")
    except OSError:
        raise SceneError(str(path), "", "not an HDF5 results file") from None


def frames(f) -> list[tuple[int, float, object]]:
    """(number, time s, group) of every particle frame, in order."""
    if "frames" not in f or not len(f["frames"]):
        raise SceneError(f.filename, "frames", "the results file holds no particle frames")
    keys = sorted(f["frames"], key=int)
    return [(int(k), float(f["frames"][k].attrs.get("time", math.nan)), f["frames"][k])
            for k in keys]


def selection(f, frame, material: Optional[str], region) -> np.ndarray:
    """The particles of ``frame`` the selection keeps (a boolean mask): of ``material`` (a
    name of the root attribute ``materials``), inside ``region`` (xmin, ymin, zmin, xmax, ymax,
    zmax, m)."""
    n = frame["position"].shape[0]
    keep = np.ones(n, bool)
    if material is not None:
        names = [str(m) for m in f.attrs.get("materials", [])]
        if material not in names:
            raise SceneError(f.filename, "--material", f"no material '{material}' in the file; "
                                                       f"it has: {', '.join(names) or 'none'}")
        if "material" not in frame:
            raise SceneError(f.filename, "--material", "the frames hold no material index")
        keep &= frame["material"][()] == names.index(material)
    if region is not None:
        lo, hi = np.asarray(region[:3], float), np.asarray(region[3:], float)
        x = frame["position"][()]
        keep &= np.all((x >= lo) & (x <= hi), axis=1)
    return keep


def _axis(direction: str) -> np.ndarray:
    """A unit axis from "x", "y", "z" or "DX,DY,DZ"."""
    named = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
    try:
        v = np.asarray(named[direction] if direction in named else
                       [float(c) for c in direction.split(",")], float)
    except ValueError:
        v = np.zeros(0)
    if v.shape != (3,) or not np.linalg.norm(v) > 0:
        raise SceneError("--axis", "", f"'{direction}' is not x, y, z or a direction DX,DY,DZ")
    return v / np.linalg.norm(v)


# ------------------------------------------------------------------------------ profile
def profile(path, bins: int, axis: str = "x", origin=(0.0, 0.0, 0.0), span=None,
            radial: Optional[float] = None, t0: float = -math.inf, t1: float = math.inf,
            material: Optional[str] = None, region=None) -> dict:
    """Bins along ``axis`` through ``origin`` (m; ``span`` (lo, hi) in m along it, default the
    particles' extent), or with ``radial`` = R, ``bins`` rings from the axis out to R m;
    averaged over the frames with t0 <= time <= t1. Returns {"centre" m, "mass" kg (mean per
    frame), "mass_per_length" kg/m (axial bins), "count" (mean per frame), "axial_velocity"
    m/s, "temperature" K, "moisture" kg/kg (mass-weighted means over the window; NaN in an
    empty bin), "frames": the frames averaged, "edges" m}."""
    if bins < 1:
        raise SceneError("--bins", "", f"must be at least 1, got {bins}")
    a = _axis(axis)
    p0 = np.asarray(origin, float)
    with _open(path) as f:
        chosen = [(k, t, g) for k, t, g in frames(f) if t0 <= t <= t1]
        if not chosen:
            raise SceneError(str(path), "--from/--to", f"no frame in [{t0:g}, {t1:g}] s")
        rows = []
        for _, _, g in chosen:
            keep = selection(f, g, material, region)
            x = g["position"][()][keep] - p0
            along = x @ a
            coordinate = (np.linalg.norm(x - np.outer(along, a), axis=1) if radial is not None
                          else along)
            mass = g["mass"][()][keep] if "mass" in g else np.ones(len(x))
            v = (g["velocity"][()][keep] @ a) if "velocity" in g else np.full(len(x), np.nan)
            temp = g["temperature"][()][keep] if "temperature" in g else None
            moist = g["moisture"][()][keep] if "moisture" in g else None
            rows.append((coordinate, mass, v, temp, moist))
    if radial is not None:
        if not radial > 0:
            raise SceneError("--radial", "", f"must be a radius > 0, got {radial}")
        edges = np.linspace(0.0, float(radial), bins + 1)
    else:
        if span is None:
            every = np.concatenate([r[0] for r in rows])
            if not len(every):
                raise SceneError(str(path), "--range", "no particle selected in the window: "
                                                       "give the range")
            span = (float(every.min()), float(every.max()) + 1e-12)
        edges = np.linspace(float(span[0]), float(span[1]), bins + 1)
    mass = np.zeros(bins)
    count = np.zeros(bins)
    momentum = np.zeros(bins)
    heat = np.zeros(bins)
    heat_mass = np.zeros(bins)
    water = np.zeros(bins)
    water_mass = np.zeros(bins)
    for coordinate, m, v, temp, moist in rows:
        k = np.digitize(coordinate, edges) - 1
        inside = (k >= 0) & (k < bins)
        k, m, v = k[inside], m[inside], v[inside]
        mass += np.bincount(k, weights=m, minlength=bins)
        count += np.bincount(k, minlength=bins)
        momentum += np.bincount(k, weights=m * v, minlength=bins)
        if temp is not None:
            heat += np.bincount(k, weights=m * temp[inside], minlength=bins)
            heat_mass += np.bincount(k, weights=m, minlength=bins)
        if moist is not None:
            water += np.bincount(k, weights=m * moist[inside], minlength=bins)
            water_mass += np.bincount(k, weights=m, minlength=bins)
    n = len(rows)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = {"edges": edges, "centre": 0.5 * (edges[1:] + edges[:-1]), "mass": mass / n,
               "count": count / n, "axial_velocity": momentum / mass,
               "temperature": heat / heat_mass if heat_mass.any() else np.full(bins, np.nan),
               "moisture": water / water_mass if water_mass.any() else np.full(bins, np.nan),
               "frames": n}
    if radial is None:
        out["mass_per_length"] = out["mass"] / np.diff(edges)
    return out


PROFILE_COLUMNS = (("centre", "m"), ("mass", "kg"), ("mass_per_length", "kg/m"),
                   ("count", "1"), ("axial_velocity", "m/s"), ("temperature", "K"),
                   ("moisture", "kg/kg"))


def write_profile(result: dict, out) -> int:
    """The profile as CSV (a header with units); returns the bins written."""
    columns = [(name, unit) for name, unit in PROFILE_COLUMNS if name in result]
    writer = csv.writer(out)
    writer.writerow([f"{name} [{unit}]" for name, unit in columns])
    for i in range(len(result["centre"])):
        writer.writerow([repr(float(result[name][i])) for name, _ in columns])
    return len(result["centre"])


def plot_profile(result: dict, png, label: str) -> None:
    """Hold-up, axial velocity and (where given) temperature against the bin centre."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    panels = [("mass_per_length" if "mass_per_length" in result else "mass",
               "hold-up (kg/m)" if "mass_per_length" in result else "mass (kg)"),
              ("axial_velocity", "axial velocity (m/s)")]
    if np.isfinite(result["temperature"]).any():
        panels.append(("temperature", "temperature (K)"))
    fig, axes = plt.subplots(len(panels), 1, figsize=(6, 2.4 * len(panels)), sharex=True)
    for ax, (name, words) in zip(np.atleast_1d(axes), panels):
        ax.plot(result["centre"], result[name], "o-")
        ax.set_ylabel(words)
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel(label)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


# ------------------------------------------------------------------------------ tracks
def tracks(path, ids, material: Optional[str] = None, region=None) -> list[list]:
    """Rows (frame, time s, id, x, y, z m, vx, vy, vz m/s, temperature K or NaN) of the
    particles ``ids`` in every frame that holds them (and that the selection keeps)."""
    wanted = set(int(i) for i in ids)
    rows = []
    with _open(path) as f:
        for k, t, g in frames(f):
            if "id" not in g:
                raise SceneError(str(path), f"frames/{k}/id", "missing: tracks need the ids")
            keep = selection(f, g, material, region)
            ident = g["id"][()]
            hit = np.nonzero(keep & np.isin(ident, list(wanted)))[0]
            x = g["position"][()]
            v = g["velocity"][()] if "velocity" in g else np.full_like(x, np.nan)
            temp = g["temperature"][()] if "temperature" in g else None
            for i in hit[np.argsort(ident[hit], kind="stable")]:
                rows.append([k, t, int(ident[i]), *map(float, x[i]), *map(float, v[i]),
                             float(temp[i]) if temp is not None else math.nan])
    return rows


TRACK_HEADER = ["frame", "time [s]", "id", "x [m]", "y [m]", "z [m]", "vx [m/s]", "vy [m/s]",
                "vz [m/s]", "temperature [K]"]


# ------------------------------------------------------------------------------ residence
def residence_records(path, name: Optional[str] = None) -> tuple[str, np.ndarray]:
    """(sensor name, rows of id, t_in s, t_out s, residence s) of a residence-time sensor's
    records (``name``: the only one when left out)."""
    with _open(path) as f:
        sensors = sorted(f["residence"]) if "residence" in f else []
        if not sensors:
            raise SceneError(str(path), "residence", "the results file holds no residence "
                                                     "records (a residence_time sensor writes them)")
        if name is None:
            if len(sensors) > 1:
                raise SceneError(str(path), "--sensor", f"several residence sensors: "
                                                        f"{', '.join(sensors)}; name one")
            name = sensors[0]
        if name not in sensors:
            raise SceneError(str(path), "--sensor", f"no residence sensor '{name}'; the file "
                                                    f"has: {', '.join(sensors)}")
        g = f["residence"][name]
        t_in, t_out = g["t_in"][()].astype(float), g["t_out"][()].astype(float)
        rows = np.column_stack([g["id"][()].astype(float), t_in, t_out, t_out - t_in])
    return name, rows


# ------------------------------------------------------------------------------ video
def video(path, target, view: str = "xz", material: Optional[str] = None, region=None,
          fps: int = 10) -> int:
    """Draw every frame's selected particles to scale in the plane ``view`` (two of x, y, z)
    into ``target`` (.gif, or .mp4 where ffmpeg is installed); returns the frames drawn."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation
    from matplotlib.collections import EllipseCollection
    if len(view) != 2 or any(c not in "xyz" for c in view) or view[0] == view[1]:
        raise SceneError("--view", "", f"'{view}' is not a plane such as xz, xy or yz")
    axes_index = ["xyz".index(c) for c in view]
    target = Path(target)
    if target.suffix.lower() not in (".gif", ".mp4"):
        raise SceneError(str(target), "", "a video is a .gif or an .mp4")
    if target.suffix.lower() == ".mp4" and not animation.FFMpegWriter.isAvailable():
        raise SceneError(str(target), "", "an .mp4 needs ffmpeg, which is not installed; "
                                          "write a .gif")
    with _open(path) as f:
        drawn = []
        for k, t, g in frames(f):
            keep = selection(f, g, material, region)
            x = g["position"][()][keep][:, axes_index]
            r = g["radius"][()][keep] if "radius" in g else np.full(len(x), 1e-3)
            drawn.append((k, t, x, r))
    every = np.concatenate([d[2] for d in drawn]) if drawn else np.zeros((0, 2))
    if not len(every):
        raise SceneError(str(path), "frames", "no particle selected in any frame")
    pad = float(max(d[3].max() for d in drawn if len(d[3])))
    lo, hi = every.min(axis=0) - pad, every.max(axis=0) + pad
    fig, ax = plt.subplots(figsize=(6, 6 * (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-12) + 0.6))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel(f"{view[0]} (m)")
    ax.set_ylabel(f"{view[1]} (m)")

    def draw(i):
        for c in list(ax.collections):
            c.remove()
        k, t, x, r = drawn[i]
        ax.add_collection(EllipseCollection(2 * r, 2 * r, np.zeros(len(r)), units="xy",
                                            offsets=x, offset_transform=ax.transData,
                                            facecolors="tab:orange", edgecolors="k",
                                            linewidths=0.2))
        ax.set_title(f"frame {k}, t = {t:.3f} s")
        return list(ax.collections)

    movie = animation.FuncAnimation(fig, draw, frames=len(drawn), blit=False)
    writer = (animation.PillowWriter(fps=fps) if target.suffix.lower() == ".gif"
              else animation.FFMpegWriter(fps=fps))
    movie.save(str(target), writer=writer)
    plt.close(fig)
    return len(drawn)


# ------------------------------------------------------------------------------ command
def add_arguments(p) -> None:
    """The ``taichi-dem analyse`` arguments."""
    p.add_argument("results", help="a results file written by run/demo/resume")
    p.add_argument("what", choices=KINDS, help="profile: bins along (or around) an axis; "
                   "track: chosen particles; residence: a residence sensor's records; video: "
                   "a GIF or MP4 of the frames")
    p.add_argument("--out", default=None, help="the CSV (profile, track, residence; '-': "
                   "stdout) or the video file (default: beside the results, "
                   "<stem>_<what>.csv or <stem>.gif)")
    p.add_argument("--material", default=None, help="only this material's particles")
    p.add_argument("--region", nargs=6, type=float, default=None,
                   metavar=("XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"),
                   help="only the particles inside this box (m)")
    g = p.add_argument_group("profile")
    g.add_argument("--bins", type=int, default=20, help="bins (default 20)")
    g.add_argument("--axis", default="x", help="x, y, z or a direction DX,DY,DZ (default x)")
    g.add_argument("--origin", nargs=3, type=float, default=(0.0, 0.0, 0.0),
                   metavar=("X", "Y", "Z"), help="a point of the axis (m; default the origin)")
    g.add_argument("--range", nargs=2, type=float, default=None, metavar=("LO", "HI"),
                   help="the span along the axis (m; default the particles' extent)")
    g.add_argument("--radial", type=float, default=None, metavar="R",
                   help="rings around the axis out to R m instead of bins along it")
    g.add_argument("--from", dest="t0", type=float, default=-math.inf,
                   help="average the frames from this time (s)")
    g.add_argument("--to", dest="t1", type=float, default=math.inf,
                   help="... to this time (s)")
    g.add_argument("--plot", default=None, metavar="PNG", help="also draw the profile")
    t = p.add_argument_group("track")
    t.add_argument("--ids", nargs="+", type=int, default=None, help="the particles' ids")
    r = p.add_argument_group("residence")
    r.add_argument("--sensor", default=None, help="the residence sensor (when there are several)")
    v = p.add_argument_group("video")
    v.add_argument("--view", default="xz", help="the plane drawn: xz (default), xy, yz, ...")
    v.add_argument("--fps", type=int, default=10, help="frames per second of the video")


def _stream(args, default: Path):
    if args.out == "-":
        return sys.stdout, None
    target = Path(args.out) if args.out else default
    return open(target, "w", newline=""), target


def cmd_analyse(args) -> int:
    """``taichi-dem analyse``."""
    path = Path(args.results)
    if not path.is_file():
        raise SceneError(str(path), "", "no such results file")
    stem = path.with_name(path.stem)
    if args.what == "video":
        target = Path(args.out) if args.out else stem.with_suffix(".gif")
        n = video(path, target, args.view, args.material, args.region, args.fps)
        print(f"wrote {target} ({n} frames)", file=sys.stderr)
        return 0
    if args.what == "profile":
        result = profile(path, args.bins, args.axis, args.origin, args.range, args.radial,
                         args.t0, args.t1, args.material, args.region)
        stream, target = _stream(args, Path(f"{stem}_profile.csv"))
        try:
            n = write_profile(result, stream)
        finally:
            if target is not None:
                stream.close()
        if args.plot:
            plot_profile(result, args.plot, "radius (m)" if args.radial else "along the axis (m)")
        what = f"{n} bins over {result['frames']} frames"
    elif args.what == "track":
        if not args.ids:
            raise SceneError("--ids", "", "name the particles to track: --ids 3 7 ...")
        rows = tracks(path, args.ids, args.material, args.region)
        stream, target = _stream(args, Path(f"{stem}_tracks.csv"))
        try:
            writer = csv.writer(stream)
            writer.writerow(TRACK_HEADER)
            writer.writerows([[str(c) if isinstance(c, int) else repr(c) for c in row]
                              for row in rows])
        finally:
            if target is not None:
                stream.close()
        what = f"{len(rows)} rows"
    else:
        name, rows = residence_records(path, args.sensor)
        stream, target = _stream(args, Path(f"{stem}_residence_{name}.csv"))
        try:
            writer = csv.writer(stream)
            writer.writerow(["id", "t_in [s]", "t_out [s]", "residence [s]"])
            writer.writerows([[str(int(r[0]))] + [repr(float(c)) for c in r[1:]] for r in rows])
        finally:
            if target is not None:
                stream.close()
        what = f"{len(rows)} records of '{name}'"
    if target is not None:
        print(f"wrote {target} ({what})", file=sys.stderr)
    return 0
