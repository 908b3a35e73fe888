"""Scene TOML -> :class:`~taichi_dem.scene.Scene`, with strict validation.

Every problem is a :class:`~taichi_dem.scene.SceneError` naming the file, the dotted TOML key
(``materials.ash.poisson_ratio``, ``particles[2].radius``) and what was wrong and what is allowed.
Unknown keys are errors (with the closest valid key suggested), so a typo never silently falls
back to a default.
"""
from __future__ import annotations

import csv
import difflib
import io
import math
import re
import tomllib
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ..errors import SceneError
from .model import (Body, CoarseGraining, Domain, Factory, Interaction, Material, Motion, Outlet, Output,
                    MobilitySettings, ParticleFill, PlaneWall, RadiusDistribution, RateSchedule, Region, Scene,
                    Sensor, SheetInlet, SimulationSettings, SpeedSchedule, GasSettings, ThermalSettings,
                    DragSettings)
from .units import MAX_MAGNITUDE, MIN_MAGNITUDE, parse_quantity, parse_vec3

SECTIONS = ("simulation", "domain", "materials", "interactions", "particles", "walls", "bodies",
            "factories", "outlets", "sensors", "thermal", "mobility", "output", "gas")
PLANNED_SECTIONS: tuple[str, ...] = ()
MOBILITY_KEYS = ("enabled", "granular_temperature_threshold", "solid_fraction_threshold",
                 "acceleration_threshold", "cell_size", "mode", "body")
MOBILITY_MODES = ("at_rest", "body_frame")
# "auto" threshold: this fraction of g d_max, (m/s)^2 (effects/mobility.py says why)
MOBILITY_THRESHOLD_SCALE = 1.0e-5
MOBILITY_CELL_DIAMETERS = 3.0       # "auto" cell_size: this many largest diameters
FACTORY_KEYS = ("name", "material", "radius", "sizes", "region", "velocity", "temperature",
                "moisture", "mass_rate", "interval", "pattern", "face", "jitter")
FACTORY_PATTERNS = ("random", "sheet")
SHEET_ONLY_KEYS = ("face", "jitter")          # pattern = "sheet" only
RANDOM_ONLY_KEYS = ("region", "sizes", "interval")   # pattern = "random" only
FACE_KEYS = ("point", "width", "depth", "min", "max")
MAX_SHEET_JITTER = 0.25                       # of the diameter
OUTLET_KEYS = ("name", "region")
SENSOR_KINDS = ("mass_flow", "residence_time", "contact_count")
SENSOR_KEYS = {"mass_flow": ("kind", "name", "plane", "radius", "box"),
               "residence_time": ("kind", "name", "from", "to"),
               "contact_count": ("kind", "name", "body")}
THERMAL_KEYS = ("conduction", "wall_conduction", "radiation", "gas", "contact_radius_correction",
                "radiation_to", "radiation_region", "evaporation_temperature", "latent_heat",
                "water_heat_capacity", "gas_gap", "gap_gas_conductivity", "gas_gap_lens",
                "gas_gap_min_gap", "gas_gap_pairs", "time_scale", "gas_gap_model",
                "gas_gap_porosity")
DRAG_MODELS = ("di_felice", "schiller_naumann")
MECHANICS_GAS_KEYS = ("velocity", "density", "viscosity", "drag")
GAS_KEYS = ("drag", "model", "temperature", "velocity", "correlation", "porosity", "density",
            "viscosity", "conductivity", "heat_capacity", "axis_point", "axis_direction",
            "length", "cells", "flow_area", "radius", "mass_flow", "inlet_temperature", "flow")
FIXED_GAS_ONLY = ("temperature", "velocity")
PLUG_FLOW_KEYS = ("axis_point", "axis_direction", "length", "cells", "flow_area", "radius",
                  "mass_flow", "inlet_temperature", "flow")
PLUG_FLOW_REQUIRED = ("axis_direction", "length", "cells", "mass_flow", "inlet_temperature")

SIMULATION_KEYS = ("end_time", "dt", "rayleigh_fraction", "gravity", "precision", "seed", "skin",
                   "max_particles")
DOMAIN_KEYS = ("min", "max", "periodic")
MATERIAL_KEYS = ("density", "youngs_modulus", "poisson_ratio", "thermal_conductivity",
                 "heat_capacity", "emissivity", "real_youngs_modulus", "coarse_grained")
COARSE_GRAINED_KEYS = ("represented_diameter", "bed_porosity", "surface_coverage", "roughness")
INTERACTION_KEYS = ("pair", "restitution", "friction", "rolling_friction", "model",
                    "rolling_damping")
ROLLING_MODELS = ("constant_torque", "epsd")
PARTICLE_KEYS = ("material", "radius", "count", "region", "velocity", "angular_velocity",
                 "temperature", "moisture", "fixed", "file")
RADIUS_KEYS = ("mean", "std", "min", "max")
REGION_KINDS = ("box", "cylinder")
BOX_KEYS = ("min", "max")
CYLINDER_KEYS = ("axis_point", "axis_direction", "radius", "length")
WALL_KEYS = ("name", "plane", "material", "temperature")
PLANE_KEYS = ("point", "normal")
BODY_KEYS = ("name", "material", "mesh", "motion", "temperature")
MOTION_KEYS = ("rotate", "translate")
ROTATE_KEYS = ("axis_point", "axis_direction", "speed")
TRANSLATE_KEYS = ("velocity",)
# particle slots are indexed with 32-bit integers (Taichi fields)
MAX_PARTICLES = 2 ** 31 - 1
# a domain narrower than this on any axis is a unit mistake (as for meshes, geometry.mesh)
MIN_DOMAIN_SIZE = 1e-6     # m
# a body's mesh may reach this fraction of the domain's size beyond each face of the domain
BODY_DOMAIN_MARGIN = 0.1
OUTPUT_KEYS = ("interval", "rrd", "h5", "checkpoint_interval")
CSV_COLUMNS = ("x", "y", "z", "radius", "vx", "vy", "vz", "wx", "wy", "wz")
AXES = ("x", "y", "z")


def load_scene(path) -> Scene:
    """Read and validate a scene file. A missing file or a TOML syntax error is a SceneError."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise SceneError(str(p), "", "scene file not found") from None
    except IsADirectoryError:
        raise SceneError(str(p), "", "is a directory, expected a scene TOML file") from None
    except OSError as e:
        raise SceneError(str(p), "", f"cannot read the scene file: {e.strerror or e}") from None
    text = _decode_utf8(data, str(p), "")
    return parse_scene(text, source=str(p), base_dir=p.parent)


def _decode_utf8(data: bytes, file: str, key: str) -> str:
    """``data`` as text (a UTF-8 byte-order mark dropped, newlines as ``\n``); bytes that are
    not UTF-8 are a SceneError saying where."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        column = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise SceneError(file, key, f"not a UTF-8 text file ({e.reason}: byte "
                                    f"0x{data[e.start]:02x} at line {line}, column {column}); "
                                    "save it as UTF-8") from None
    return text.replace("\r\n", "\n").replace("\r", "\n")


