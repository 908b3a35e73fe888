"""[thermal] and [thermal.gas]: the keys of the heat effects (thermal/effects.py), their
settings and checks, in one place. Plain Python (no Taichi): the loader and ``taichi-dem
schema`` read this module only.

Each key names the effect it configures (``effect``): conduction, wall_conduction, gas_gap
(the gas-gap conduction to walls and between particles), radiation, drying, temperature
(the explicit update and its time scaling), convection and plug_flow_gas.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

from taichi_dem.errors import SceneError
from taichi_dem import air
from taichi_dem.scene.keys import (Key, Section, equals, given, none_of, register, type_name,
                                   unless)
from taichi_dem.scene.sections.regions import REGION
from taichi_dem.scene.keys import Series
from .host_keys import HOST_KEYS, check_hosts, check_materials, host_rules

DRAG_MODELS = ("di_felice", "schiller_naumann")
# (as [gas] through_bed: effects/drag/settings.py)
DRAG_THROUGH_BED_HELP = ("true: the gas is forced through every packing at its superficial "
                         "velocity (a bed on a distributor); false: it flows round packings (a "
                         "drum's bed, a flight's load) and drags only the particles that no "
                         "contact touches (the curtains)")
GAS_MODELS = ("fixed", "axial_plug_flow")
CORRELATIONS = ("ranz_marshall", "gunn")
FLOWS = ("along_axis", "against_axis")
RADIUS_CORRECTIONS = ("static", "collision", "none")
CONTACT_CONDUCTION_MODELS = ("steady", "collision")
GAS_GAP_MODELS = ("isothermal", "solid_resistance", "voronoi", "schlunder")
GAS_GAP_KEYS = ("gap_gas_conductivity", "gas_gap_lens", "gas_gap_min_gap", "gas_gap_pairs",
                "gas_gap_model", "gas_gap_porosity", "gas_pressure", "gas_gap_free_path")
# the models that size a Voronoi cone (gas_gap_porosity) and that widen the gap by l + delta
VORONOI_MODELS = ("voronoi", "schlunder")
WIDENED_MODELS = ("schlunder",)
# the "schlunder" model's default lens (radii): its packed beds of glass, steel and a low-
# conductivity solid come within 10 % of Zehner-Bauer-Schlünder at 0.4, 9-18 % below at 0.2
# (tests/verification/test_packed_bed.py, docs/verification/first_layer.md)
SCHLUNDER_LENS = 0.4

_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0

# the series of heat transfer (written by the heat effects, the sensors' loads and energy
# balance, and the outlets; declared here, with the effects, not in taichi_dem/sensors/series.py)
SERIES = (
    Series("thermal_time", "s", "thermal time, thermal.time_scale x the simulated time"),
    Series("bodies/*/heat_flow", "W", "into the body (an isothermal body)", interval="mean"),
    Series("bodies/*/heat_transfer_coefficient", "W/(m^2 K)", "wall to bed", interval="mean"),
    Series("walls/*/heat_flow", "W", "into the wall (an isothermal wall)"),
    Series("outlets/*/mean_temperature", "K", "of the particles removed in the interval",
           interval="weighted", weight="mass_flow"),
    Series("outlets/*/mean_moisture", "1", "of the particles removed in the interval",
           interval="weighted", weight="mass_flow"),
    Series("thermal/energy_inside", "J", "sum m c T of the particles inside"),
    Series("thermal/energy_fed", "J", "brought in by the factories so far"),
    Series("thermal/energy_removed", "J", "taken out by the outlets so far"),
    Series("thermal/particle_heat_loss", "J", "heat the particles gave off so far"),
    Series("thermal/wall_heat", "J", "into walls and bodies so far"),
    Series("thermal/gas_heat", "J", "into the gas so far"),
    Series("thermal/source_heat", "J", "into the particles from the effects' own sources so "
           "far (radiation in, less the vapour's enthalpy out)"),
    Series("particles/mean_temperature", "K", "mass- and heat-capacity-weighted mean; NaN "
           "while no particle is inside"),
    Series("particles/mean_moisture", "1", "drying: kg water per kg dry solid, mean; NaN while "
           "no particle is inside"),
    Series("particles/evaporated_mass", "kg", "drying: water evaporated so far"),
    Series("thermal/vapour_heat", "J", "drying: carried off by the vapour so far, "
           "(L + c_w T_e) per kg"),
    Series("thermal/radiated_heat", "J", "radiation: into the particles so far"),
    Series("gas/temperature", "K", "plug flow: the gas leaving each cell", "(cells,)"),
    Series("gas/outlet_temperature", "K", "plug flow: the gas leaving the stream"),
    Series("gas/heat_flow", "W", "plug flow: from the gas to the particles"),
    Series("gas/transferred_heat", "J", "plug flow: from the gas to the particles so far"),
)

# the per-particle fields heat transfer adds to each recorded frame (HDF5 /frames/<k>/<name>,
# the XDMF and ParaView point attributes, Simulation.particles()), where the particles carry
# them: name -> (unit, shape, description); a field's f64 residual, where it has one
# (<name>_residual, f32 scenes), is added to it (scene/catalog.py frame_fields)
FRAME_FIELDS = {
    "temperature": ("K", "(N,)", "temperature; with [thermal] only"),
    "moisture": ("1", "(N,)", "kg water per kg dry solid; with moisture only"),
}
# what a fill started from an earlier run's frame accepts of each (scene/sections/particles.py
# read_frame): the values must be "positive" or "nonnegative" (besides finite)
FRAME_FIELD_VALUES = {"temperature": "positive", "moisture": "nonnegative"}
# what the viewers colour the particles by, first choice first, where the frames have it (the
# rerun recording and the ParaView script; else the speed)
COLOUR_FIELDS = ("temperature",)
# the time-series views the rerun recording adds: title -> the series (fnmatch patterns)
SERIES_VIEWS = {"temperature (K)": ("*mean_temperature", "gas/outlet_temperature")}

GAS = register(Section("thermal.gas", "The gas the particles exchange heat with by convection: "
                       "uniform (\"fixed\") or an axial plug-flow stream", (
    Key("model", "choice", "\"fixed\": a uniform gas; \"axial_plug_flow\": a 1-D stream along an "
        "axis, marched cell by cell", default="fixed", choices=GAS_MODELS, effect="convection"),
    Key("drag", "choice", "the gas's drag on the particles (one-way)", default="none",
        choices=("none",) + DRAG_MODELS, effect="drag"),
    Key("drag_through_bed", "boolean", "with drag: " + DRAG_THROUGH_BED_HELP, default=False,
        effect="drag"),
    Key("temperature", "quantity", "fixed gas: its temperature", unit="temperature",
        default=air.TEMPERATURE, **_P, effect="convection"),
    Key("velocity", "vector", "fixed gas: its superficial velocity", unit="speed",
        default=(0.0, 0.0, 0.0), effect="convection"),
    Key("correlation", "choice", "the Nusselt correlation", default="ranz_marshall",
        choices=CORRELATIONS, effect="convection"),
    Key("porosity", "quantity", "the bed's voidage (\"gunn\")", unit="dimensionless",
        default=0.4, minimum=0.0, maximum=1.0, exclusive_minimum=True, exclusive_maximum=True,
        effect="convection"),
    Key("density", "quantity", "the gas's density", unit="density", default=air.DENSITY, **_P),
    Key("viscosity", "quantity", "the gas's dynamic viscosity", unit="viscosity",
        default=air.VISCOSITY, **_P),
    Key("conductivity", "quantity", "the gas's thermal conductivity", unit="thermal_conductivity",
        default=air.CONDUCTIVITY, **_P),
    Key("heat_capacity", "quantity", "the gas's specific heat", unit="specific_heat",
        default=air.HEAT_CAPACITY, **_P),
    Key("axis_point", "vector", "plug flow: the axis's start", unit="length",
        default=(0.0, 0.0, 0.0), effect="plug_flow_gas"),
    Key("axis_direction", "direction", "plug flow: the axis's direction (required)",
        default=(1.0, 0.0, 0.0), effect="plug_flow_gas"),
    Key("length", "quantity", "plug flow: the stream's length (required)", unit="length",
        default=None, **_P, effect="plug_flow_gas"),
    Key("cells", "integer", "plug flow: the number of equal cells along the axis (required)",
        default=None, minimum=1, maximum=10000, effect="plug_flow_gas"),
    Key("flow_area", "quantity", "plug flow: the gas's free cross-section (or `radius`)",
        unit="area", default=None, **_P, effect="plug_flow_gas"),
    Key("radius", "quantity", "plug flow: the flow area as pi r^2 (or `flow_area`)",
        unit="length", default=None, **_P, effect="plug_flow_gas"),
    Key("mass_flow", "quantity", "plug flow: the gas's mass flow (required)", unit="mass_rate",
        default=None, **_P, effect="plug_flow_gas"),
    Key("inlet_temperature", "quantity", "plug flow: the gas's inlet temperature (required)",
        unit="temperature", default=None, **_P, effect="plug_flow_gas"),
    Key("flow", "choice", "plug flow: entering at axis_point (\"along_axis\") or at the far end",
        default="along_axis", choices=FLOWS, effect="plug_flow_gas"),
), owner=__name__, schema_rules=lambda: [
    # the plug-flow gas's keys, and the fixed gas's, as parse_gas checks them
    {"if": unless("model", "axial_plug_flow"), "then": none_of(*PLUG_FLOW_KEYS),
     "else": {"required": list(PLUG_FLOW_REQUIRED),
              "allOf": [none_of(*FIXED_GAS_ONLY), {"oneOf": [given("flow_area"), given("radius")]}]}},
]))
FIXED_GAS_ONLY = ("temperature", "velocity")
PLUG_FLOW_KEYS = ("axis_point", "axis_direction", "length", "cells", "flow_area", "radius",
                  "mass_flow", "inlet_temperature", "flow")
PLUG_FLOW_REQUIRED = ("axis_direction", "length", "cells", "mass_flow", "inlet_temperature")

def _absolute_temperature() -> dict:
    """The JSON Schema of a temperature above 0 K (a number in K or a string with a unit)."""
    from taichi_dem.scene.schema import quantity
    return quantity("temperature", 0.0, exclusive_minimum=True)


THERMAL = register(Section("thermal", "Heat transfer: present = compiled and run; each part "
                           "switchable", (
    Key("conduction", "boolean", "particle-particle conduction through the contact spot",
        default=True, effect="conduction"),
    Key("wall_conduction", "boolean", "conduction to walls and bodies that have a temperature",
        default=True, effect="wall_conduction"),
    Key("radiation", "boolean", "grey-body radiation to `radiation_to`", default=False,
        effect="radiation"),
    Key("gas", "table", "the gas for convection (and drag): [thermal.gas]", default=None,
        effect="convection"),
    Key("contact_radius_correction", "choice", "the contact radius corrected for a softened "
        "modulus: \"static\" a ~ E*^-1/3, \"collision\" a ~ E*^-1/5, or \"none\"",
        default="static", choices=RADIUS_CORRECTIONS, effect="conduction"),
    Key("contact_conduction_model", "choice", "contacts between particles, and with walls "
        "and bodies where wall_conduction is on: \"steady\" the spot law 2 k a alone; \"collision\" Sun & Chen's transient heat of a collision too "
        "(0.87 pi a_max^2 t_c^1/2 dT / sum (rho c k)^-1/2, as Zhou, Yu & Zulli 2010's per-step "
        "flux): while a contact lasts no longer than the Hertz duration t_c of its impact (the "
        "normal speed at its first step) it passes the real collision's heat, the larger of "
        "that and the spot law (real radius and t_c where the modulus is softened); the spot "
        "law after, so a resting bed keeps it. It matters where the contact's Fourier number "
        "kappa t_c / a^2 is small: a collision conducts ~0.9/sqrt(Fo) times the spot law's heat",
        default="steady", choices=CONTACT_CONDUCTION_MODELS, effect="conduction"),
    Key("radiation_to", "any", "what the particles see: \"gas\", a wall or body with a "
        "temperature, or a temperature (an enclosure); required with radiation",
        default=None, effect="radiation",
        schema={"anyOf": [{"type": "string"}, _absolute_temperature()],
                "x-unit": "K", "x-dimension": "temperature"}),
    Key("radiation_region", "table", "radiation only inside this region (a box or cylinder)",
        default=None, effect="radiation"),
    Key("evaporation_temperature", "quantity", "drying: the water's evaporation temperature",
        unit="temperature", default=373.15, **_P, effect="drying"),
    Key("latent_heat", "quantity", "drying: the water's latent heat", unit="specific_energy",
        default=2.26e6, **_P, effect="drying"),
    Key("water_heat_capacity", "quantity", "drying: liquid water's specific heat",
        unit="specific_heat", default=4186.0, minimum=0.0, effect="drying"),
    Key("critical_moisture", "quantity", "drying: the falling-rate period below this "
        "moisture (kg water per kg dry solid): only X / X_cr of the heat above the evaporation "
        "temperature evaporates water, the rest warms the particle (0: none)",
        unit="dimensionless", default=0.0, minimum=0.0, effect="drying"),
    Key("gas_gap", "boolean", "conduction through the gas gap near contacts (to walls and "
        "bodies, and between particles unless gas_gap_pairs = false)", default=False,
        effect="gas_gap"),
    Key("gap_gas_conductivity", "quantity", "the gap gas's conductivity (default: [thermal.gas]"
        " conductivity, else air's)", unit="thermal_conductivity", default=air.CONDUCTIVITY,
        **_P, effect="gas_gap"),
    Key("gas_gap_lens", "quantity", "the fluid lens's thickness, in particle radii (default "
        "0.4 with the \"schlunder\" model, whose packed beds it brings within 10 % of "
        "Zehner-Bauer-Schlünder; 0.2 with the others)", unit="dimensionless", default=0.2,
        minimum=0.0, maximum=1.0, exclusive_minimum=True,
        why="at most 1: a lens one radius thick", effect="gas_gap",
        default_words='0.4 with gas_gap_model = "schlunder", else 0.2'),
    Key("gas_gap_min_gap", "quantity", "gaps narrower than this count as it (the roughness "
        "scale)", unit="length", default=1.0e-6, **_P, effect="gas_gap"),
    Key("gas_gap_pairs", "boolean", "the gas gap between particles too (with conduction on)",
        default=True, effect="gas_gap"),
    Key("gas_gap_model", "choice", "the solid's share of the path: \"solid_resistance\" (Cheng, "
        "Yu & Zulli 1999), \"isothermal\" (Rong & Horio 1999), \"voronoi\" (the Voronoi cones), "
        "\"schlunder\" (walls: Schlünder's isothermal first layer; pairs: the Voronoi cones; "
        "every gap widened by the mean free path and roughness)",
        default="schlunder", choices=GAS_GAP_MODELS, effect="gas_gap"),
    Key("gas_gap_porosity", "quantity", "\"voronoi\" and \"schlunder\": the porosity of the "
        "packing the Voronoi cones are sized for", unit="dimensionless", default=0.4,
        minimum=0.2, maximum=0.9, why="a packing's porosity, 0.2 to 0.9", effect="gas_gap"),
    Key("gas_pressure", "quantity", "\"schlunder\": the gas's pressure, for its mean free path "
        "(the Smoluchowski effect: lower pressure, wider effective gaps)", unit="pressure",
        default=101325.0, **_P, effect="gas_gap"),
    Key("gas_gap_free_path", "quantity", "\"schlunder\": the gas's modified mean free path l "
        "(default: Schlünder's, of air at gas_pressure and the scene's mean wall/feed "
        "temperature, with his accommodation coefficient)", unit="length", default=None, **_P,
        effect="gas_gap"),
    Key("time_scale", "quantity", "heat capacities divided by this: heat moves S times faster "
        "than the mechanics (thermal time = S x simulated time)", unit="dimensionless",
        default=1.0, minimum=1.0, why="it divides heat capacities so that heat moves S times "
        "faster than the mechanics", effect="temperature"),
), owner=__name__, nested={"gas": GAS, "radiation_region": REGION},
   builds="taichi_dem.thermal.effects:build",
   adds=HOST_KEYS, added_rules=host_rules, check_added=check_materials,
   reader=lambda table, parser: parse_thermal(table, parser, parser.sources, parser.walls,
                                              parser.bodies),
   schema_rules=lambda: [
    # the switches and the keys that need them, as parse_thermal checks them
    {"if": {"anyOf": [given("radiation_to"), given("radiation_region")]},
     "then": equals("radiation", True)},
    {"if": equals("radiation", True), "then": given("radiation_to")},
    {"if": {"anyOf": [given(k) for k in GAS_GAP_KEYS]}, "then": equals("gas_gap", True)},
    {"if": unless("contact_conduction_model", "steady"), "then": unless("conduction", False)},
    {"if": given("gas_gap_porosity"),
     "then": {"properties": {"gas_gap_model": {"enum": list(VORONOI_MODELS)}}}},
    {"if": {"anyOf": [given("gas_pressure"), given("gas_gap_free_path")]},
     "then": {"properties": {"gas_gap_model": {"enum": list(WIDENED_MODELS)}}}},
    {"if": given("gas_gap_min_gap"),
     "then": unless("gas_gap_model", *WIDENED_MODELS) | {"required": ["gas_gap_model"]}},
]))


@dataclass(frozen=True)
class GasSettings:
    """The gas particles exchange heat with by convection (air at 300 K by default).

    ``"fixed"``: uniform ``temperature`` and ``velocity``. ``"axial_plug_flow"``: a 1-D stream
    along the axis from ``axis_point`` along unit ``axis_direction`` for ``length``, in
    ``cells`` equal cells, entering at the axis_point end (``flow = "along_axis"``) or at the
    far end (``"against_axis"``) with ``mass_flow`` kg/s at ``temperature`` (the inlet
    temperature, K); ``velocity`` is then the stream's, mass_flow / (density flow_area) along
    the flow (the loader derives it). Defaults: the declarations above."""
    model: str = GAS.default("model")
    temperature: float = GAS.default("temperature")          # K (plug flow: the inlet's)
    velocity: tuple = GAS.default("velocity")                # m/s
    correlation: str = GAS.default("correlation")
    porosity: float = GAS.default("porosity")
    density: float = GAS.default("density")                  # kg/m^3
    viscosity: float = GAS.default("viscosity")              # Pa s
    conductivity: float = GAS.default("conductivity")        # W/(m K)
    heat_capacity: float = GAS.default("heat_capacity")      # J/(kg K)
    # axial_plug_flow only
    axis_point: tuple = GAS.default("axis_point")            # m
    axis_direction: tuple = GAS.default("axis_direction")    # unit
    length: float = 0.0                  # m
    cells: int = 0
    flow_area: float = 0.0               # m^2, the gas's free cross-section
    mass_flow: float = 0.0               # kg/s
    flow: str = GAS.default("flow")
    drag: str = GAS.default("drag")
    drag_through_bed: bool = GAS.default("drag_through_bed")

    @property
    def plug_flow(self) -> bool:
        return self.model == "axial_plug_flow"


@dataclass(frozen=True)
class ThermalSettings:
    """[thermal]: present = heat transfer compiled and run; each part switchable. What each
    field means: the key declarations above (THERMAL); the resolved radiation target:
    ``radiation_to`` "gas" | "surface" (the wall/body ``radiation_surface``) | "enclosure"
    (at ``radiation_temperature``, K); ``moisture``: on when a fill or factory is wet."""
    conduction: bool = THERMAL.default("conduction")
    wall_conduction: bool = THERMAL.default("wall_conduction")
    radiation: bool = THERMAL.default("radiation")
    gas: Optional[GasSettings] = None    # None = no convection
    contact_radius_correction: str = THERMAL.default("contact_radius_correction")
    contact_conduction_model: str = THERMAL.default("contact_conduction_model")
    radiation_to: str = ""
    radiation_surface: Optional[str] = None
    radiation_temperature: Optional[float] = None
    radiation_region: Any = None
    moisture: bool = False
    evaporation_temperature: float = THERMAL.default("evaporation_temperature")
    latent_heat: float = THERMAL.default("latent_heat")
    water_heat_capacity: float = THERMAL.default("water_heat_capacity")
    critical_moisture: float = THERMAL.default("critical_moisture")
    gas_gap: bool = THERMAL.default("gas_gap")
    gas_gap_pairs: bool = THERMAL.default("gas_gap_pairs")
    gas_gap_model: str = THERMAL.default("gas_gap_model")
    gas_gap_porosity: float = THERMAL.default("gas_gap_porosity")
    gas_pressure: float = THERMAL.default("gas_pressure")
    gas_gap_free_path: Optional[float] = None       # m; None: from the pressure, temperature
    time_scale: float = THERMAL.default("time_scale")
    gap_gas_conductivity: float = THERMAL.default("gap_gas_conductivity")
    gas_gap_lens: float = THERMAL.default("gas_gap_lens")
    # the lens came from the "schlunder" model's default, not the scene (the coarse-grained
    # wall law's reach keeps the key's own default then: its calibration is the lens's 0.2)
    gas_gap_lens_defaulted: bool = False

    @property
    def coarse_reach(self) -> float:
        """The coarse-grained wall law's reach (radii): gas_gap_lens as the scene gives it, else
        the key's default 0.2."""
        return THERMAL.default("gas_gap_lens") if self.gas_gap_lens_defaulted else self.gas_gap_lens
    gas_gap_min_gap: float = THERMAL.default("gas_gap_min_gap")


