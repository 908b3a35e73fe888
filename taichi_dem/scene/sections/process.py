"""[[factories]], [[outlets]] and [[sensors]]: their keys and checks."""
from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ...errors import SceneError
from ..keys import REQUIRED, Key, Section, added_values, host_section, register
from ..keys import suggest as _suggest
from ..model import Factory, Outlet, RateSchedule, Sensor, SheetInlet
from .particles import BOX, RADIUS, REGION, fmt, region_bounds
from .surfaces import PLANE

FACTORY_PATTERNS = ("random", "sheet")
SHEET_ONLY_KEYS = ("face", "jitter")          # pattern = "sheet" only
RANDOM_ONLY_KEYS = ("region", "sizes", "interval")   # pattern = "random" only
MAX_SHEET_JITTER = 0.25                       # of the diameter
SENSOR_KINDS = ("mass_flow", "residence_time", "contact_count", "contact_statistics")
_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0
_SCHEDULE = {"anyOf": [{"type": ["number", "string"]}, {"type": "array"}]}

FACE = register(Section("factories[].face", "A sheet factory's face: { point, width, depth } "
                        "or a box face { min, max } (one axis flat)", (
    Key("point", "vector", "the face's centre", unit="length", default=None),
    Key("width", "vector", "the face's first edge (a vector)", unit="length", default=None),
    Key("depth", "vector", "the face's second edge (a vector)", unit="length", default=None),
    Key("min", "vector", "a box face's lower corner", unit="length", default=None),
    Key("max", "vector", "a box face's upper corner", unit="length", default=None),
), owner=__name__))
FACTORY = register(Section("factories[]", "Insertion at a mass rate, [[factories]]: at random "
                           "in a region, or sheet layers through a face", (
    Key("name", "string", "its name (residence sensors)", default=REQUIRED),
    Key("material", "string", "a material name", default=REQUIRED),
    Key("radius", "any", "a radius or a distribution (or `sizes`)", unit="length",
        default=None, schema={"anyOf": [{"type": ["number", "string"]}, {"type": "object"}]}),
    Key("sizes", "any", "random only: a size mix [[radius, mass fraction], ...] (or `radius`)",
        unit="length", default=None,
        schema={"type": "array", "items": {"type": "array", "minItems": 2, "maxItems": 2}}),
    Key("region", "table", "random only: where particles appear", default=None),
    Key("velocity", "vector", "the inserted particles' velocity", unit="speed",
        default=(0.0, 0.0, 0.0)),
    Key("mass_rate", "any", "the mass rate, or a schedule [[t, rate], ...] (steps)",
        unit="mass_rate", default=REQUIRED, schema=_SCHEDULE),
    Key("interval", "quantity", "random only: time between batches", unit="time",
        default=None, **_P),
    Key("pattern", "choice", "\"random\" in a region, or \"sheet\" layers through a face",
        default="random", choices=FACTORY_PATTERNS),
    Key("face", "table", "sheet only: the face the layers come through", default=None),
    Key("jitter", "quantity", "sheet only: random offset in the layer, a fraction of the "
        "diameter", unit="dimensionless", default=None, minimum=0.0, maximum=MAX_SHEET_JITTER),
), owner=__name__, nested={"face": FACE, "region": REGION, "radius": RADIUS}))
OUTLET = register(Section("outlets[]", "A region that removes the particles entering it, "
                          "[[outlets]]", (
    Key("name", "string", "its name (residence sensors)", default=REQUIRED),
    Key("region", "table", "{ box = ... } or { cylinder = ... }", default=REQUIRED),
), owner=__name__, nested={"region": REGION}))
SENSOR = register(Section("sensors[]", "A sensor, [[sensors]]: mass flow through a plane, "
                          "residence time from a factory to an outlet, contact counts on a body, contact "
                          "statistics per pair kind", (
    Key("kind", "choice", "what it measures", default=REQUIRED, choices=SENSOR_KINDS),
    Key("name", "string", "its name (the series' prefix)", default=REQUIRED),
    Key("plane", "table", "mass_flow: the plane { point, normal }", default=None),
    Key("radius", "quantity", "mass_flow: only within this distance of the plane's point",
        unit="length", default=None, **_P),
    Key("box", "table", "mass_flow: only within this box { min, max }", default=None),
    Key("from", "string", "residence_time: the factory", default=None),
    Key("to", "string", "residence_time: the outlet", default=None),
    Key("body", "string", "contact_count: the body", default=None),
), owner=__name__, nested={"plane": PLANE, "box": BOX}))
SENSOR_KEYS = {"mass_flow": ("kind", "name", "plane", "radius", "box"),
               "residence_time": ("kind", "name", "from", "to"),
               "contact_count": ("kind", "name", "body"),
               "contact_statistics": ("kind", "name")}


