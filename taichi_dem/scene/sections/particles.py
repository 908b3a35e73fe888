"""[[particles]] (the initial fills: a region or a CSV file), radius distributions and
regions (box, cylinder): their keys and checks."""
from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ...errors import SceneError
from ..keys import REQUIRED, Key, Section, added_values, host_section, register
from ..keys import suggest as _suggest
from ..model import ParticleFill, RadiusDistribution, Region
from ..units import MAX_MAGNITUDE, MIN_MAGNITUDE
from .common import control_character, decode_utf8
from .regions import BOX, BOX_KEYS, CYLINDER, CYLINDER_KEYS, REGION, REGION_KINDS  # noqa: F401

CSV_COLUMNS = ("x", "y", "z", "radius", "vx", "vy", "vz", "wx", "wy", "wz")
_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0


RADIUS = register(Section("radius", "A radius distribution (normal, optionally truncated): a "
                          "number for one size, or this table", (
    Key("mean", "quantity", "the mean radius", unit="length", default=REQUIRED, **_P),
    Key("std", "quantity", "the standard deviation", unit="length", default=REQUIRED,
        minimum=0.0),
    Key("min", "quantity", "truncated below", unit="length", default=None, **_P),
    Key("max", "quantity", "truncated above", unit="length", default=None, **_P),
), owner=__name__))

PARTICLE = register(Section("particles[]", "An initial fill, [[particles]]: `count` spheres "
                            "placed at random without overlap in `region`, or the rows of a CSV "
                            "`file`", (
    Key("material", "string", "a material name", default=REQUIRED),
    Key("radius", "any", "a radius, or a distribution { mean, std, min, max }", unit="length",
        default=None, schema={"anyOf": [{"type": ["number", "string"]}, {"type": "object"}]}),
    Key("count", "integer", "how many spheres (with region)", default=0, minimum=0),
    Key("region", "table", "where they are placed: { box = ... } or { cylinder = ... }",
        default=None),
    Key("velocity", "vector", "initial velocity", unit="speed", default=(0.0, 0.0, 0.0)),
    Key("angular_velocity", "vector", "initial angular velocity", unit="angular_speed",
        default=(0.0, 0.0, 0.0)),
    Key("fixed", "boolean", "frozen in place (a rough wall of spheres)", default=False),
    Key("file", "string", "a CSV of x,y,z,radius[,vx,vy,vz[,wx,wy,wz]] (SI), or a results file "
        "(.h5) of an earlier run whose frame gives the particles of this fill's material (their "
        "positions, radii, velocities and, unless the fill gives them, temperatures and "
        "moistures): settle once, run many cases; instead of count and region", default=None),
    Key("frame", "integer", "with a results file: the frame to start from (-1 the last, the "
        "default; 0 the first)", default=None),
), owner=__name__, nested={"region": REGION, "radius": RADIUS}))