def parse_thermal(value: Any, ctx, fills, walls, bodies) -> ThermalSettings:
    """[thermal] and [thermal.gas]; every particle material needs thermal_conductivity and
    heat_capacity, every fill a temperature, and walls/bodies with a temperature a
    thermal_conductivity for their material. ``ctx``: the loader (``source``, ``materials``,
    ``parse_region``)."""
    key, file = "thermal", ctx.source
    t = ctx.table(value, key)
    THERMAL.check(t, file, key)
    kw: dict[str, Any] = THERMAL.read(t, file, key, only=("conduction", "wall_conduction",
                                                          "radiation", "contact_radius_correction",
                                                          "contact_conduction_model"))
    if kw.get("contact_conduction_model", "steady") != "steady" and not kw.get("conduction", True):
        raise SceneError(file, f"{key}.contact_conduction_model", "given but conduction is off "
                                                                  "(it is a law of the particle-"
                                                                  "particle conduction); set "
                                                                  "conduction = true")
    if "gas" in t:
        kw["gas"] = parse_gas(t["gas"], ctx, f"{key}.gas")
    for k in ("radiation_to", "radiation_region"):
        if k in t and not kw.get("radiation"):
            raise SceneError(file, f"{key}.{k}", "given but radiation is off; set radiation = true")
    if kw.get("radiation"):
        kw.update(parse_radiation(t, ctx, key, kw.get("gas"), fills, walls, bodies))
    # the sources' moisture (fills and factories), or a fill's particles' from a results file
    kw["moisture"] = any(f.moisture is not None or (getattr(f, "frame_values", {}).get(
        "moisture") is not None and f.frame_values["moisture"].any()) for f in fills)
    kw.update(THERMAL.read(t, file, key, only=("evaporation_temperature", "latent_heat",
                                               "water_heat_capacity", "critical_moisture",
                                               "gas_gap")))
    if "time_scale" in t:
        k = f"{key}.time_scale"
        scale = Key("time_scale", "quantity", "", unit="dimensionless", minimum=0.0,
                    exclusive_minimum=True).read(t["time_scale"], file, k)
        if scale < THERMAL["time_scale"].minimum:
            raise SceneError(file, k, f"must be at least 1 (got {scale:g}): it divides heat "
                                      "capacities so that heat moves S times faster than the "
                                      "mechanics")
        kw["time_scale"] = scale
    for k in GAS_GAP_KEYS:
        if k in t and not kw.get("gas_gap"):
            raise SceneError(file, f"{key}.{k}", "given but gas_gap is off; set gas_gap = true")
    if kw.get("gas_gap"):
        kw.update(THERMAL.read(t, file, key, only=GAS_GAP_KEYS))
        if "gap_gas_conductivity" not in t and kw.get("gas") is not None:
            kw["gap_gas_conductivity"] = kw["gas"].conductivity
        model = kw.get("gas_gap_model", THERMAL.default("gas_gap_model"))
        kw["gas_gap_model"] = model
        if model in WIDENED_MODELS and "gas_gap_lens" not in t:
            kw["gas_gap_lens"] = SCHLUNDER_LENS
            kw["gas_gap_lens_defaulted"] = True
        if "gas_gap_porosity" in t and model not in VORONOI_MODELS:
            raise SceneError(file, f"{key}.gas_gap_porosity", "only the \"voronoi\" and "
                                                              "\"schlunder\" gas_gap_models use it")
        for k in ("gas_pressure", "gas_gap_free_path"):
            if k in t and model not in WIDENED_MODELS:
                raise SceneError(file, f"{key}.{k}", "only the \"schlunder\" gas_gap_model uses "
                                                     "it (the others clamp the gap to "
                                                     "gas_gap_min_gap)")
        if "gas_gap_min_gap" in t and model in WIDENED_MODELS:
            raise SceneError(file, f"{key}.gas_gap_min_gap", "the \"schlunder\" gas_gap_model "
                                                             "widens every gap by the gas's mean "
                                                             "free path and the surfaces' "
                                                             "roughness instead: set "
                                                             "gas_gap_free_path or the materials' "
                                                             "surface_roughness")
    settings = ThermalSettings(**kw)
    if settings.gas_gap:
        hot = [w.name for w in list(walls) + list(bodies) if w.temperature is not None]
        to_walls = settings.wall_conduction and hot
        to_pairs = settings.conduction and settings.gas_gap_pairs
        if not to_walls and not to_pairs:
            raise SceneError(file, f"{key}.gas_gap", "has nothing to conduct through: the gas gap "
                                                     "between particles needs conduction = true "
                                                     "(and gas_gap_pairs not false), the one to "
                                                     "walls and bodies needs wall_conduction on and "
                                                     "a wall or body with a temperature; enable one "
                                                     "or drop gas_gap")
    check_hosts(settings, ctx, fills, walls, bodies)
    return settings