class ProcessSections:
    """Read by the loader's parser (scene/loader.py), which mixes this in with the reading
    helpers of common.Reader."""

    def unique_names(self, items, section: str) -> None:
        seen: dict[str, int] = {}
        for i, it in enumerate(items):
            if it.name in seen:
                raise self.err(f"{section}[{i}].name", f"'{it.name}' is already the name of "
                                                       f"{section}[{seen[it.name]}]; names must be unique")
            seen[it.name] = i

    def name(self, t: dict, key: str) -> str:
        if "name" not in t:
            raise self.err(f"{key}.name", "required key is missing")
        n = self.string(t["name"], f"{key}.name")
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", n) or n in (".", ".."):
            raise self.err(f"{key}.name", f"'{n}' must be letters, digits, '_', '-' or '.', "
                                          "and not '.' or '..' (it names HDF5 groups)")
        return n

    # -- process tooling ---------------------------------------------------------------------------
    def parse_rate(self, value: Any, key: str) -> RateSchedule:
        """A mass rate ("6.5 t/h", kg/s) or a schedule [[0, "6.5 t/h"], [150, "13 t/h"]]."""
        if not isinstance(value, list):
            try:
                return RateSchedule(points=((0.0, self.nonnegative(value, "mass_rate", key)),))
            except SceneError as e:
                raise self.err(key, f"{e.reason}; mass_rate is a rate (\"13 t/h\", kg/s) or a "
                                    "schedule [[0.0, \"6.5 t/h\"], [150.0, \"13 t/h\"]]") from None
        if not value:
            raise self.err(key, "an empty schedule; give [[0.0, \"6.5 t/h\"], ...] (start time, rate)")
        points: list[tuple[float, float]] = []
        for j, item in enumerate(value):
            k = f"{key}[{j}]"
            if not isinstance(item, list) or len(item) != 2:
                raise self.err(k, "expected [start time, mass rate], e.g. [150.0, \"13 t/h\"]")
            start = self.nonnegative(item[0], "time", f"{k}[0]")
            rate = self.nonnegative(item[1], "mass_rate", f"{k}[1]")
            if j == 0 and start != 0.0:
                raise self.err(f"{k}[0]", f"the schedule must start at time 0, got {start:g} s")
            if points and not start > points[-1][0]:
                raise self.err(f"{k}[0]", f"start times must increase: {start:g} s follows "
                                          f"{points[-1][0]:g} s")
            points.append((start, rate))
        return RateSchedule(points=tuple(points))

    def parse_factory(self, t: dict, key: str) -> Factory:
        pattern = self.string(t["pattern"], f"{key}.pattern") if "pattern" in t else "random"
        if pattern not in FACTORY_PATTERNS:
            raise self.err(f"{key}.pattern", f"unknown pattern '{pattern}'; "
                                             f"{_suggest(pattern, FACTORY_PATTERNS)}allowed: "
                                             f"{', '.join(FACTORY_PATTERNS)}")
        if pattern == "sheet":
            return self.parse_sheet_factory(t, key)
        self.check_keys(t, key, host_section(FACTORY), required=("name", "material", "region", "mass_rate"))
        for k in SHEET_ONLY_KEYS:
            if k in t:
                raise self.err(f"{key}.{k}", 'only for pattern = "sheet" (this factory places '
                                             "at random in its region)")
        kw: dict[str, Any] = {}
        if ("radius" in t) == ("sizes" in t):
            raise self.err(f"{key}.radius", "give exactly one of radius (a length or { mean, std, "
                                            "min, max }) or sizes = [[radius, mass fraction], ...]")
        if "radius" in t:
            kw["radius"] = self.parse_radius(t["radius"], f"{key}.radius")
        else:
            sizes = t["sizes"]
            if not isinstance(sizes, list) or not sizes:
                raise self.err(f"{key}.sizes", "expected [[radius, mass fraction], ...], e.g. "
                                               "[[\"5 mm\", 0.3], [\"7.5 mm\", 0.7]]")
            rows = []
            for j, item in enumerate(sizes):
                k = f"{key}.sizes[{j}]"
                if not isinstance(item, list) or len(item) != 2:
                    raise self.err(k, "expected [radius, mass fraction]")
                rows.append((self.positive(item[0], "length", f"{k}[0]"),
                             self.positive(item[1], "dimensionless", f"{k}[1]")))
            total = sum(f for _, f in rows)
            if abs(total - 1.0) > 1e-6:
                raise self.err(f"{key}.sizes", f"the mass fractions must sum to 1, they sum to "
                                               f"{total:.6g}")
            kw["sizes"] = tuple(rows)
        if "velocity" in t:
            kw["velocity"] = self.vec3(t["velocity"], "speed", f"{key}.velocity")
        kw["effect_values"] = added_values(FACTORY.path, t, self.source, key)
        if "interval" in t:
            kw["interval"] = self.positive(t["interval"], "time", f"{key}.interval")
        region = self.parse_region(t["region"], f"{key}.region")
        f = Factory(key=key, name=self.name(t, key),
                    material=self.material_name(t["material"], f"{key}.material"),
                    region=region, mass_rate=self.parse_rate(t["mass_rate"], f"{key}.mass_rate"),
                    **kw)
        lo, hi = region_bounds(region)
        if np.any(hi - lo < 2.0 * f.largest_radius):
            raise self.err(f"{key}.region", f"the region is narrower than one particle of radius "
                                            f"{f.largest_radius:g} m")
        return f

    def parse_sheet_face(self, value: Any, key: str):
        """``face = { point, width, depth }`` (a corner and two perpendicular edge vectors) or
        ``{ min, max }`` (an axis-aligned rectangle: the box face with one zero extent).
        Returns (point, width, depth) as numpy vectors, m."""
        t = self.table(value, key, "a table { point, width, depth } or { min, max }")
        self.check_keys(t, key, FACE)
        if set(t) == {"point", "width", "depth"}:
            p = np.array(self.vec3(t["point"], "length", f"{key}.point"))
            w = np.array(self.vec3(t["width"], "length", f"{key}.width"))
            d = np.array(self.vec3(t["depth"], "length", f"{key}.depth"))
            for k, v in (("width", w), ("depth", d)):
                if not np.linalg.norm(v) > 0.0:
                    raise self.err(f"{key}.{k}", "must be a nonzero edge vector (m)")
            cos = abs(float(w @ d)) / (np.linalg.norm(w) * np.linalg.norm(d))
            if cos > 1e-6:
                raise self.err(f"{key}.depth", f"width and depth must be perpendicular edges of "
                                               f"the rectangle; they make "
                                               f"{math.degrees(math.acos(min(cos, 1.0))):.4g} deg")
            return p, w, d
        if set(t) == {"min", "max"}:
            lo = np.array(self.vec3(t["min"], "length", f"{key}.min"))
            hi = np.array(self.vec3(t["max"], "length", f"{key}.max"))
            ext = hi - lo
            if np.any(ext < 0.0):
                raise self.err(f"{key}.max", f"max must not be below min on any axis; got "
                                             f"min = {fmt(lo)}, max = {fmt(hi)}")
            flat = np.nonzero(ext == 0.0)[0]
            if len(flat) != 1:
                raise self.err(f"{key}.max", f"a face is a box face: exactly one axis with "
                                             f"min = max (the face's normal), got extents "
                                             f"{fmt(ext)}")
            a, b = [i for i in range(3) if i != flat[0]]
            w, d = np.zeros(3), np.zeros(3)
            w[a], d[b] = ext[a], ext[b]
            return lo, w, d
        raise self.err(key, "give either point, width and depth (a corner and two perpendicular "
                            "edge vectors) or min and max (an axis-aligned rectangle, one "
                            f"extent zero); got keys {', '.join(sorted(t)) or 'none'}")

    def parse_sheet_factory(self, t: dict, key: str) -> Factory:
        """``pattern = "sheet"``: lattice layers through ``face`` at ``velocity``, one layer
        whenever the stream has carried the previous one the spacing the mass rate implies."""
        self.check_keys(t, key, host_section(FACTORY), required=())
        for k in RANDOM_ONLY_KEYS:
            if k in t:
                reason = {"region": "a sheet inserts through its face; give face = { point, "
                                    "width, depth } (or { min, max }) instead of a region",
                          "sizes": "a sheet inserts one radius (its lattice is sized for it); "
                                   "give radius",
                          "interval": "a sheet inserts a layer whenever the previous one has "
                                      "moved one layer spacing; the interval follows from the "
                                      "mass rate and velocity"}[k]
                raise self.err(f"{key}.{k}", f'not for pattern = "sheet": {reason}')
        self.check_keys(t, key, host_section(FACTORY),
                        required=("name", "material", "face", "velocity", "mass_rate", "radius"))
        radius = self.parse_radius(t["radius"], f"{key}.radius")
        if radius.std != 0.0:
            raise self.err(f"{key}.radius", "a sheet inserts one radius (its lattice is sized for "
                                            "it): give a length, not a distribution")
        point, width, depth = self.parse_sheet_face(t["face"], f"{key}.face")
        velocity = self.vec3(t["velocity"], "speed", f"{key}.velocity")
        jitter = 0.05
        if "jitter" in t:
            jitter = self.nonnegative(t["jitter"], "dimensionless", f"{key}.jitter")
            if jitter > MAX_SHEET_JITTER:
                raise self.err(f"{key}.jitter", f"at most {MAX_SHEET_JITTER} (a fraction of the "
                                                f"diameter: the largest displacement from the "
                                                f"lattice site), got {jitter:g}")
        normal = np.cross(width, depth)
        normal /= np.linalg.norm(normal)
        v = np.asarray(velocity, float)
        u_n = float(v @ normal)
        if abs(u_n) < 1e-9 * max(float(np.linalg.norm(v)), 1e-30) or not np.linalg.norm(v) > 0.0:
            raise self.err(f"{key}.velocity", f"the stream must cross its face: velocity "
                                              f"{fmt(v)} m/s has no component along the face's "
                                              f"normal {fmt(normal)}")
        if u_n < 0.0:
            normal, u_n = -normal, -u_n
        sheet = SheetInlet(point=tuple(float(c) for c in point),
                           width=tuple(float(c) for c in width),
                           depth=tuple(float(c) for c in depth),
                           normal=tuple(float(c) for c in normal),
                           radius=radius.mean, jitter=jitter)
        for k, extent in zip(("width", "depth"), sheet.extents):
            need = sheet.pitch
            if extent < need:
                raise self.err(f"{key}.face", f"the face's {k} ({extent:g} m) is narrower than "
                                              f"one jittered sphere, the lattice pitch 2 radius "
                                              f"x 1.001 + 2 jitter x diameter = {need:g} m")
        # the face and the first layer in front of it must lie inside the domain
        lo, hi = np.asarray(self.domain.min, float), np.asarray(self.domain.max, float)
        front = normal * 2.0 * (radius.mean + sheet.jitter_amplitude)
        for corner in (point, point + width, point + depth, point + width + depth):
            for c in (corner, corner + front):
                if np.any(c < lo - 1e-12) or np.any(c > hi + 1e-12):
                    raise self.err(f"{key}.face", f"the face (and one layer in front of it) must "
                                                  f"lie inside the domain; corner {fmt(c)} is "
                                                  f"outside [{fmt(lo)}, {fmt(hi)}]")
        rate = self.parse_rate(t["mass_rate"], f"{key}.mass_rate")
        material = self.material_name(t["material"], f"{key}.material")
        density = self.materials[material].density
        limit = sheet.max_mass_rate(density, u_n)
        if rate.max_rate > limit * (1.0 + 1e-9):
            w_len, d_len = sheet.extents
            need = rate.max_rate / (density * w_len * d_len * u_n)
            can = limit / (density * w_len * d_len * u_n)
            raise self.err(f"{key}.mass_rate",
                           f"{rate.max_rate:.4g} kg/s through a {w_len:g} x {d_len:g} m face at "
                           f"{u_n:.4g} m/s needs an inflow solid fraction of {need:.3g} "
                           f"(mass_rate / (density x width x depth x normal speed)); the "
                           f"jittered sheet lattice carries at most {can:.3g}, i.e. "
                           f"{limit:.4g} kg/s. Lower mass_rate or jitter, or raise the face's "
                           f"depth or the velocity")
        kw: dict[str, Any] = {}
        kw["effect_values"] = added_values(FACTORY.path, t, self.source, key)
        return Factory(key=key, name=self.name(t, key), material=material, region=None,
                       mass_rate=rate, radius=radius, velocity=velocity, pattern="sheet",
                       sheet=sheet, **kw)

    def parse_outlet(self, t: dict, key: str) -> Outlet:
        self.check_keys(t, key, OUTLET)
        return Outlet(key=key, name=self.name(t, key),
                      region=self.parse_region(t["region"], f"{key}.region"))

    def parse_sensor(self, t: dict, key: str, factories, outlets, bodies) -> Sensor:
        if "kind" not in t:
            raise self.err(f"{key}.kind", f"required: one of {', '.join(SENSOR_KINDS)}")
        kind = self.string(t["kind"], f"{key}.kind")
        if kind not in SENSOR_KINDS:
            raise self.err(f"{key}.kind", f"unknown sensor kind '{kind}'; "
                                          f"{_suggest(kind, SENSOR_KINDS)}allowed: {', '.join(SENSOR_KINDS)}")
        allowed = SENSOR_KEYS[kind]
        required = {"mass_flow": ("plane",), "residence_time": ("from", "to"),
                    "contact_count": ("body",), "contact_statistics": ()}[kind]
        self.check_keys(t, key, allowed, required=("name",) + required)
        kw: dict[str, Any] = {"key": key, "name": self.name(t, key), "kind": kind}
        if kind == "mass_flow":
            kw["point"], kw["normal"] = self.parse_plane(t["plane"], f"{key}.plane")
            if "radius" in t and "box" in t:
                raise self.err(f"{key}.box", "give at most one of radius (a disk about the plane "
                                             "point) or box = { min, max }")
            if "radius" in t:
                kw["radius"] = self.positive(t["radius"], "length", f"{key}.radius")
            if "box" in t:
                b = self.table(t["box"], f"{key}.box")
                self.check_keys(b, f"{key}.box", BOX)
                kw["box_min"] = self.vec3(b["min"], "length", f"{key}.box.min")
                kw["box_max"] = self.vec3(b["max"], "length", f"{key}.box.max")
                if not all(a < c for a, c in zip(kw["box_min"], kw["box_max"])):
                    raise self.err(f"{key}.box.max", "max must exceed min on every axis")
        elif kind == "residence_time":
            src = self.string(t["from"], f"{key}.from")
            names = [f.name for f in factories]
            if src not in names:
                raise self.err(f"{key}.from", f"no factory named '{src}'; factories: "
                                              f"{', '.join(names) or 'none'}")
            dst = self.string(t["to"], f"{key}.to")
            names = [o.name for o in outlets]
            if dst not in names:
                raise self.err(f"{key}.to", f"no outlet named '{dst}'; outlets: "
                                            f"{', '.join(names) or 'none'}")
            kw["source"], kw["target"] = src, dst
        elif kind == "contact_count":
            body = self.string(t["body"], f"{key}.body")
            names = [b.name for b in bodies]
            if body not in names:
                raise self.err(f"{key}.body", f"no body named '{body}'; bodies: "
                                              f"{', '.join(names) or 'none'}")
            kw["body"] = body
        return Sensor(**kw)