class ParticleSections:
    """Read by the loader's parser (scene/loader.py), which mixes this in with the reading
    helpers of common.Reader."""

    def parse_radius(self, value: Any, key: str) -> RadiusDistribution:
        if isinstance(value, dict):
            self.check_keys(value, key, RADIUS)
            mean = self.positive(value["mean"], "length", f"{key}.mean")
            std = self.nonnegative(value["std"], "length", f"{key}.std")
            if std > 0.0:
                for k in ("min", "max"):
                    if k not in value:
                        raise self.err(f"{key}.{k}", "required when std > 0 (the normal "
                                                     "distribution is truncated to [min, max])")
            lo = self.positive(value["min"], "length", f"{key}.min") if "min" in value else None
            hi = self.positive(value["max"], "length", f"{key}.max") if "max" in value else None
            if lo is not None and not lo <= mean:
                raise self.err(f"{key}.min", f"need 0 < min <= mean <= max; min = {lo:g} > "
                                             f"mean = {mean:g}")
            if hi is not None and not mean <= hi:
                raise self.err(f"{key}.max", f"need 0 < min <= mean <= max; max = {hi:g} < "
                                             f"mean = {mean:g}")
            return RadiusDistribution(mean=mean, std=std, min=lo, max=hi)
        try:
            return RadiusDistribution(mean=self.positive(value, "length", key))
        except SceneError as e:
            raise self.err(key, f"{e.reason}; radius is a positive length or a table "
                                f"{{ mean, std, min, max }}") from None

    def parse_region(self, value: Any, key: str) -> Region:
        t = self.table(value, key, "a table { box = {...} } or { cylinder = {...} }")
        self.check_keys(t, key, REGION)
        if len(t) != 1:
            raise self.err(key, "give exactly one of box = { min, max } or cylinder = "
                                "{ axis_point, axis_direction, radius, length }")
        kind = next(iter(t))
        k = f"{key}.{kind}"
        sub = self.table(t[kind], k)
        if kind == "box":
            self.check_keys(sub, k, BOX)
            lo, hi = self.corners(sub, k)
            region = Region(kind="box", box_min=lo, box_max=hi)
            amin, amax = np.array(lo), np.array(hi)
        else:
            self.check_keys(sub, k, CYLINDER)
            p = self.vec3(sub["axis_point"], "length", f"{k}.axis_point")
            d = self.direction(sub["axis_direction"], f"{k}.axis_direction")
            r = self.positive(sub["radius"], "length", f"{k}.radius")
            length = self.positive(sub["length"], "length", f"{k}.length")
            region = Region(kind="cylinder", axis_point=p, axis_direction=d, radius=r,
                            length=length)
            amin, amax = region_bounds(region)
        dlo, dhi = np.array(self.domain.min), np.array(self.domain.max)
        tol = 1e-9 * float(np.max(dhi - dlo))
        if np.any(amin < dlo - tol) or np.any(amax > dhi + tol):
            raise self.err(k, f"the region (bounds {fmt(amin)} to {fmt(amax)}) must lie inside "
                              f"the domain ({fmt(dlo)} to {fmt(dhi)})")
        return region

    def parse_fill(self, t: dict, key: str) -> ParticleFill:
        self.check_keys(t, key, host_section(PARTICLE), required=("material",))
        material = self.material_name(t["material"], f"{key}.material")
        kw: dict[str, Any] = {}
        if "velocity" in t:
            kw["velocity"] = self.vec3(t["velocity"], "speed", f"{key}.velocity")
        if "angular_velocity" in t:
            kw["angular_velocity"] = self.vec3(t["angular_velocity"], "angular_speed",
                                               f"{key}.angular_velocity")
        kw["effect_values"] = added_values(PARTICLE.path, t, self.source, key)
        if "fixed" in t:
            kw["fixed"] = self.boolean(t["fixed"], f"{key}.fixed")
        if "file" in t:
            for k in ("count", "region", "radius"):
                if k in t:
                    raise self.err(f"{key}.{k}", "not allowed together with file (the file "
                                                 "gives positions and radii); use either file "
                                                 "or count + region + radius")
            fname = self.string(t["file"], f"{key}.file")
            if fname.lower().endswith((".h5", ".hdf5")):
                frame = self.integer(t["frame"], f"{key}.frame") if "frame" in t else -1
                arrays = self.read_frame(fname, f"{key}.file", frame, material)
                own = {t for t, _, _ in OWN_FRAME_DATASETS.values()}
                kw["frame_values"] = {t: a for t, a in arrays.items()
                                      if t not in own and a is not None}
                return ParticleFill(key=key, material=material, file=fname, frame=frame,
                                    **{t: a for t, a in arrays.items() if t in own}, **kw)
            if "frame" in t:
                raise self.err(f"{key}.frame", "only with a results file (.h5) as file; a CSV "
                                               "holds one set of particles")
            arrays = self.read_csv(fname, f"{key}.file")
            return ParticleFill(key=key, material=material, file=fname, **arrays, **kw)
        if "frame" in t:
            raise self.err(f"{key}.frame", "only with file = a results file (.h5)")
        for k in ("count", "region", "radius"):
            if k not in t:
                raise self.err(f"{key}.{k}", "required key is missing (a fill needs count, "
                                             "region and radius, or file)")
        radius = self.parse_radius(t["radius"], f"{key}.radius")
        count = self.integer(t["count"], f"{key}.count")
        if count < 0:
            raise self.err(f"{key}.count", f"must be >= 0, got {count}")
        region = self.parse_region(t["region"], f"{key}.region")
        if count > 0:
            self.check_fill_fits(key, radius, count, region)
        return ParticleFill(key=key, material=material, radius=radius, count=count,
                            region=region, **kw)

    def check_fill_fits(self, key: str, radius: RadiusDistribution, count: int,
                        region: Region) -> None:
        """Refuse, before any placement, a fill that cannot fit its region: a sphere wider
        than the region, or more spheres than the region's volume holds (a count of 1e15 would
        otherwise be allocated by the placement)."""
        width = _region_width(region)
        r = radius.largest
        if 2.0 * r > width:
            raise self.err(f"{key}.radius", f"a sphere of radius {r:g} m does not fit in the "
                                            f"region, which is {width:g} m across at its "
                                            "narrowest (each sphere must lie wholly inside "
                                            "it); check the units or enlarge the region")
        volume = _region_volume(region)
        solid = count * 4.0 / 3.0 * math.pi * radius.smallest ** 3
        if solid > volume:
            raise self.err(f"{key}.count", f"{count:,} spheres of radius {radius.smallest:g} m "
                                           f"or more are {solid:.4g} m^3 of solid, more than "
                                           f"the region's whole volume ({volume:.4g} m^3); "
                                           "reduce count or enlarge the region")

    def read_frame(self, fname: str, key: str, frame: int, material: str) -> dict:
        """The particles of ``material`` in frame ``frame`` (negative: from the last) of the
        results file ``fname`` (relative to the scene): positions (m), radii (m), velocities
        (m/s), angular velocities (rad/s) and, when the frame has them, the fields effects add
        to frames (a temperature, K), each by its name. The file is validated like a scene: every dataset's shape and type,
        one row per particle everywhere, finite values, positive radii (and temperatures); what
        is wrong is a SceneError naming the scene, ``key``, the HDF5 file and the dataset."""
        import h5py
        path = self.resolve_path(fname, key)
        if not path.is_file():
            raise self.err(key, f"results file '{fname}' not found (looked for {path})")
        where = str(path)

        def bad(reason: str) -> SceneError:
            return self.err(key, f"{where}: {reason}")

        try:
            f = h5py.File(path, "r")
        except OSError as e:
            raise bad(f"cannot open as an HDF5 results file ({e})") from None
        try:
            with f:
                if "fields" in f and "count" in f.attrs:
                    out = _checkpoint_particles(f, where, key, material, self, bad)
                else:
                    out = self._frame_particles(f, where, key, frame, material, bad)
        except OSError as e:           # h5py: a dataset or link that cannot be read
            raise bad(f"cannot read the HDF5 file ({e})") from None
        return self._inside_domain(out, key)

    def _frame_particles(self, f, where: str, key: str, frame: int, material: str,
                         bad) -> dict:
        """read_frame for a results file: the rows of ``material`` in /frames/<k>."""
        import h5py
        frames = _member(f, "frames", bad)
        if frames is None or (isinstance(frames, h5py.Group) and not len(frames)):
            raise bad("the file holds no particle frames (is it a results file of a run that "
                      "wrote some?)")
        if not isinstance(frames, h5py.Group):
            raise bad("/frames is a dataset; a results file's /frames is a group of frames "
                      "/frames/0, /frames/1, ...")
        names = list(frames)
        odd = [n for n in names if not re.fullmatch(r"[0-9]{1,18}", n)]
        if odd:
            raise bad(f"the frame group /frames/{_printable(odd[0])} is not named by a frame "
                      "number; a results file's frames are /frames/0, /frames/1, ...")
        keys = sorted(names, key=int)
        if not -len(keys) <= frame < len(keys):
            raise self.err(key.rsplit(".", 1)[0] + ".frame",
                           f"{frame}: no such frame; {where} holds {len(keys)} "
                           f"(0 - {len(keys) - 1}, or -1 for the last)")
        gpath = f"/frames/{keys[frame]}"
        g = frames[keys[frame]]
        if not isinstance(g, h5py.Group):
            raise bad(f"{gpath} is a dataset; a frame is a group of datasets (position, "
                      "radius, velocity, ...)")
        arrays = {}
        for name, (target, columns, _) in frame_datasets().items():
            ds = _member(g, name, bad, gpath)
            if ds is None:
                if name in ("position", "radius"):
                    raise bad(f"frame {keys[frame]} has no '{name}' dataset ({gpath}/{name})")
                arrays[target] = None
                continue
            arrays[target] = _numeric(ds, f"{gpath}/{name}", bad)
        count = _rows(arrays, gpath, bad)
        rows = np.arange(count)
        names = _material_names(f, bad)
        mds = _member(g, "material", bad, gpath)
        if names and mds is not None:
            if material not in names:
                raise bad(f"holds no particles of material '{material}' (its materials: "
                          f"{', '.join(_printable(n) for n in names)})")
            index = _numeric(mds, f"{gpath}/material", bad)
            if index.shape != (count,) or index.dtype.kind not in "iu":
                raise bad(f"dataset {gpath}/material has shape {index.shape} and type "
                          f"{index.dtype}; expected one material index (an integer) per "
                          f"particle, shape ({count},)")
            rows = np.nonzero(index == names.index(material))[0]
            if not len(rows):
                raise bad(f"frame {keys[frame]} holds no particles of material '{material}'")
        _check_values(arrays, {n: f"{gpath}/{n}" for n in frame_datasets()}, bad)
        return {target: (None if a is None else a[rows].astype(float))
                for target, a in arrays.items()}

    def resolve_path(self, fname: str, key: str) -> Path:
        """A file the scene names, relative to the scene's folder; a NUL byte
        or another control character in the name is a SceneError for ``key``."""
        char = control_character(fname)
        if char is not None:
            raise self.err(key, f"the file name contains the control character {char}; a "
                                "path cannot hold it")
        path = Path(fname)
        return path if path.is_absolute() else self.base_dir / path

    def _inside_domain(self, out: dict, key: str) -> dict:
        """``out`` (read_frame's arrays) when every centre lies in this scene's domain."""
        lo, hi = np.array(self.domain.min), np.array(self.domain.max)
        outside = np.nonzero(np.any((out["positions"] < lo) | (out["positions"] > hi), axis=1))[0]
        if len(outside):
            raise self.err(key, f"{len(outside)} of the frame's particles lie outside this scene's "
                                f"domain ({fmt(lo)} to {fmt(hi)}), e.g. one at "
                                f"{fmt(out['positions'][outside[0]])}")
        return out

    def read_csv(self, fname: str, key: str) -> dict[str, Optional[np.ndarray]]:
        """The particles of a CSV file (relative to the scene) with the header
        x,y,z,radius[,vx,vy,vz[,wx,wy,wz]] (SI: m, m/s, rad/s); a SceneError naming the CSV
        file, ``key``, the line and the column otherwise (never quoting the file's text)."""
        path = self.resolve_path(fname, key)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            raise self.err(key, f"particle file '{fname}' not found (looked for {path})") from None
        except OSError as e:
            raise self.err(key, f"cannot read particle file '{fname}' ({path}): "
                                f"{e.strerror or e}") from None
        csv_file = str(path)
        try:
            rows = list(csv.reader(io.StringIO(decode_utf8(data, csv_file, key), newline="")))
        except csv.Error as e:
            raise SceneError(csv_file, key, f"cannot read as CSV: {e}") from None

        def bad(reason: str) -> SceneError:
            return SceneError(csv_file, key, reason)

        # skip leading blank lines / comments
        lines = [(i + 1, r) for i, r in enumerate(rows)
                 if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
        if not lines:
            raise bad("empty file; expected a header x,y,z,radius[,vx,vy,vz[,wx,wy,wz]]")
        hline, header = lines[0]
        names = [h.strip().lower() for h in header]
        # the messages below never quote the file's text (a scene could name any readable
        # file: /etc/passwd): they say where and what is wrong, and quote only column names
        # once the header has proved to be one
        for c, n in enumerate(names):
            if n not in CSV_COLUMNS:
                raise bad(f"line {hline}: column {c + 1} of the header is not a column "
                          f"name; {_suggest(n, CSV_COLUMNS)}the header must be "
                          f"x,y,z,radius[,vx,vy,vz[,wx,wy,wz]]; found {len(names)} "
                          f"column{'s' if len(names) != 1 else ''}")
        for n in set(names):
            if names.count(n) > 1:
                raise bad(f"line {hline}: column '{n}' appears twice in the header")
        for group in (("x", "y", "z", "radius"),):
            for n in group:
                if n not in names:
                    raise bad(f"line {hline}: the header lacks column '{n}'; expected "
                              f"x,y,z,radius[,vx,vy,vz[,wx,wy,wz]]")
        for group in (("vx", "vy", "vz"), ("wx", "wy", "wz")):
            present = [n for n in group if n in names]
            if present and len(present) != 3:
                raise bad(f"line {hline}: give all of {','.join(group)} or none of them")
        data = np.empty((len(lines) - 1, len(names)), dtype=float)
        for r, (lineno, row) in enumerate(lines[1:]):
            if len(row) != len(names):
                raise bad(f"line {lineno}: {len(row)} values, the header has {len(names)}")
            for c, cell in enumerate(row):
                try:
                    v = float(cell)
                except ValueError:
                    raise bad(f"line {lineno}, column '{names[c]}': not a number "
                              "(expected a decimal number such as 0.004 or 4e-3)") from None
                if not math.isfinite(v):
                    raise bad(f"line {lineno}, column '{names[c]}': not finite (NaN or "
                              "infinite)")
                if v != 0.0 and not MIN_MAGNITUDE <= abs(v) <= MAX_MAGNITUDE:
                    raise bad(f"line {lineno}, column '{names[c]}': {v:g} is absurd "
                              f"(SI magnitudes {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g} are "
                              "accepted; wrong units?)")
                data[r, c] = v
        col = {n: data[:, i] for i, n in enumerate(names)}
        positions = np.stack([col["x"], col["y"], col["z"]], axis=1)
        radii = col["radius"].copy()
        row_lines = [ln for ln, _ in lines[1:]]
        badr = np.nonzero(~(radii > 0.0))[0]
        if len(badr):
            raise bad(f"line {row_lines[badr[0]]}: radius must be > 0, got {radii[badr[0]]:g}")
        lo, hi = np.array(self.domain.min), np.array(self.domain.max)
        outside = np.nonzero(np.any((positions < lo) | (positions > hi), axis=1))[0]
        if len(outside):
            j = outside[0]
            raise bad(f"line {row_lines[j]}: the particle centre {fmt(positions[j])} lies "
                      f"outside the domain ({fmt(lo)} to {fmt(hi)})")
        vel = np.stack([col["vx"], col["vy"], col["vz"]], axis=1) if "vx" in col else None
        ang = np.stack([col["wx"], col["wy"], col["wz"]], axis=1) if "wx" in col else None
        return dict(positions=positions, radii=radii, velocities=vel, angular_velocities=ang)


def region_bounds(region: Region) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounding box of a region."""
    if region.kind == "box":
        return np.array(region.box_min, float), np.array(region.box_max, float)
    p0 = np.array(region.axis_point, float)
    d = np.array(region.axis_direction, float)
    p1 = p0 + d * region.length
    ext = region.radius * np.sqrt(np.clip(1.0 - d * d, 0.0, 1.0))
    return np.minimum(p0, p1) - ext, np.maximum(p0, p1) + ext


def _region_width(region: Region) -> float:
    """The region's narrowest extent, m: the widest sphere that fits is half of it."""
    if region.kind == "box":
        return float(np.min(np.array(region.box_max, float) - np.array(region.box_min, float)))
    return min(2.0 * region.radius, region.length)


def _region_volume(region: Region) -> float:
    if region.kind == "box":
        return float(np.prod(np.array(region.box_max, float) - np.array(region.box_min, float)))
    return math.pi * region.radius ** 2 * region.length


# the mechanics' per-particle datasets of a settled-start frame: dataset -> (read_frame's
# array, columns (None: one value per particle), what its values must be)
OWN_FRAME_DATASETS = {
    "position": ("positions", 3, "finite"),
    "radius": ("radii", None, "positive"),
    "velocity": ("velocities", 3, "finite"),
    "angular_velocity": ("angular_velocities", 3, "finite"),
}


def frame_datasets() -> dict:
    """OWN_FRAME_DATASETS and the fields the effects add to a frame (scene/catalog.py
    frame_fields: a temperature), each read under its own name into the fill's
    ``frame_values``, its values as the effect says (frame_field_values)."""
    from ..catalog import frame_field_values, frame_fields
    out = dict(OWN_FRAME_DATASETS)
    for name, rule in frame_field_values().items():
        shape = frame_fields()[name][1]
        columns = None if shape == "(N,)" else int(shape.strip("()").split(",")[1])
        out[name] = (name, columns, rule)
    return out


def _name_of(target: str) -> str:
    """The dataset a read_frame array ``target`` comes from."""
    return next(name for name, (t, _, _) in frame_datasets().items() if t == target)


def _printable(name: str) -> str:
    """``name`` with control characters escaped (a dataset name quoted in a message)."""
    return name if control_character(name) is None else name.encode("unicode_escape").decode()


def _member(group, name: str, bad, gpath: str = ""):
    """``group[name]`` (a dataset or group), None when absent; a link that cannot be followed
    is ``bad``."""
    try:
        return group[name] if name in group else None
    except (KeyError, OSError) as e:
        raise bad(f"{gpath}/{name} cannot be opened (a broken link?): {e}") from None


def _numeric(obj, dpath: str, bad) -> np.ndarray:
    """The values of the dataset ``obj`` (at ``dpath``) when it holds real numbers."""
    import h5py
    if not isinstance(obj, h5py.Dataset):
        raise bad(f"{dpath} is a group; expected a dataset of numbers")
    if obj.dtype.kind not in "iuf":
        raise bad(f"dataset {dpath} holds values of type {obj.dtype} "
                  f"({_KINDS.get(obj.dtype.kind, 'not numbers')}); expected real numbers")
    return np.asarray(obj[()])


_KINDS = {"b": "booleans", "c": "complex numbers", "S": "byte strings", "U": "strings",
          "O": "strings or objects", "V": "compound records or opaque data",
          "M": "dates", "m": "time spans"}


def _rows(arrays: dict, gpath: str, bad) -> int:
    """The particle count N of a frame's ``arrays`` (read_frame's names): every dataset has
    shape (N,) or (N, 3) as frame_datasets says, the same N everywhere."""
    count = None
    for target, a in arrays.items():
        if a is None:
            continue
        name = _name_of(target)
        columns = frame_datasets()[name][1]
        n = a.shape[0] if a.ndim else None
        want = "(N,)" if columns is None else f"(N, {columns})"
        if a.ndim != (1 if columns is None else 2) or (columns and a.shape[1] != columns):
            shape = "is a scalar" if a.ndim == 0 else f"has shape {a.shape}"
            raise bad(f"dataset {gpath}/{name} {shape}; expected {want}, one "
                      f"{'value' if columns is None else 'vector'} per particle")
        if count is None:
            count = n
        elif n != count:
            first = next(_name_of(t) for t, b in arrays.items() if b is not None)
            raise bad(f"dataset {gpath}/{name} has {n} rows but {gpath}/{first} has {count}; "
                      "every dataset of a frame has one row per particle")
    return count or 0


def _check_values(arrays: dict, paths: dict, bad, row_numbers=None) -> None:
    """Every value of a frame's ``arrays`` (read_frame's names; ``paths``: the dataset of
    each, ``row_numbers``: each row's number in it) finite and within the SI magnitudes a scene
    accepts; radii > 0, and the effects' fields as frame_datasets says."""
    for target, a in arrays.items():
        if a is None:
            continue
        name = _name_of(target)
        rule = frame_datasets()[name][2]
        values = a.astype(np.float64, copy=False).reshape(len(a), -1)
        magnitude = np.abs(values)
        tests = [(~np.isfinite(values), "is not finite (NaN or infinite)"),
                 ((values != 0.0) & ~((magnitude >= MIN_MAGNITUDE) & (magnitude <= MAX_MAGNITUDE)),
                  f"is absurd (SI magnitudes {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g} are "
                  "accepted)")]
        if rule == "positive":
            tests.append((~(values > 0.0), "is not > 0"))
        elif rule == "nonnegative":
            tests.append((~(values >= 0.0), "is negative"))
        for wrong, what in tests:
            rows = np.nonzero(np.any(wrong, axis=1))[0]
            if len(rows):
                row = int(rows[0])
                value = values[row][np.nonzero(wrong[row])[0][0]]
                number = row if row_numbers is None else int(row_numbers[row])
                raise bad(f"dataset {paths[name]}: {len(rows)} particle(s) with a "
                          f"{name.replace('_', ' ')} that {what}, e.g. row {number} (from 0): "
                          f"{value:g}")


def _material_names(f, bad) -> list[str]:
    """The file's ``materials`` attribute (the names of the frames' material indices)."""
    names = f.attrs.get("materials", ())
    if isinstance(names, (str, bytes)) or np.ndim(names) != 1:
        raise bad("the file's 'materials' attribute is not a list of material names")
    return [n.decode("utf-8", "replace") if isinstance(n, bytes) else str(n) for n in names]


def _checkpoint_particles(f, where: str, key: str, material: str, reader, bad) -> dict:
    """read_frame for a checkpoint file (run/checkpoint.py): the alive particles of
    ``material`` in the engine's fields as saved, in id order, with the f64 residuals of a
    split-precision state added back; every field used validated as a frame's datasets."""
    import tomllib
    import h5py
    fields: dict = {}

    def collect(name, obj):              # (visititems stops at the first non-None return)
        if isinstance(obj, h5py.Dataset):
            fields.setdefault(name.rsplit("/", 1)[-1], ("/fields/" + name, obj))
    group = f["fields"]
    if not isinstance(group, h5py.Group):
        raise bad("/fields is a dataset; a checkpoint's /fields is a group of the engine's "
                  "particle fields")
    group.visititems(collect)
    count = f.attrs["count"]
    if np.ndim(count) != 0 or np.asarray(count).dtype.kind not in "iu" or int(count) < 0:
        raise bad("the checkpoint's 'count' attribute is not a particle count (an integer "
                  ">= 0)")
    count = int(count)
    for name in ("alive", "material", "position", "radius"):
        if name not in fields:
            raise bad(f"the checkpoint's /fields has no '{name}' dataset (is it a checkpoint "
                      "of this version of taichi-dem?)")
    if "serial" not in fields and "particle_id" not in fields:
        raise bad("the checkpoint's /fields has neither a 'serial' nor a 'particle_id' "
                  "dataset (is it a checkpoint of this version of taichi-dem?)")
    try:
        names = sorted(tomllib.loads(str(f.attrs.get("scene", ""))).get("materials", {}))
    except (tomllib.TOMLDecodeError, RecursionError, AttributeError):
        names = []
    if material not in names:
        raise reader.err(key, f"{where} holds no particles of material '{material}' "
                              f"(its materials: {', '.join(names) or 'none named'})")

    def column(name, columns=None) -> np.ndarray:
        dpath, ds = fields[name]
        a = _numeric(ds, dpath, bad)
        want = (1 if columns is None else 2)
        if a.ndim != want or a.shape[0] < count or (columns and a.shape[1] != columns):
            shape = "is a scalar" if a.ndim == 0 else f"has shape {a.shape}"
            raise bad(f"dataset {dpath} {shape}; expected at least {count} rows (the "
                      f"checkpoint's count) of {'one value' if columns is None else 'a vector'}"
                      " per particle")
        return a[:count]
    alive = column("alive") != 0
    rows = np.nonzero(alive & (column("material") == names.index(material)))[0]
    if not len(rows):
        raise reader.err(key, f"the checkpoint {where} holds no particles of material "
                              f"'{material}'")
    ids = column("serial" if "serial" in fields else "particle_id")[rows]
    rows = rows[np.argsort(ids, kind="stable")]

    def read(name):
        if name not in fields:
            return None
        columns = frame_datasets()[name][1]
        value = column(name, columns)[rows].astype(float)
        if name + "_residual" in fields:
            value = value + column(name + "_residual", columns)[rows]
        return value
    out = {target: read(name) for name, (target, _, _) in frame_datasets().items()}
    _check_values(out, {n: fields[n][0] for n in frame_datasets() if n in fields}, bad, rows)
    return out


def fmt(v) -> str:
    return "[" + ", ".join(f"{float(x):g}" for x in v) + "]"