def parse_gas(value: Any, ctx, key: str) -> GasSettings:
    """[thermal.gas]: a fixed gas, or an axial plug-flow stream (its velocity derived from
    the mass flow, density and flow area)."""
    file = ctx.source
    g = ctx.table(value, key)
    GAS.check(g, file, key)
    gk: dict[str, Any] = GAS.read(g, file, key, only=("model", "drag", "drag_through_bed"))
    model = gk.setdefault("model", "fixed")
    if "drag_through_bed" in gk and gk.get("drag", "none") == "none":
        raise SceneError(file, f"{key}.drag_through_bed", "only with a drag (drag = "
                                                          "\"di_felice\" or \"schiller_naumann\")")
    if model == "fixed":
        for k in PLUG_FLOW_KEYS:
            if k in g:
                raise SceneError(file, f"{key}.{k}", "only for model = \"axial_plug_flow\" (this "
                                                     "gas is \"fixed\")")
    else:
        for k in FIXED_GAS_ONLY:
            if k in g:
                what = ("the inlet temperature is inlet_temperature" if k == "temperature"
                        else "the stream's velocity follows from mass_flow, density and "
                             "flow_area (or radius)")
                raise SceneError(file, f"{key}.{k}", f"not used by model = \"axial_plug_flow\": {what}")
    gk.update(GAS.read(g, file, key, only=("correlation", "temperature", "velocity", "porosity",
                                           "density", "viscosity", "conductivity",
                                           "heat_capacity")))
    if model == "axial_plug_flow":
        for k in PLUG_FLOW_REQUIRED:
            if k not in g:
                raise SceneError(file, f"{key}.{k}", "required for model = \"axial_plug_flow\" "
                                                     "(axis_point, axis_direction, length, cells, "
                                                     "flow_area or radius, mass_flow, inlet_temperature)")
        if ("flow_area" in g) == ("radius" in g):
            raise SceneError(file, f"{key}.flow_area", "give exactly one of flow_area (m^2, the "
                                                       "gas's free cross-section) or radius (m: pi r^2)")
        plug = GAS.read(g, file, key, only=PLUG_FLOW_KEYS)
        for k in ("axis_point", "axis_direction", "length", "cells", "flow_area", "mass_flow"):
            if k in plug:
                gk[k] = plug[k]
        if "radius" in plug:
            gk["flow_area"] = math.pi * plug["radius"] ** 2
        gk["temperature"] = plug["inlet_temperature"]
        gk["flow"] = flow = plug.get("flow", "along_axis")
        density = gk.get("density", GasSettings.density)
        speed = gk["mass_flow"] / (density * gk["flow_area"])
        sign = 1.0 if flow == "along_axis" else -1.0
        gk["velocity"] = tuple(sign * speed * c for c in gk["axis_direction"])
    return GasSettings(**gk)


