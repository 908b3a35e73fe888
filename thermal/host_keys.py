"""The keys heat transfer adds to the scene's own sections (scene/keys.py ``Section.adds``): a
material's conductivity, heat capacity, emissivity and surface, a wall's or body's fixed
temperature, a fill's or factory's temperature and moisture; with their checks. [thermal]
declares them (thermal/settings.py), so the scene's code names none of them. Plain Python (no
Taichi).

Without [thermal], a material's properties are kept (a scene turns heat off by leaving out
[thermal], and its materials stay whole); a temperature on a fill, factory, wall or body is
ignored with a note (CONTRACT.md's own example scene has them); a moisture or a coarse graining
is refused (it would do nothing).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from taichi_dem.errors import SceneError
from . import dimensions  # noqa: F401 (the temperature's units, before the keys that use them)
from taichi_dem.scene.keys import REQUIRED, Key, Section, given, register, type_name

_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0


@dataclass(frozen=True)
class CoarseGraining:
    """[materials.NAME] coarse_grained: the particles stand for a bed of finer ones, and take
    heat from walls and bodies as that bed would (thermal/coarse_grained.py)."""
    represented_diameter: float          # m, the real particles' diameter
    bed_porosity: float = 0.4            # of the real bed: its bulk density and conductivity
    surface_coverage: float = 0.8        # Schlünder's phi_A, the wall's coverage by the first layer
    roughness: float = 0.0               # m, Schlünder's delta, added to the mean free path


COARSE_GRAINED = register(Section("materials.*.coarse_grained", "Particles that stand for a "
                                  "finer bed: its contact resistance and penetration to walls", (
    Key("represented_diameter", "quantity", "the real particles' diameter", unit="length",
        default=REQUIRED, **_P),
    Key("bed_porosity", "quantity", "the represented bed's porosity", unit="dimensionless",
        default=CoarseGraining.bed_porosity, minimum=0.2, maximum=0.9,
        why="the porosity of the represented bed"),
    Key("surface_coverage", "quantity", "Schlünder's phi_A: the fraction of the wall the first "
        "layer covers", unit="dimensionless", default=CoarseGraining.surface_coverage,
        minimum=0.0, maximum=1.0, exclusive_minimum=True,
        why="the fraction of the wall the first layer covers"),
    Key("roughness", "quantity", "Schlünder's delta, added to the mean free path", unit="length",
        default=CoarseGraining.roughness, minimum=0.0),
), owner=__name__))


def parse_coarse_grained(value: Any, file: str, key: str) -> CoarseGraining:
    """[materials.NAME] coarse_grained = { represented_diameter, bed_porosity,
    surface_coverage, roughness }."""
    if not isinstance(value, dict):
        raise SceneError(file, key, f"expected an inline table {{ represented_diameter = ... }}"
                                    f", got {type_name(value)}")
    return CoarseGraining(**COARSE_GRAINED.read(value, file, key))


_IGNORED = dict(when_off="ignored")
_KEPT = dict(when_off="kept")
_TEMPERATURE = dict(unit="temperature", default=None, **_P, **_IGNORED)
_MOISTURE = dict(unit="dimensionless", default=None, minimum=0.0,
                 off_reason="drying needs heat transfer: add a [thermal] section (and a gas "
                            "to dry in)")

HOST_KEYS = {
    "materials.*": (
        Key("thermal_conductivity", "quantity", "the solid's conductivity (needed with "
            "[thermal])", unit="thermal_conductivity", default=None, **_P, **_KEPT),
        Key("heat_capacity", "quantity", "the solid's specific heat (needed with [thermal])",
            unit="specific_heat", default=None, **_P, **_KEPT),
        Key("emissivity", "quantity", "grey-body emissivity (needed with radiation)",
            unit="dimensionless", default=None, minimum=0.0, maximum=1.0, **_KEPT),
        Key("real_youngs_modulus", "quantity", "the real (unsoftened) modulus: contact "
            "conduction corrected for the softening; >= youngs_modulus", unit="pressure",
            default=None, **_P, **_KEPT),
        Key("surface_roughness", "quantity", "the surface's roughness: the \"schlunder\" gas-gap "
            "law widens every gap by it (Schlünder's delta; 0 smooth)", unit="length",
            default=0.0, minimum=0.0, **_KEPT),
        Key("surface_slope", "quantity", "the RMS slope of the surface's asperities: with "
            "surface_roughness and microhardness, the contact spot conducts through them "
            "(Yovanovich)", unit="dimensionless", default=None, **_P, **_KEPT),
        Key("microhardness", "quantity", "the surface's microhardness (rough contact spots, "
            "Yovanovich)", unit="pressure", default=None, **_P, **_KEPT),
        Key("coarse_grained", "table", "these particles stand for a finer bed (its heat law to "
            "walls): { represented_diameter, bed_porosity, surface_coverage, roughness }",
            default=None, parse=parse_coarse_grained,
            off_reason="is a heat law: add a [thermal] section"),
    ),
    "walls[]": (
        Key("temperature", "quantity", "a fixed temperature (adiabatic when absent)",
            **_TEMPERATURE),
    ),
    "bodies[]": (
        Key("temperature", "quantity", "a fixed temperature (adiabatic when absent)",
            **_TEMPERATURE),
    ),
    "particles[]": (
        Key("temperature", "quantity", "initial temperature (required with [thermal])",
            **_TEMPERATURE),
        Key("moisture", "quantity", "kg water per kg dry solid (drying; needs [thermal])",
            **_MOISTURE),
    ),
    "factories[]": (
        Key("temperature", "quantity", "their temperature (with [thermal])", **_TEMPERATURE),
        Key("moisture", "quantity", "kg water per kg dry solid; drying, with [thermal]",
            **_MOISTURE),
    ),
}


def host_rules() -> dict:
    """The conditional keys among those added (for the schema's ``allOf`` of each host)."""
    nonzero = {"not": {"const": 0}}
    return {"materials.*": [
        {"if": {"anyOf": [given("surface_slope"), given("microhardness")]},
         "then": {"required": ["surface_slope", "microhardness", "surface_roughness"],
                  "properties": {"surface_roughness": nonzero}}},
    ]}


def check_materials(ctx) -> None:
    """Whether or not [thermal] is on: a real modulus is no softer than the simulated one, and
    a rough contact spot has its three keys. ``ctx``: the loader (``source``, ``materials``,
    ``doc``: the scene as given)."""
    for name, m in ctx.materials.items():
        key = f"materials.{name}"
        if (m.real_youngs_modulus or math.inf) < m.youngs_modulus:
            raise SceneError(ctx.source, f"{key}.real_youngs_modulus",
                             f"the real (unsoftened) modulus {m.real_youngs_modulus:g} Pa "
                             f"must be >= youngs_modulus = {m.youngs_modulus:g} Pa")
        given_keys = ctx.doc.get("materials", {}).get(name, {})
        spot = [k for k in ("surface_slope", "microhardness") if k in given_keys]
        if spot and (len(spot) < 2 or not m.surface_roughness):
            missing = [k for k in ("surface_roughness", "surface_slope", "microhardness")
                       if not getattr(m, k)]
            raise SceneError(ctx.source, f"{key}.{spot[0]}",
                             f"a rough contact spot needs surface_roughness, surface_slope and "
                             f"microhardness together; missing: {', '.join(missing)}")


def check_hosts(settings, ctx, fills, walls, bodies) -> None:
    """With [thermal] on (``settings``): every particle material has a conductivity and a
    heat capacity, every fill and factory a temperature, every wall or body with a
    temperature (where wall conduction is on) a conductivity for its material, and a
    coarse-grained material is a particle material that a hot wall or body reaches.
    ``ctx``: the loader (``source``, ``materials``); ``fills``: the fills and factories."""
    file = ctx.source
    _check_coarse_grained(settings, ctx, fills, walls, bodies)
    for f in fills:
        mat = ctx.materials[f.material]
        for k in ("thermal_conductivity", "heat_capacity"):
            if getattr(mat, k) is None:
                raise SceneError(file, f"materials.{f.material}.{k}",
                                 f"required when [thermal] is present (particles of '{f.material}')")
        if f.temperature is None and getattr(f, "frame_values", {}).get("temperature") is None:
            raise SceneError(file, f"{f.key}.temperature", "required when [thermal] is present"
                             + (" (the results file's frame has no temperatures)"
                                if getattr(f, "frame", None) is not None else ""))
    if settings.wall_conduction:
        for w in list(walls) + list(bodies):
            if w.temperature is not None and ctx.materials[w.material].thermal_conductivity is None:
                raise SceneError(file, f"materials.{w.material}.thermal_conductivity",
                                 f"required: '{w.name}' has a temperature and [thermal] "
                                 f"wall_conduction is on")


def _check_coarse_grained(settings, ctx, sources, walls, bodies) -> None:
    """A coarse_grained material must be a particle material whose wall conduction reaches a
    wall or body with a temperature: the law acts there and nowhere else, so anything less
    would be a key that silently does nothing."""
    used = {f.material for f in sources}
    for w in list(walls) + list(bodies):
        if ctx.materials[w.material].coarse_grained is not None and w.material not in used:
            raise SceneError(ctx.source, f"materials.{w.material}.coarse_grained",
                             f"'{w.name}' is made of it: coarse graining describes particles "
                             f"that stand for finer ones, not a wall")
    for name in sorted(used):
        if ctx.materials[name].coarse_grained is None:
            continue
        hot = [w for w in list(walls) + list(bodies) if w.temperature is not None]
        if not (settings.wall_conduction and hot):
            raise SceneError(ctx.source, f"materials.{name}.coarse_grained",
                             "acts between particles and walls or bodies with a temperature, "
                             "and there is none with [thermal] wall_conduction on: give a wall "
                             "or body a temperature, or drop coarse_grained")
