"""[mobility]: its keys, its settings and their checks (the effect is effect.py).

Plain Python (no Taichi): the loader and ``taichi-dem schema`` read this module only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

from ...errors import SceneError
from ...scene.keys import AUTO, Key, Section, equals, given, register, suggest, type_name

MODES = ("at_rest", "body_frame")
# "auto" threshold: this fraction of g d_max, (m/s)^2 (effect.py says why)
THRESHOLD_SCALE = 1.0e-5
CELL_DIAMETERS = 3.0       # "auto" cell_size: this many largest diameters
DENSEST_PACKING = 0.74     # of equal spheres

SECTION = register(Section("mobility", "Skip the contacts and the integration of particles "
                           "that do not move (contacts between inactive particles frozen)", (
    Key("enabled", "boolean", "false: the section is ignored (no mobility)", default=True),
    Key("granular_temperature_threshold", "quantity", "a cell is mobile above this granular "
        "temperature (or squared mean velocity); \"auto\": 1e-5 g d_max", unit="specific_energy",
        default=AUTO, auto=True, minimum=0.0, exclusive_minimum=True),
    Key("solid_fraction_threshold", "quantity", "a cell is mobile below this solid fraction",
        unit="dimensionless", default=0.4, minimum=0.0, maximum=DENSEST_PACKING,
        exclusive_maximum=True, why="0.74: the densest packing of equal spheres; 0.4 typical"),
    Key("acceleration_threshold", "quantity", "a cell is mobile above this rms acceleration of "
        "its particles (a bed still ringing); not checked when absent", unit="acceleration",
        default=None, minimum=0.0, exclusive_minimum=True),
    Key("cell_size", "quantity", "the mobility cells' size; \"auto\": 3 largest diameters; at "
        "least 2", unit="length", default=AUTO, auto=True, minimum=0.0, exclusive_minimum=True),
    Key("mode", "choice", "velocities relative to rest, or to the rigid motion of `body`",
        default="at_rest", choices=MODES),
    Key("body", "string", "mode \"body_frame\": the body whose rigid motion the bed follows "
        "(a drum's shell)", default=None),
), owner=__name__, reader=lambda table, parser: read(table, parser),
   builds="taichi_dem.effects.mobility.effect:build", schema_rules=lambda: [
    {"if": equals("mode", "body_frame"), "then": given("body")},
    {"if": given("body"), "then": equals("mode", "body_frame")},
]))


@dataclass(frozen=True)
class MobilitySettings:
    """[mobility]: skip the contacts and the integration of particles that do not move
    (effects/mobility/effect.py). Cells of the mobility grid (blocks of contact cells about
    ``cell_size`` across) are judged at every neighbour rebuild, and at least every 2000 steps
    (a bed at rest asks for no rebuild; effect.py JUDGE_WITHIN_STEPS): *mobile* when the granular
    temperature of their particles (velocity fluctuation about the cell mean, (m/s)^2) or the
    squared mean velocity exceeds ``granular_temperature_threshold``, when their solid
    fraction is below ``solid_fraction_threshold``, when the rms acceleration of their
    particles exceeds ``acceleration_threshold`` (a bed still ringing after an impact is not
    in equilibrium: freezing it would freeze its forces) or when they touch an empty cell; *active*
    within one cell of a mobile one; *inactive* otherwise. Velocities are taken relative to
    the rigid motion of ``body`` in mode "body_frame" (drums, coolers), to rest in mode
    "at_rest"."""
    granular_temperature_threshold: float    # (m/s)^2 (resolved: "auto" = 1e-5 g d_max)
    solid_fraction_threshold: float = SECTION.default("solid_fraction_threshold")
    cell_size: float = 0.0                   # m (resolved: "auto" = 3 d_max)
    mode: str = SECTION.default("mode")      # "at_rest" | "body_frame"
    acceleration_threshold: float = math.inf  # m/s^2, rms acceleration; inf = not checked
    body: Optional[str] = None               # the body whose frame "body_frame" uses
    threshold_is_auto: bool = False


def read(table: Any, parser) -> Optional[MobilitySettings]:
    """The section (``parser``: the loader's, with the scene's gravity, particle sources and
    bodies read already); None when ``enabled = false``."""
    return parse(table, parser.source, parser.simulation.gravity, parser.sources, parser.bodies)


def parse(table: Any, file: str, gravity, sources, bodies) -> Optional[MobilitySettings]:
    """[mobility] (``enabled = false`` or no section: None). "auto" values scale with the
    scene: granular temperature THRESHOLD_SCALE x g d_max, cell size CELL_DIAMETERS x d_max
    (d_max the largest diameter of the fills and factories ``sources``)."""
    key = "mobility"
    if not isinstance(table, dict):
        raise SceneError(file, key, f"expected a table, got {type_name(table)}")
    SECTION.check(table, file, key)
    # a disabled section is still read whole: a wrong value is wrong whether used or not
    enabled = ("enabled" not in table
               or SECTION["enabled"].read(table["enabled"], file, f"{key}.enabled"))
    radii = [f.largest_radius for f in sources]
    d_max = 2.0 * max(radii) if radii else 0.0
    kw: dict[str, Any] = {}
    mode = table.get("mode", "at_rest")
    if mode not in MODES:
        raise SceneError(file, f"{key}.mode", f"unknown mode {type_name(mode)}; "
                                              f"{suggest(str(mode), MODES)}allowed: "
                                              + ", ".join(MODES))
    kw["mode"] = mode
    if mode == "body_frame":
        if "body" not in table:
            raise SceneError(file, f"{key}.body", "required for mode \"body_frame\": the name of "
                                                  "the body whose rigid motion the bed follows "
                                                  "(a drum's shell)")
        name = SECTION["body"].read(table["body"], file, f"{key}.body")
        names = [b.name for b in bodies]
        if name not in names:
            raise SceneError(file, f"{key}.body", f"unknown body '{name}'; {suggest(name, names)}"
                                                  f"bodies: {', '.join(names) or 'none'}")
        kw["body"] = name
    elif "body" in table:
        raise SceneError(file, f"{key}.body", "only used with mode = \"body_frame\"")
    k = f"{key}.granular_temperature_threshold"
    try:
        threshold = SECTION["granular_temperature_threshold"].read(
            table.get("granular_temperature_threshold", AUTO), file, k)
    except SceneError as e:
        raise SceneError(file, e.key, f"{e.reason}; a granular temperature in (m/s)^2 "
                                      "(e.g. 1e-4 or \"1e-4 m^2/s^2\"), or \"auto\"") from None
    if threshold == AUTO:
        g = math.sqrt(sum(c * c for c in gravity))
        if (g == 0.0 or d_max == 0.0) and enabled:
            raise SceneError(file, k, "\"auto\" scales with g d (gravity x the largest diameter), "
                                      "but this scene has " + ("no gravity" if g == 0.0 else "no particles")
                             + ": give a value in (m/s)^2, e.g. 1e-3 x (a reference speed)^2")
        kw["granular_temperature_threshold"] = THRESHOLD_SCALE * g * d_max
        kw["threshold_is_auto"] = True
    else:
        kw["granular_temperature_threshold"] = threshold
    kw.update(SECTION.read(table, file, key, only=("solid_fraction_threshold",
                                                   "acceleration_threshold")))
    k = f"{key}.cell_size"
    cell = SECTION["cell_size"].read(table.get("cell_size", AUTO), file, k)
    if cell == AUTO:
        kw["cell_size"] = CELL_DIAMETERS * d_max
    else:
        kw["cell_size"] = cell
        if enabled and d_max > 0 and cell < 2.0 * d_max:
            raise SceneError(file, k, f"{cell:.3g} m is less than two largest diameters "
                                      f"({2 * d_max:.3g} m): too few particles per cell for a "
                                      "granular temperature or a solid fraction")
    return MobilitySettings(**kw) if enabled else None