def parse_radiation(t: dict, ctx, key: str, gas, fills, walls, bodies) -> dict:
    """radiation_to = "gas" | a wall or body name (with a temperature) | a temperature;
    radiation_region optional; every particle material needs an emissivity."""
    file = ctx.source
    if "radiation_to" not in t:
        raise SceneError(file, f"{key}.radiation_to", "required when radiation = true: \"gas\" (the "
                                                      "local gas temperature), the name of a wall or "
                                                      "body with a temperature, or a temperature "
                                                      "(an enclosure, e.g. \"1200 C\")")
    to = t["radiation_to"]
    k = f"{key}.radiation_to"
    out: dict[str, Any] = {}
    surfaces = {w.name: w for w in list(walls) + list(bodies)}
    if to == "gas":
        if gas is None:
            raise SceneError(file, k, "\"gas\" needs a [thermal.gas] table")
        out["radiation_to"] = "gas"
    elif isinstance(to, str) and to in surfaces:
        w = surfaces[to]
        if w.temperature is None:
            raise SceneError(file, k, f"'{to}' has no temperature (it is adiabatic); give it a "
                                      f"temperature to radiate to it")
        out.update(radiation_to="surface", radiation_surface=to,
                   radiation_temperature=w.temperature)
    else:
        temperature = Key("radiation_to", "quantity", "", unit="temperature", minimum=0.0,
                          exclusive_minimum=True)
        try:
            temp = temperature.read(to, file, k)
        except SceneError:
            names = ", ".join(surfaces) or "none"
            raise SceneError(file, k, f"expected \"gas\", the name of a wall or body (defined: "
                                      f"{names}) or a temperature, got {type_name(to)}") from None
        out.update(radiation_to="enclosure", radiation_temperature=temp)
    if "radiation_region" in t:
        out["radiation_region"] = ctx.parse_region(t["radiation_region"], f"{key}.radiation_region")
    for f in fills:
        mat = ctx.materials[f.material]
        if mat.emissivity is None:
            raise SceneError(file, f"materials.{f.material}.emissivity",
                             f"required when radiation = true (particles of '{f.material}')")
    return out