def parse_scene(text: str, source: str = "<string>", base_dir=None) -> Scene:
    """Validate TOML ``text``; relative particle files resolve against ``base_dir`` (default:
    the directory of ``source`` when it is a path, else the current directory)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        msg = str(e)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        if m:
            what = msg[:m.start()].strip()
            reason = f"TOML syntax error at line {m.group(1)}, column {m.group(2)}: {what}"
        elif "end of document" in msg:
            what = msg.replace("(at end of document)", "").strip()
            n = max(1, len(text.splitlines()))
            reason = f"TOML syntax error at line {n} (end of document): {what}"
        else:
            reason = f"TOML syntax error: {msg}"
        raise SceneError(source, "", reason) from None
    if base_dir is None:
        base_dir = Path(source).parent if not source.startswith("<") else Path.cwd()
    return _Parser(source, Path(base_dir)).scene(doc, text)


# ---------------------------------------------------------------------------------------------

def _type_name(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    return type(value).__name__


def _suggest(word: str, choices) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'? " if close else ""


def _join(key: str, sub: str) -> str:
    return f"{key}.{sub}" if key else sub


class _Parser:
    def __init__(self, source: str, base_dir: Path):
        self.source = source
        self.base_dir = base_dir

    # -- generic helpers ----------------------------------------------------------------------
    def err(self, key: str, reason: str) -> SceneError:
        return SceneError(self.source, key, reason)

    def table(self, value: Any, key: str, what: str = "a table") -> dict:
        if not isinstance(value, dict):
            raise self.err(key, f"expected {what}, got {_type_name(value)}")
        return value

    def check_keys(self, tbl: dict, key: str, allowed, required=()) -> None:
        for k in tbl:
            if k not in allowed:
                raise self.err(_join(key, k),
                               f"unknown key '{k}'; {_suggest(k, allowed)}"
                               f"allowed keys here: {', '.join(allowed)}")
        for k in required:
            if k not in tbl:
                raise self.err(_join(key, k), "required key is missing")

    def q(self, value: Any, dimension: str, key: str) -> float:
        return parse_quantity(value, dimension, file=self.source, key=key)

    def positive(self, value: Any, dimension: str, key: str) -> float:
        x = self.q(value, dimension, key)
        if not x > 0.0:
            raise self.err(key, f"must be > 0, got {x:g}")
        return x

    def nonnegative(self, value: Any, dimension: str, key: str) -> float:
        x = self.q(value, dimension, key)
        if not x >= 0.0:
            raise self.err(key, f"must be >= 0, got {x:g}")
        return x

    def vec3(self, value: Any, dimension: str, key: str) -> tuple[float, float, float]:
        return parse_vec3(value, dimension, file=self.source, key=key)

    def direction(self, value: Any, key: str) -> tuple[float, float, float]:
        v = np.array(self.vec3(value, "dimensionless", key), dtype=float)
        n = float(np.linalg.norm(v))
        if not n > 0.0:
            raise self.err(key, "must be a nonzero vector (it is normalised on load)")
        return tuple(float(c) for c in v / n)

    def boolean(self, value: Any, key: str) -> bool:
        if not isinstance(value, bool):
            raise self.err(key, f"expected true or false, got {_type_name(value)}")
        return value

    def integer(self, value: Any, key: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.err(key, f"expected an integer, got {_type_name(value)}")
        return value

    def string(self, value: Any, key: str) -> str:
        if not isinstance(value, str):
            raise self.err(key, f"expected a string, got {_type_name(value)}")
        return value

    def material_name(self, value: Any, key: str) -> str:
        name = self.string(value, key)
        if name not in self.materials:
            known = ", ".join(sorted(self.materials)) or "none (add a [materials.NAME] table)"
            raise self.err(key, f"unknown material '{name}'; {_suggest(name, self.materials)}"
                                f"defined materials: {known}")
        return name

    def array_of_tables(self, doc: dict, name: str) -> list[dict]:
        value = doc.get(name, [])
        if not isinstance(value, list):
            raise self.err(name, f"expected an array of tables ([[{name}]]), got "
                                 f"{_type_name(value)}")
        for i, item in enumerate(value):
            self.table(item, f"{name}[{i}]", f"a table ([[{name}]])")
        return value

    # -- the scene -----------------------------------------------------------------------------
    def scene(self, doc: dict, text: str) -> Scene:
        for k in doc:
            if k in PLANNED_SECTIONS:
                raise self.err(k, "not supported yet by this version of taichi_dem (planned)")
        for k in doc:
            if k not in SECTIONS:
                raise self.err(k, f"unknown section '{k}'; {_suggest(k, SECTIONS + PLANNED_SECTIONS)}"
                                  f"allowed sections: {', '.join(SECTIONS)}")
        simulation = self.simulation(doc.get("simulation", {}))
        if "domain" not in doc:
            raise self.err("domain", "required section [domain] is missing (min, max, periodic)")
        self.domain = self.parse_domain(doc["domain"])
        self.materials = self.parse_materials(doc.get("materials", {}))
        interactions, _ = self.parse_interactions(self.array_of_tables(doc, "interactions"))
        walls = self.parse_walls(self.array_of_tables(doc, "walls"))
        bodies = self.parse_bodies(self.array_of_tables(doc, "bodies"), walls)
        fills = tuple(self.parse_fill(f, f"particles[{i}]")
                      for i, f in enumerate(self.array_of_tables(doc, "particles")))
        factories = tuple(self.parse_factory(f, f"factories[{i}]")
                          for i, f in enumerate(self.array_of_tables(doc, "factories")))
        self.unique_names(factories, "factories")
        outlets = tuple(self.parse_outlet(o, f"outlets[{i}]")
                        for i, o in enumerate(self.array_of_tables(doc, "outlets")))
        self.unique_names(outlets, "outlets")
        sensors = tuple(self.parse_sensor(x, f"sensors[{i}]", factories, outlets, bodies)
                        for i, x in enumerate(self.array_of_tables(doc, "sensors")))
        self.unique_names(sensors, "sensors")
        output = self.parse_output(doc.get("output", {}))
        self.check_particle_total(simulation, fills, factories)
        sources = tuple(fills) + factories
        self.check_coverage(interactions, sources, walls, bodies)
        thermal = self.parse_thermal(doc["thermal"], sources, walls, bodies) if "thermal" in doc else None
        self.check_coarse_grained(thermal, sources, walls, bodies)
        if thermal is None:
            for f in sources:
                if f.moisture is not None:
                    raise self.err(f"{f.key}.moisture", "drying needs heat transfer: add a "
                                                        "[thermal] section (and a gas to dry in)")
        drag = self.parse_drag(doc, thermal)
        mobility = (self.parse_mobility(doc["mobility"], simulation, sources, bodies)
                    if "mobility" in doc else None)
        return Scene(source=self.source, text=text, simulation=simulation, domain=self.domain,
                     materials=self.materials, interactions=interactions, fills=fills,
                     walls=walls, bodies=bodies, output=output, thermal=thermal,
                     factories=factories, outlets=outlets, sensors=sensors, drag=drag,
                     mobility=mobility)

    def parse_drag(self, doc: dict, thermal) -> "DragSettings | None":
        """Drag from the mechanics-only [gas] section (velocity, density, viscosity, drag) or
        from [thermal.gas] with drag = "di_felice" | "schiller_naumann"; not both."""
        heat_gas = thermal.gas if thermal is not None else None
        if "gas" in doc:
            if heat_gas is not None:
                raise self.err("gas", "the scene has a [thermal.gas] already: give its drag "
                                      "there (drag = \"di_felice\"), not a second gas")
            g = self.table(doc["gas"], "gas")
            self.check_keys(g, "gas", MECHANICS_GAS_KEYS)
            model = self.string(g.get("drag", "di_felice"), "gas.drag")
            if model not in DRAG_MODELS:
                raise self.err("gas.drag", f"must be \"di_felice\" or \"schiller_naumann\", "
                                           f"got \"{model}\"")
            if "velocity" not in g:
                raise self.err("gas.velocity", "required: the gas's superficial velocity, m/s")
            return DragSettings(
                model=model, velocity=self.vec3(g["velocity"], "speed", "gas.velocity"),
                density=(self.positive(g["density"], "density", "gas.density")
                         if "density" in g else GasSettings.density),
                viscosity=(self.positive(g["viscosity"], "viscosity", "gas.viscosity")
                           if "viscosity" in g else GasSettings.viscosity))
        if heat_gas is not None and heat_gas.drag != "none":
            return DragSettings(model=heat_gas.drag, velocity=heat_gas.velocity,
                                density=heat_gas.density, viscosity=heat_gas.viscosity)
        return None

    def parse_mobility(self, value: Any, simulation, sources, bodies) -> Optional[MobilitySettings]:
        """[mobility] (effects/mobility.py). ``enabled = false`` (or no section) means absent.
        "auto" thresholds scale with the scene: granular temperature MOBILITY_THRESHOLD_SCALE
        x g d_max, cell size MOBILITY_CELL_DIAMETERS x d_max (d_max the largest diameter of
        the fills and factories)."""
        key = "mobility"
        t = self.table(value, key)
        self.check_keys(t, key, MOBILITY_KEYS)
        if "enabled" in t and not self.boolean(t["enabled"], f"{key}.enabled"):
            return None
        radii = [f.largest_radius for f in sources]
        d_max = 2.0 * max(radii) if radii else 0.0
        kw: dict[str, Any] = {}
        mode = t.get("mode", "at_rest")
        if mode not in MOBILITY_MODES:
            raise self.err(f"{key}.mode", f"unknown mode {_type_name(mode)}; "
                                          f"{_suggest(str(mode), MOBILITY_MODES)}allowed: "
                                          + ", ".join(MOBILITY_MODES))
        kw["mode"] = mode
        if mode == "body_frame":
            if "body" not in t:
                raise self.err(f"{key}.body", "required for mode \"body_frame\": the name of the "
                                              "body whose rigid motion the bed follows (a drum's shell)")
            name = self.string(t["body"], f"{key}.body")
            names = [b.name for b in bodies]
            if name not in names:
                raise self.err(f"{key}.body", f"unknown body '{name}'; {_suggest(name, names)}"
                                              f"bodies: {', '.join(names) or 'none'}")
            kw["body"] = name
        elif "body" in t:
            raise self.err(f"{key}.body", "only used with mode = \"body_frame\"")
        k = f"{key}.granular_temperature_threshold"
        value_t = t.get("granular_temperature_threshold", "auto")
        if isinstance(value_t, str) and value_t.strip().lower() == "auto":
            g = float(np.linalg.norm(simulation.gravity))
            if g == 0.0 or d_max == 0.0:
                raise self.err(k, "\"auto\" scales with g d (gravity x the largest diameter), "
                                  "but this scene has " + ("no gravity" if g == 0.0 else "no particles")
                                  + ": give a value in (m/s)^2, e.g. 1e-3 x (a reference speed)^2")
            kw["granular_temperature_threshold"] = MOBILITY_THRESHOLD_SCALE * g * d_max
            kw["threshold_is_auto"] = True
        else:
            try:
                kw["granular_temperature_threshold"] = self.positive(value_t, "specific_energy", k)
            except SceneError as e:
                raise self.err(e.key, f"{e.reason}; a granular temperature in (m/s)^2 "
                                      "(e.g. 1e-4 or \"1e-4 m^2/s^2\"), or \"auto\"") from None
        if "solid_fraction_threshold" in t:
            k = f"{key}.solid_fraction_threshold"
            x = self.q(t["solid_fraction_threshold"], "dimensionless", k)
            if not 0.0 <= x < 0.74:
                raise self.err(k, f"must be in [0, 0.74) (0.74: the densest packing of equal "
                                  f"spheres; 0.4 typical), got {x:g}")
            kw["solid_fraction_threshold"] = x
        if "acceleration_threshold" in t:
            # opt-in: an rms acceleration (m/s^2) above which a cell is not in equilibrium
            kw["acceleration_threshold"] = self.positive(t["acceleration_threshold"], "acceleration",
                                                         f"{key}.acceleration_threshold")
        value_c = t.get("cell_size", "auto")
        k = f"{key}.cell_size"
        if isinstance(value_c, str) and value_c.strip().lower() == "auto":
            kw["cell_size"] = MOBILITY_CELL_DIAMETERS * d_max
        else:
            kw["cell_size"] = self.positive(value_c, "length", k)
            if d_max > 0 and kw["cell_size"] < 2.0 * d_max:
                raise self.err(k, f"{kw['cell_size']:.3g} m is less than two largest diameters "
                                  f"({2 * d_max:.3g} m): too few particles per cell for a granular "
                                  "temperature or a solid fraction")
        return MobilitySettings(**kw)

    def check_particle_total(self, simulation: SimulationSettings, fills, factories) -> None:
        """The fills, and the factories' schedules until end_time (unless max_particles caps
        them), must stay within what the engine can index."""
        total = 0
        for f in fills:
            total += f.expected_count
            if total > MAX_PARTICLES:
                raise self.err(f"{f.key}.count" if f.file is None else f"{f.key}.file",
                               f"the fills hold {total:,} particles, more than the "
                               f"{MAX_PARTICLES:,} the engine can index (32-bit fields)")
        if simulation.max_particles is not None:
            return
        expected = float(total)
        for f in factories:
            mass = f.mass_rate.mass_until(simulation.end_time)
            expected += mass / (self.materials[f.material].density * f.mean_particle_volume())
            if not 1.1 * expected + 64 <= MAX_PARTICLES:
                raise self.err(f"{f.key}.mass_rate",
                               f"the schedules insert about {expected:.3g} particles by "
                               f"end_time = {simulation.end_time:g} s, more than the "
                               f"{MAX_PARTICLES:,} the engine can index; lower the rate, "
                               "shorten end_time or cap them with [simulation] max_particles")

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
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", n):
            raise self.err(f"{key}.name", f"'{n}' must be letters, digits, '_', '-' or '.' "
                                          "(it names HDF5 groups)")
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
        self.check_keys(t, key, FACTORY_KEYS, required=("name", "material", "region", "mass_rate"))
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
        if "temperature" in t:
            kw["temperature"] = self.positive(t["temperature"], "temperature", f"{key}.temperature")
        if "moisture" in t:
            kw["moisture"] = self.nonnegative(t["moisture"], "dimensionless", f"{key}.moisture")
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
        self.check_keys(t, key, FACE_KEYS)
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
                                             f"min = {_fmt(lo)}, max = {_fmt(hi)}")
            flat = np.nonzero(ext == 0.0)[0]
            if len(flat) != 1:
                raise self.err(f"{key}.max", f"a face is a box face: exactly one axis with "
                                             f"min = max (the face's normal), got extents "
                                             f"{_fmt(ext)}")
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
        self.check_keys(t, key, FACTORY_KEYS)
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
        self.check_keys(t, key, FACTORY_KEYS,
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
                                              f"{_fmt(v)} m/s has no component along the face's "
                                              f"normal {_fmt(normal)}")
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
                                                  f"lie inside the domain; corner {_fmt(c)} is "
                                                  f"outside [{_fmt(lo)}, {_fmt(hi)}]")
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
        if "temperature" in t:
            kw["temperature"] = self.positive(t["temperature"], "temperature", f"{key}.temperature")
        if "moisture" in t:
            kw["moisture"] = self.nonnegative(t["moisture"], "dimensionless", f"{key}.moisture")
        return Factory(key=key, name=self.name(t, key), material=material, region=None,
                       mass_rate=rate, radius=radius, velocity=velocity, pattern="sheet",
                       sheet=sheet, **kw)

    def parse_outlet(self, t: dict, key: str) -> Outlet:
        self.check_keys(t, key, OUTLET_KEYS, required=OUTLET_KEYS)
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
                    "contact_count": ("body",)}[kind]
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
                self.check_keys(b, f"{key}.box", BOX_KEYS, required=BOX_KEYS)
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
        else:
            body = self.string(t["body"], f"{key}.body")
            names = [b.name for b in bodies]
            if body not in names:
                raise self.err(f"{key}.body", f"no body named '{body}'; bodies: "
                                              f"{', '.join(names) or 'none'}")
            kw["body"] = body
        return Sensor(**kw)

    def simulation(self, value: Any) -> SimulationSettings:
        key = "simulation"
        t = self.table(value, key)
        self.check_keys(t, key, SIMULATION_KEYS)
        kw: dict[str, Any] = {}
        if "end_time" in t:
            kw["end_time"] = self.positive(t["end_time"], "time", f"{key}.end_time")
        if "dt" in t:
            dt = t["dt"]
            if isinstance(dt, str) and dt.strip().lower() == "auto":
                kw["dt"] = None
            else:
                try:
                    kw["dt"] = self.positive(dt, "time", f"{key}.dt")
                except SceneError as e:
                    raise self.err(e.key, f"{e.reason}; dt is \"auto\" or a positive time") from None
        if "rayleigh_fraction" in t:
            k = f"{key}.rayleigh_fraction"
            x = self.q(t["rayleigh_fraction"], "dimensionless", k)
            if not 0.0 < x <= 1.0:
                raise self.err(k, f"must be in (0, 1], got {x:g} (typically 0.1 to 0.3)")
            kw["rayleigh_fraction"] = x
        if "gravity" in t:
            kw["gravity"] = self.vec3(t["gravity"], "acceleration", f"{key}.gravity")
        if "precision" in t:
            p = t["precision"]
            if p not in ("f32", "f64"):
                raise self.err(f"{key}.precision", f"must be \"f32\" or \"f64\", got "
                                                   f"{_type_name(p)}")
            kw["precision"] = p
        if "seed" in t:
            kw["seed"] = self.integer(t["seed"], f"{key}.seed")
            if kw["seed"] < 0:
                raise self.err(f"{key}.seed", f"must be >= 0 (it seeds numpy's generator), got "
                                              f"{kw['seed']}")
        if "skin" in t:
            kw["skin"] = self.positive(t["skin"], "length", f"{key}.skin")
        if "max_particles" in t:
            kw["max_particles"] = self.integer(t["max_particles"], f"{key}.max_particles")
            if kw["max_particles"] < 1:
                raise self.err(f"{key}.max_particles", f"must be >= 1, got {kw['max_particles']}")
            if kw["max_particles"] > MAX_PARTICLES:
                raise self.err(f"{key}.max_particles", f"{kw['max_particles']:,} is more than the "
                                                       f"{MAX_PARTICLES:,} particles the engine "
                                                       "can index (32-bit fields)")
        return SimulationSettings(**kw)

    def parse_domain(self, value: Any) -> Domain:
        key = "domain"
        t = self.table(value, key)
        self.check_keys(t, key, DOMAIN_KEYS, required=("min", "max"))
        lo = self.vec3(t["min"], "length", f"{key}.min")
        hi = self.vec3(t["max"], "length", f"{key}.max")
        for i, ax in enumerate(AXES):
            if not lo[i] < hi[i]:
                raise self.err(f"{key}.max", f"max must exceed min on every axis; on {ax}: "
                                             f"min = {lo[i]:g}, max = {hi[i]:g}")
            if hi[i] - lo[i] < MIN_DOMAIN_SIZE:
                raise self.err(f"{key}.max", f"the domain is {hi[i] - lo[i]:.3g} m across on "
                                             f"{ax}: absurd for a DEM scene (wrong units? "
                                             "lengths are in metres: write 0.2 or \"200 mm\")")
        periodic = t.get("periodic", [])
        if not isinstance(periodic, list):
            raise self.err(f"{key}.periodic", f"expected an array of axis names (\"x\", \"y\", "
                                              f"\"z\"), got {_type_name(periodic)}")
        seen: list[str] = []
        for i, a in enumerate(periodic):
            if a not in AXES:
                raise self.err(f"{key}.periodic[{i}]", f"must be \"x\", \"y\" or \"z\", got "
                                                       f"{_type_name(a)}")
            if a in seen:
                raise self.err(f"{key}.periodic[{i}]", f"axis \"{a}\" is listed twice")
            seen.append(a)
        return Domain(min=lo, max=hi, periodic=tuple(seen))

    def parse_materials(self, value: Any) -> dict[str, Material]:
        t = self.table(value, "materials", "a table of [materials.NAME] tables")
        out: dict[str, Material] = {}
        for name, m in t.items():
            key = f"materials.{name}"
            m = self.table(m, key, f"a table ([materials.{name}])")
            self.check_keys(m, key, MATERIAL_KEYS,
                            required=("density", "youngs_modulus", "poisson_ratio"))
            density = self.positive(m["density"], "density", f"{key}.density")
            e = self.positive(m["youngs_modulus"], "pressure", f"{key}.youngs_modulus")
            nu = self.q(m["poisson_ratio"], "dimensionless", f"{key}.poisson_ratio")
            if not -1.0 < nu < 0.5:
                raise self.err(f"{key}.poisson_ratio",
                               f"must lie strictly between -1 and 0.5, got {nu:g}")
            kw: dict[str, Any] = {}
            if "thermal_conductivity" in m:
                kw["thermal_conductivity"] = self.positive(
                    m["thermal_conductivity"], "thermal_conductivity", f"{key}.thermal_conductivity")
            if "heat_capacity" in m:
                kw["heat_capacity"] = self.positive(m["heat_capacity"], "specific_heat",
                                                    f"{key}.heat_capacity")
            if "emissivity" in m:
                k = f"{key}.emissivity"
                x = self.q(m["emissivity"], "dimensionless", k)
                if not 0.0 <= x <= 1.0:
                    raise self.err(k, f"must be in [0, 1], got {x:g}")
                kw["emissivity"] = x
            if "real_youngs_modulus" in m:
                k = f"{key}.real_youngs_modulus"
                x = self.positive(m["real_youngs_modulus"], "pressure", k)
                if x < e:
                    raise self.err(k, f"the real (unsoftened) modulus {x:g} Pa must be >= "
                                      f"youngs_modulus = {e:g} Pa")
                kw["real_youngs_modulus"] = x
            if "coarse_grained" in m:
                kw["coarse_grained"] = self.parse_coarse_grained(m["coarse_grained"],
                                                                 f"{key}.coarse_grained")
            out[name] = Material(name=name, density=density, youngs_modulus=e,
                                 poisson_ratio=nu, **kw)
        return out

    def check_coarse_grained(self, thermal, sources, walls, bodies) -> None:
        """A coarse_grained material must be a particle material, in a scene with [thermal]
        whose wall conduction reaches a wall or body with a temperature: the law acts there
        and nowhere else, so anything less would be a key that silently does nothing."""
        used = {f.material for f in sources}
        for w in list(walls) + list(bodies):
            if self.materials[w.material].coarse_grained is not None and w.material not in used:
                raise self.err(f"materials.{w.material}.coarse_grained",
                               f"'{w.name}' is made of it: coarse graining describes particles "
                               f"that stand for finer ones, not a wall")
        for name in sorted(used):
            if self.materials[name].coarse_grained is None:
                continue
            key = f"materials.{name}.coarse_grained"
            if thermal is None:
                raise self.err(key, "is a heat law: add a [thermal] section")
            hot = [w for w in list(walls) + list(bodies) if w.temperature is not None]
            if not (thermal.wall_conduction and hot):
                raise self.err(key, "acts between particles and walls or bodies with a "
                                    "temperature, and there is none with [thermal] "
                                    "wall_conduction on: give a wall or body a temperature, "
                                    "or drop coarse_grained")

    def parse_coarse_grained(self, value: Any, key: str) -> CoarseGraining:
        """[materials.NAME] coarse_grained = { represented_diameter, bed_porosity,
        surface_coverage, roughness }."""
        t = self.table(value, key, "an inline table { represented_diameter = ... }")
        self.check_keys(t, key, COARSE_GRAINED_KEYS, required=("represented_diameter",))
        kw: dict[str, Any] = {"represented_diameter": self.positive(
            t["represented_diameter"], "length", f"{key}.represented_diameter")}
        if "bed_porosity" in t:
            x = self.positive(t["bed_porosity"], "dimensionless", f"{key}.bed_porosity")
            if not 0.2 <= x <= 0.9:
                raise self.err(f"{key}.bed_porosity", f"the porosity of the represented bed: "
                                                      f"0.2 to 0.9, got {x:g}")
            kw["bed_porosity"] = x
        if "surface_coverage" in t:
            x = self.positive(t["surface_coverage"], "dimensionless", f"{key}.surface_coverage")
            if x > 1.0:
                raise self.err(f"{key}.surface_coverage", f"the fraction of the wall the first "
                                                          f"layer covers: at most 1, got {x:g}")
            kw["surface_coverage"] = x
        if "roughness" in t:
            kw["roughness"] = self.nonnegative(t["roughness"], "length", f"{key}.roughness")
        return CoarseGraining(**kw)

    def parse_interactions(self, items: list[dict]):
        out: dict[frozenset, Interaction] = {}
        where: dict[frozenset, str] = {}
        for i, t in enumerate(items):
            key = f"interactions[{i}]"
            self.check_keys(t, key, INTERACTION_KEYS, required=("pair", "restitution", "friction"))
            pair = t["pair"]
            if not isinstance(pair, list) or len(pair) != 2:
                raise self.err(f"{key}.pair", f"expected an array of two material names, got "
                                              f"{_type_name(pair)}")
            a = self.material_name(pair[0], f"{key}.pair[0]")
            b = self.material_name(pair[1], f"{key}.pair[1]")
            fs = frozenset((a, b))
            if fs in out:
                raise self.err(f"{key}.pair", f"duplicate: the pair ('{a}', '{b}') is already "
                                              f"given by {where[fs]}")
            e = self.q(t["restitution"], "dimensionless", f"{key}.restitution")
            if not 0.0 < e <= 1.0:
                raise self.err(f"{key}.restitution", f"must be in (0, 1], got {e:g}")
            mu = self.nonnegative(t["friction"], "dimensionless", f"{key}.friction")
            mur = 0.0
            if "rolling_friction" in t:
                mur = self.nonnegative(t["rolling_friction"], "dimensionless",
                                       f"{key}.rolling_friction")
            model = t.get("model", "constant_torque")
            if model not in ROLLING_MODELS:
                raise self.err(f"{key}.model", f"must be \"constant_torque\" or \"epsd\", got "
                                               f"{_type_name(model)}")
            eta = 0.3
            if "rolling_damping" in t:
                eta = self.q(t["rolling_damping"], "dimensionless", f"{key}.rolling_damping")
                if not 0.0 <= eta <= 1.0:
                    raise self.err(f"{key}.rolling_damping",
                                   f"must be in [0, 1] (a fraction of critical damping), got {eta:g}")
            out[fs] = Interaction(pair=(a, b), restitution=e, friction=mu, rolling_friction=mur,
                                  rolling_model=model, rolling_damping=eta)
            where[fs] = key
        return out, where

    def parse_plane(self, value: Any, key: str):
        t = self.table(value, key, "a table { point = [x, y, z], normal = [nx, ny, nz] }")
        self.check_keys(t, key, PLANE_KEYS, required=PLANE_KEYS)
        return self.vec3(t["point"], "length", f"{key}.point"), self.direction(t["normal"],
                                                                                f"{key}.normal")

    def parse_walls(self, items: list[dict]) -> tuple[PlaneWall, ...]:
        out: list[PlaneWall] = []
        names: dict[str, str] = {}
        for i, t in enumerate(items):
            key = f"walls[{i}]"
            self.check_keys(t, key, WALL_KEYS, required=("name", "plane", "material"))
            name = self.string(t["name"], f"{key}.name")
            if not name.strip():
                raise self.err(f"{key}.name", "must be a non-empty name")
            if name in names:
                raise self.err(f"{key}.name", f"duplicate wall name '{name}' (also {names[name]})")
            names[name] = key
            point, normal = self.parse_plane(t["plane"], f"{key}.plane")
            material = self.material_name(t["material"], f"{key}.material")
            temp = None
            if "temperature" in t:
                temp = self.positive(t["temperature"], "temperature", f"{key}.temperature")
            out.append(PlaneWall(name=name, point=point, normal=normal, material=material,
                                 temperature=temp))
        return tuple(out)

    # -- [[bodies]] ------------------------------------------------------------------------------
    def parse_bodies(self, items: list[dict], walls) -> tuple[Body, ...]:
        out: list[Body] = []
        names: dict[str, str] = {w.name: f"walls[{i}]" for i, w in enumerate(walls)}
        for i, t in enumerate(items):
            key = f"bodies[{i}]"
            self.check_keys(t, key, BODY_KEYS, required=("name", "material", "mesh"))
            name = self.string(t["name"], f"{key}.name")
            if not name.strip():
                raise self.err(f"{key}.name", "must be a non-empty name")
            if name in names:
                raise self.err(f"{key}.name", f"duplicate name '{name}' (also {names[name]}); "
                                              "bodies and walls need distinct names")
            names[name] = key
            material = self.material_name(t["material"], f"{key}.material")
            mesh = self.parse_mesh(t["mesh"], f"{key}.mesh")
            motion = Motion()
            if "motion" in t:
                motion = self.parse_motion(t["motion"], f"{key}.motion", t["mesh"], f"{key}.mesh")
            temp = None
            if "temperature" in t:
                temp = self.positive(t["temperature"], "temperature", f"{key}.temperature")
            vertices = np.array(mesh.vertices, dtype=np.float64).reshape(-1, 3)
            faces = np.array(mesh.faces, dtype=np.int64).reshape(-1, 3)
            self.check_inside_domain(vertices, f"{key}.mesh")
            out.append(Body(key=key, name=name, material=material, vertices=vertices,
                            faces=faces, motion=motion, temperature=temp))
        return tuple(out)

    def parse_mesh(self, spec: Any, key: str):
        """Build (and validate) a body's ``mesh`` through :mod:`geometry`."""
        import geometry
        try:
            mesh = geometry.build_mesh(spec, key=key, base_dir=self.base_dir)
            return mesh.validate(key)
        except geometry.GeometryError as e:
            raise self.err(e.key or key, e.reason) from None

    def check_inside_domain(self, vertices: np.ndarray, key: str) -> None:
        dlo, dhi = np.array(self.domain.min, float), np.array(self.domain.max, float)
        margin = BODY_DOMAIN_MARGIN * (dhi - dlo)
        elo, ehi = dlo - margin, dhi + margin
        vlo, vhi = vertices.min(axis=0), vertices.max(axis=0)
        for i, ax in enumerate(AXES):
            if ax in self.domain.periodic:
                continue
            if vlo[i] < elo[i] or vhi[i] > ehi[i]:
                raise self.err(key, f"the body's mesh lies outside the domain: on {ax} it spans "
                                    f"{vlo[i]:g} to {vhi[i]:g} m, the domain {dlo[i]:g} to "
                                    f"{dhi[i]:g} m (a mesh may reach "
                                    f"{100 * BODY_DOMAIN_MARGIN:g} % of the domain's size beyond "
                                    f"it: {elo[i]:g} to {ehi[i]:g} m); enlarge [domain] or move "
                                    "the mesh (origin)")

    def parse_motion(self, value: Any, key: str, mesh_spec: Any, mesh_key: str) -> Motion:
        t = self.table(value, key, "a table { rotate = { axis_point, axis_direction, speed } "
                                   "} and/or { translate = { velocity } }")
        self.check_keys(t, key, MOTION_KEYS)
        kw: dict[str, Any] = {}
        if "translate" in t:
            k = f"{key}.translate"
            tr = self.table(t["translate"], k, "a table { velocity = [vx, vy, vz] }")
            self.check_keys(tr, k, TRANSLATE_KEYS, required=TRANSLATE_KEYS)
            kw["velocity"] = self.vec3(tr["velocity"], "speed", f"{k}.velocity")
        if "rotate" in t:
            k = f"{key}.rotate"
            rot = self.table(t["rotate"], k, "a table { axis_point, axis_direction, speed }")
            self.check_keys(rot, k, ROTATE_KEYS, required=("speed",))
            kw["speed"] = self.parse_speed(rot["speed"], f"{k}.speed")
            point = direction = None
            if "axis_point" in rot:
                point = self.vec3(rot["axis_point"], "length", f"{k}.axis_point")
            if "axis_direction" in rot:
                direction = self.direction(rot["axis_direction"], f"{k}.axis_direction")
            if point is None or direction is None:
                missing = "axis_point" if point is None else "axis_direction"
                axis = self.builder_axis(mesh_spec, mesh_key)
                if axis is None:
                    raise self.err(f"{k}.{missing}",
                                   "required key is missing: the mesh is not made by a builder, "
                                   "so it has no axis of its own to rotate about")
                if point is None:
                    point = tuple(float(c) for c in axis[0])
                if direction is None:
                    d = np.asarray(axis[1], float)
                    direction = tuple(float(c) for c in d / np.linalg.norm(d))
            kw["axis_point"] = point
            kw["axis_direction"] = direction
        return Motion(**kw)

    def builder_axis(self, spec: Any, key: str):
        """The placed +x axis ``(point, direction)`` of the first mesh of ``spec`` when a
        builder makes it, else None (an imported file has no axis of its own)."""
        import geometry
        body_axis = getattr(geometry, "body_axis", None)
        first = spec[0] if isinstance(spec, list) and spec else spec
        if body_axis is None or not isinstance(first, dict) or "builder" not in first \
                or first.get("builder") == "file":
            return None
        try:
            return body_axis(first, key=f"{key}[0]" if isinstance(spec, list) else key)
        except geometry.GeometryError as e:
            raise self.err(e.key or key, e.reason) from None

    def parse_speed(self, value: Any, key: str) -> SpeedSchedule:
        """An angular speed ("10 rpm", rad/s) or a schedule [[t0 = 0, w0], [t1, w1], ...]."""
        if not isinstance(value, list):
            try:
                w = self.q(value, "angular_speed", key)
            except SceneError as e:
                raise self.err(key, f"{e.reason}; speed is an angular speed (\"10 rpm\", rad/s) "
                                    "or a schedule [[0.0, \"10 rpm\"], [30.0, \"20 rpm\"]]") from None
            return SpeedSchedule(points=((0.0, w),))
        if not value:
            raise self.err(key, "an empty schedule; give [[0.0, \"10 rpm\"], ...] (start time, "
                                "angular speed)")
        points: list[tuple[float, float]] = []
        for j, item in enumerate(value):
            k = f"{key}[{j}]"
            if not isinstance(item, list) or len(item) != 2:
                raise self.err(k, f"expected [start time, angular speed], e.g. [30.0, \"20 rpm\"], "
                                  f"got {_type_name(item)}"
                                  + (f" of length {len(item)}" if isinstance(item, list) else ""))
            start = self.nonnegative(item[0], "time", f"{k}[0]")
            w = self.q(item[1], "angular_speed", f"{k}[1]")
            if j == 0 and start != 0.0:
                raise self.err(f"{k}[0]", f"the schedule must start at time 0, got {start:g} s "
                                          "(the speed before the first entry would be undefined)")
            if points and not start > points[-1][0]:
                raise self.err(f"{k}[0]", f"start times must increase: {start:g} s follows "
                                          f"{points[-1][0]:g} s")
            points.append((start, w))
        return SpeedSchedule(points=tuple(points))

    def parse_radius(self, value: Any, key: str) -> RadiusDistribution:
        if isinstance(value, dict):
            self.check_keys(value, key, RADIUS_KEYS, required=("mean", "std"))
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
        self.check_keys(t, key, REGION_KINDS)
        if len(t) != 1:
            raise self.err(key, "give exactly one of box = { min, max } or cylinder = "
                                "{ axis_point, axis_direction, radius, length }")
        kind = next(iter(t))
        k = f"{key}.{kind}"
        sub = self.table(t[kind], k)
        if kind == "box":
            self.check_keys(sub, k, BOX_KEYS, required=BOX_KEYS)
            lo = self.vec3(sub["min"], "length", f"{k}.min")
            hi = self.vec3(sub["max"], "length", f"{k}.max")
            for i, ax in enumerate(AXES):
                if not lo[i] < hi[i]:
                    raise self.err(f"{k}.max", f"max must exceed min on every axis; on {ax}: "
                                               f"min = {lo[i]:g}, max = {hi[i]:g}")
            region = Region(kind="box", box_min=lo, box_max=hi)
            amin, amax = np.array(lo), np.array(hi)
        else:
            self.check_keys(sub, k, CYLINDER_KEYS, required=CYLINDER_KEYS)
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
            raise self.err(k, f"the region (bounds {_fmt(amin)} to {_fmt(amax)}) must lie inside "
                              f"the domain ({_fmt(dlo)} to {_fmt(dhi)})")
        return region

    def parse_fill(self, t: dict, key: str) -> ParticleFill:
        self.check_keys(t, key, PARTICLE_KEYS, required=("material",))
        material = self.material_name(t["material"], f"{key}.material")
        kw: dict[str, Any] = {}
        if "velocity" in t:
            kw["velocity"] = self.vec3(t["velocity"], "speed", f"{key}.velocity")
        if "angular_velocity" in t:
            kw["angular_velocity"] = self.vec3(t["angular_velocity"], "angular_speed",
                                               f"{key}.angular_velocity")
        if "temperature" in t:
            kw["temperature"] = self.positive(t["temperature"], "temperature",
                                              f"{key}.temperature")
        if "moisture" in t:
            kw["moisture"] = self.nonnegative(t["moisture"], "dimensionless", f"{key}.moisture")
        if "fixed" in t:
            kw["fixed"] = self.boolean(t["fixed"], f"{key}.fixed")
        if "file" in t:
            for k in ("count", "region", "radius"):
                if k in t:
                    raise self.err(f"{key}.{k}", f"not allowed together with file (the file "
                                                 f"gives positions and radii); use either file "
                                                 "or count + region + radius")
            fname = self.string(t["file"], f"{key}.file")
            arrays = self.read_csv(fname, f"{key}.file")
            return ParticleFill(key=key, material=material, file=fname, **arrays, **kw)
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

    def read_csv(self, fname: str, key: str) -> dict[str, Optional[np.ndarray]]:
        path = Path(fname)
        if not path.is_absolute():
            path = self.base_dir / path
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            raise self.err(key, f"particle file '{fname}' not found (looked for {path})") from None
        except OSError as e:
            raise self.err(key, f"cannot read particle file '{fname}' ({path}): "
                                f"{e.strerror or e}") from None
        csv_file = str(path)
        try:
            rows = list(csv.reader(io.StringIO(_decode_utf8(data, csv_file, key), newline="")))
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
        for n in names:
            if n not in CSV_COLUMNS:
                raise bad(f"line {hline}: unknown column '{n}' in the header; "
                          f"{_suggest(n, CSV_COLUMNS)}expected x,y,z,radius[,vx,vy,vz[,wx,wy,wz]]")
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
                    raise bad(f"line {lineno}, column '{names[c]}': cannot read {cell.strip()!r} "
                              f"as a number") from None
                if not math.isfinite(v):
                    raise bad(f"line {lineno}, column '{names[c]}': {cell.strip()} is not finite")
                if v != 0.0 and not MIN_MAGNITUDE <= abs(v) <= MAX_MAGNITUDE:
                    raise bad(f"line {lineno}, column '{names[c]}': {cell.strip()} is absurd "
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
            raise bad(f"line {row_lines[j]}: the particle centre {_fmt(positions[j])} lies "
                      f"outside the domain ({_fmt(lo)} to {_fmt(hi)})")
        vel = np.stack([col["vx"], col["vy"], col["vz"]], axis=1) if "vx" in col else None
        ang = np.stack([col["wx"], col["wy"], col["wz"]], axis=1) if "wx" in col else None
        return dict(positions=positions, radii=radii, velocities=vel, angular_velocities=ang)

    def parse_output(self, value: Any) -> Output:
        key = "output"
        t = self.table(value, key)
        self.check_keys(t, key, OUTPUT_KEYS)
        kw: dict[str, Any] = {}
        if "interval" in t:
            kw["interval"] = self.positive(t["interval"], "time", f"{key}.interval")
        for k in ("rrd", "h5"):
            if k in t:
                s = self.string(t[k], f"{key}.{k}")
                if not s.strip():
                    raise self.err(f"{key}.{k}", "must be a non-empty file path")
                kw[k] = s
        if "checkpoint_interval" in t:
            kw["checkpoint_interval"] = self.positive(t["checkpoint_interval"], "time",
                                                      f"{key}.checkpoint_interval")
        return Output(**kw)

    def parse_thermal(self, value: Any, fills, walls, bodies) -> ThermalSettings:
        """[thermal] and [thermal.gas]; every particle material needs thermal_conductivity and
        heat_capacity, every fill a temperature, and walls/bodies with a temperature a
        thermal_conductivity for their material."""
        key = "thermal"
        t = self.table(value, key)
        self.check_keys(t, key, THERMAL_KEYS)
        kw: dict[str, Any] = {}
        for k in ("conduction", "wall_conduction", "radiation"):
            if k in t:
                kw[k] = self.boolean(t[k], f"{key}.{k}")
        if "contact_radius_correction" in t:
            c = self.string(t["contact_radius_correction"], f"{key}.contact_radius_correction")
            if c not in ("static", "collision", "none"):
                raise self.err(f"{key}.contact_radius_correction",
                               f"must be \"static\", \"collision\" or \"none\", got \"{c}\"")
            kw["contact_radius_correction"] = c
        if "gas" in t:
            kw["gas"] = self.parse_gas(t["gas"], f"{key}.gas")
        for k in ("radiation_to", "radiation_region"):
            if k in t and not kw.get("radiation"):
                raise self.err(f"{key}.{k}", "given but radiation is off; set radiation = true")
        if kw.get("radiation"):
            kw.update(self.parse_radiation(t, key, kw.get("gas"), fills, walls, bodies))
        kw["moisture"] = any(f.moisture is not None for f in fills)
        if "evaporation_temperature" in t:
            kw["evaporation_temperature"] = self.positive(
                t["evaporation_temperature"], "temperature", f"{key}.evaporation_temperature")
        if "latent_heat" in t:
            kw["latent_heat"] = self.positive(t["latent_heat"], "specific_energy", f"{key}.latent_heat")
        if "water_heat_capacity" in t:
            kw["water_heat_capacity"] = self.nonnegative(
                t["water_heat_capacity"], "specific_heat", f"{key}.water_heat_capacity")
        if "time_scale" in t:
            scale = self.positive(t["time_scale"], "dimensionless", f"{key}.time_scale")
            if scale < 1.0:
                raise self.err(f"{key}.time_scale", f"must be at least 1 (got {scale:g}): it "
                                                    "divides heat capacities so that heat moves "
                                                    "S times faster than the mechanics")
            kw["time_scale"] = scale
        if "gas_gap" in t:
            kw["gas_gap"] = self.boolean(t["gas_gap"], f"{key}.gas_gap")
        for k in ("gap_gas_conductivity", "gas_gap_lens", "gas_gap_min_gap", "gas_gap_pairs",
                  "gas_gap_model", "gas_gap_porosity"):
            if k in t and not kw.get("gas_gap"):
                raise self.err(f"{key}.{k}", "given but gas_gap is off; set gas_gap = true")
        if kw.get("gas_gap"):
            if "gap_gas_conductivity" in t:
                kw["gap_gas_conductivity"] = self.positive(
                    t["gap_gas_conductivity"], "thermal_conductivity", f"{key}.gap_gas_conductivity")
            elif kw.get("gas") is not None:
                kw["gap_gas_conductivity"] = kw["gas"].conductivity
            if "gas_gap_lens" in t:
                lens = self.positive(t["gas_gap_lens"], "dimensionless", f"{key}.gas_gap_lens")
                if lens > 1.0:
                    raise self.err(f"{key}.gas_gap_lens", f"must be at most 1 (a lens one radius "
                                                          f"thick), got {lens:g}")
                kw["gas_gap_lens"] = lens
            if "gas_gap_min_gap" in t:
                kw["gas_gap_min_gap"] = self.positive(t["gas_gap_min_gap"], "length",
                                                      f"{key}.gas_gap_min_gap")
            if "gas_gap_pairs" in t:
                kw["gas_gap_pairs"] = self.boolean(t["gas_gap_pairs"], f"{key}.gas_gap_pairs")
            if "gas_gap_model" in t:
                model = t["gas_gap_model"]
                if model not in ("isothermal", "solid_resistance", "voronoi"):
                    raise self.err(f"{key}.gas_gap_model", f"must be \"isothermal\", "
                                                           f"\"solid_resistance\" or \"voronoi\", "
                                                           f"not {model!r}")
                kw["gas_gap_model"] = model
            if "gas_gap_porosity" in t:
                porosity = self.positive(t["gas_gap_porosity"], "dimensionless",
                                         f"{key}.gas_gap_porosity")
                if not 0.2 <= porosity <= 0.9:
                    raise self.err(f"{key}.gas_gap_porosity", f"the porosity of the packing the "
                                                              f"Voronoi cones are sized for: 0.2 to "
                                                              f"0.9, got {porosity:g}")
                if kw.get("gas_gap_model") != "voronoi":
                    raise self.err(f"{key}.gas_gap_porosity", "only the \"voronoi\" gas_gap_model "
                                                              "uses it")
                kw["gas_gap_porosity"] = porosity
        settings = ThermalSettings(**kw)
        if settings.gas_gap:
            hot = [w.name for w in list(walls) + list(bodies) if w.temperature is not None]
            to_walls = settings.wall_conduction and hot
            to_pairs = settings.conduction and settings.gas_gap_pairs
            if not to_walls and not to_pairs:
                raise self.err(f"{key}.gas_gap", "has nothing to conduct through: the gas gap "
                                                 "between particles needs conduction = true "
                                                 "(and gas_gap_pairs not false), the one to "
                                                 "walls and bodies needs wall_conduction on and "
                                                 "a wall or body with a temperature; enable one "
                                                 "or drop gas_gap")
        for f in fills:
            mat = self.materials[f.material]
            for k in ("thermal_conductivity", "heat_capacity"):
                if getattr(mat, k) is None:
                    raise self.err(f"materials.{f.material}.{k}",
                                   f"required when [thermal] is present (particles of '{f.material}')")
            if f.temperature is None:
                raise self.err(f"{f.key}.temperature", "required when [thermal] is present")
        if settings.wall_conduction:
            for w in list(walls) + list(bodies):
                if w.temperature is not None and self.materials[w.material].thermal_conductivity is None:
                    raise self.err(f"materials.{w.material}.thermal_conductivity",
                                   f"required: '{w.name}' has a temperature and [thermal] "
                                   f"wall_conduction is on")
        return settings

    def parse_gas(self, value: Any, key: str) -> GasSettings:
        """[thermal.gas]: a fixed gas, or an axial plug-flow stream (its velocity derived from
        the mass flow, density and flow area)."""
        g = self.table(value, key)
        self.check_keys(g, key, GAS_KEYS)
        gk: dict[str, Any] = {}
        model = self.string(g.get("model", "fixed"), f"{key}.model")
        if model not in ("fixed", "axial_plug_flow"):
            raise self.err(f"{key}.model", f"must be \"fixed\" or \"axial_plug_flow\", got \"{model}\"")
        gk["model"] = model
        if "drag" in g:
            drag = self.string(g["drag"], f"{key}.drag")
            if drag not in DRAG_MODELS + ("none",):
                raise self.err(f"{key}.drag", f"must be \"none\", \"di_felice\" or "
                                              f"\"schiller_naumann\", got \"{drag}\"")
            gk["drag"] = drag
        if model == "fixed":
            for k in PLUG_FLOW_KEYS:
                if k in g:
                    raise self.err(f"{key}.{k}", f"only for model = \"axial_plug_flow\" (this "
                                                 f"gas is \"fixed\")")
        else:
            for k in FIXED_GAS_ONLY:
                if k in g:
                    what = ("the inlet temperature is inlet_temperature" if k == "temperature"
                            else "the stream's velocity follows from mass_flow, density and "
                                 "flow_area (or radius)")
                    raise self.err(f"{key}.{k}", f"not used by model = \"axial_plug_flow\": {what}")
        corr = self.string(g.get("correlation", "ranz_marshall"), f"{key}.correlation")
        if corr not in ("ranz_marshall", "gunn"):
            raise self.err(f"{key}.correlation", f"must be \"ranz_marshall\" or \"gunn\", got \"{corr}\"")
        gk["correlation"] = corr
        if "temperature" in g:
            gk["temperature"] = self.positive(g["temperature"], "temperature", f"{key}.temperature")
        if "velocity" in g:
            gk["velocity"] = self.vec3(g["velocity"], "speed", f"{key}.velocity")
        if "porosity" in g:
            eps = self.q(g["porosity"], "dimensionless", f"{key}.porosity")
            if not 0.0 < eps < 1.0:
                raise self.err(f"{key}.porosity", f"must be in (0, 1), got {eps:g}")
            gk["porosity"] = eps
        for k, dim in (("density", "density"), ("viscosity", "viscosity"),
                       ("conductivity", "thermal_conductivity"), ("heat_capacity", "specific_heat")):
            if k in g:
                gk[k] = self.positive(g[k], dim, f"{key}.{k}")
        if model == "axial_plug_flow":
            for k in PLUG_FLOW_REQUIRED:
                if k not in g:
                    raise self.err(f"{key}.{k}", "required for model = \"axial_plug_flow\" "
                                                 "(axis_point, axis_direction, length, cells, "
                                                 "flow_area or radius, mass_flow, inlet_temperature)")
            if ("flow_area" in g) == ("radius" in g):
                raise self.err(f"{key}.flow_area", "give exactly one of flow_area (m^2, the gas's "
                                                   "free cross-section) or radius (m: pi r^2)")
            if "axis_point" in g:
                gk["axis_point"] = self.vec3(g["axis_point"], "length", f"{key}.axis_point")
            gk["axis_direction"] = self.direction(g["axis_direction"], f"{key}.axis_direction")
            gk["length"] = self.positive(g["length"], "length", f"{key}.length")
            cells = self.integer(g["cells"], f"{key}.cells")
            if not 1 <= cells <= 10000:
                raise self.err(f"{key}.cells", f"must be between 1 and 10000, got {cells}")
            gk["cells"] = cells
            if "flow_area" in g:
                gk["flow_area"] = self.positive(g["flow_area"], "area", f"{key}.flow_area")
            else:
                gk["flow_area"] = math.pi * self.positive(g["radius"], "length", f"{key}.radius") ** 2
            gk["mass_flow"] = self.positive(g["mass_flow"], "mass_rate", f"{key}.mass_flow")
            gk["temperature"] = self.positive(g["inlet_temperature"], "temperature",
                                              f"{key}.inlet_temperature")
            flow = self.string(g.get("flow", "along_axis"), f"{key}.flow")
            if flow not in ("along_axis", "against_axis"):
                raise self.err(f"{key}.flow", f"must be \"along_axis\" (entering at axis_point) or "
                                              f"\"against_axis\" (entering at the far end), got \"{flow}\"")
            gk["flow"] = flow
            density = gk.get("density", GasSettings.density)
            speed = gk["mass_flow"] / (density * gk["flow_area"])
            sign = 1.0 if flow == "along_axis" else -1.0
            gk["velocity"] = tuple(sign * speed * c for c in gk["axis_direction"])
        return GasSettings(**gk)

    def parse_radiation(self, t: dict, key: str, gas, fills, walls, bodies) -> dict:
        """radiation_to = "gas" | a wall or body name (with a temperature) | a temperature;
        radiation_region optional; every particle material needs an emissivity."""
        if "radiation_to" not in t:
            raise self.err(f"{key}.radiation_to", "required when radiation = true: \"gas\" (the "
                                                  "local gas temperature), the name of a wall or "
                                                  "body with a temperature, or a temperature "
                                                  "(an enclosure, e.g. \"1200 C\")")
        to = t["radiation_to"]
        k = f"{key}.radiation_to"
        out: dict[str, Any] = {}
        surfaces = {w.name: w for w in list(walls) + list(bodies)}
        if to == "gas":
            if gas is None:
                raise self.err(k, "\"gas\" needs a [thermal.gas] table")
            out["radiation_to"] = "gas"
        elif isinstance(to, str) and to in surfaces:
            w = surfaces[to]
            if w.temperature is None:
                raise self.err(k, f"'{to}' has no temperature (it is adiabatic); give it a "
                                  f"temperature to radiate to it")
            out.update(radiation_to="surface", radiation_surface=to,
                       radiation_temperature=w.temperature)
        else:
            try:
                temp = self.positive(to, "temperature", k)
            except SceneError:
                names = ", ".join(surfaces) or "none"
                raise self.err(k, f"expected \"gas\", the name of a wall or body (defined: "
                                  f"{names}) or a temperature, got {_type_name(to)}") from None
            out.update(radiation_to="enclosure", radiation_temperature=temp)
        if "radiation_region" in t:
            out["radiation_region"] = self.parse_region(t["radiation_region"], f"{key}.radiation_region")
        for f in fills:
            mat = self.materials[f.material]
            if mat.emissivity is None:
                raise self.err(f"materials.{f.material}.emissivity",
                               f"required when radiation = true (particles of '{f.material}')")
        return out

    def check_coverage(self, interactions: dict, fills, walls, bodies=()) -> None:
        """Every pair of materials that can meet needs an [[interactions]] entry."""
        particle_mats: list[str] = []
        for f in fills:
            if f.material not in particle_mats:
                particle_mats.append(f.material)
        needed: list[tuple[str, str, str]] = []
        for i, a in enumerate(particle_mats):
            for b in particle_mats[i:]:
                needed.append((a, b, f"particles of '{a}' and of '{b}'"))
        for w in walls:
            for a in particle_mats:
                needed.append((a, w.material, f"particles of '{a}' and wall '{w.name}'"))
        for b in bodies:
            for a in particle_mats:
                needed.append((a, b.material, f"particles of '{a}' and body '{b.name}'"))
        for a, b, why in needed:
            if frozenset((a, b)) not in interactions:
                raise self.err("interactions",
                               f"no interaction for the material pair ('{a}', '{b}'), which can "
                               f"meet ({why}); add [[interactions]] with pair = [\"{a}\", "
                               f"\"{b}\"], restitution and friction")


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


def _fmt(v) -> str:
    return "[" + ", ".join(f"{float(x):g}" for x in v) + "]"
