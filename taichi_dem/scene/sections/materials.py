"""[materials.NAME] (with coarse_grained and calibration) and [[interactions]]: their keys and checks."""
from __future__ import annotations

import math
from typing import Any

from ..keys import REQUIRED, Key, Section, material_keys, material_section, register
from ..keys import type_name as _type_name
from ..model import CoarseGraining, Interaction, Material
from .calibration import CALIBRATION, CalibrationSection

ROLLING_MODELS = ("constant_torque", "epsd")
_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0

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

MATERIAL = register(Section("materials.*", "A material, [materials.NAME]", (
    Key("density", "quantity", "the solid's density", unit="density", default=REQUIRED, **_P),
    Key("youngs_modulus", "quantity", "Young's modulus (may be softened for a longer step)",
        unit="pressure", default=REQUIRED, **_P),
    Key("poisson_ratio", "quantity", "Poisson's ratio", unit="dimensionless", default=REQUIRED,
        minimum=-1.0, maximum=0.5, exclusive_minimum=True, exclusive_maximum=True),
    Key("thermal_conductivity", "quantity", "the solid's conductivity (needed with [thermal])",
        unit="thermal_conductivity", default=None, **_P),
    Key("heat_capacity", "quantity", "the solid's specific heat (needed with [thermal])",
        unit="specific_heat", default=None, **_P),
    Key("emissivity", "quantity", "grey-body emissivity (needed with radiation)",
        unit="dimensionless", default=None, minimum=0.0, maximum=1.0),
    Key("real_youngs_modulus", "quantity", "the real (unsoftened) modulus: contact conduction "
        "corrected for the softening; >= youngs_modulus", unit="pressure", default=None, **_P),
    Key("surface_roughness", "quantity", "the surface's roughness: the \"schlunder\" gas-gap "
        "law widens every gap by it (Schlünder's delta; 0 smooth)", unit="length", default=0.0,
        minimum=0.0),
    Key("surface_slope", "quantity", "the RMS slope of the surface's asperities: with "
        "surface_roughness and microhardness, the contact spot conducts through them "
        "(Yovanovich)", unit="dimensionless", default=None, **_P),
    Key("microhardness", "quantity", "the surface's microhardness (rough contact spots, "
        "Yovanovich)", unit="pressure", default=None, **_P),
    Key("coarse_grained", "table", "these particles stand for a finer bed (its heat law to "
        "walls): { represented_diameter, bed_porosity, surface_coverage, roughness }",
        default=None),
    Key("calibration", "table", "what the material was calibrated against: the record "
        "`taichi-dem calibrate` writes, or its file ([materials.NAME.calibration])",
        default=None),
), owner=__name__, nested={"coarse_grained": COARSE_GRAINED, "calibration": CALIBRATION}))

INTERACTION = register(Section("interactions[]", "The contact parameters of a pair of "
                               "materials, [[interactions]]", (
    Key("pair", "any", "two material names", default=REQUIRED,
        schema={"type": "array", "items": {"type": "string"}, "minItems": 2, "maxItems": 2}),
    Key("restitution", "quantity", "normal coefficient of restitution", unit="dimensionless",
        default=REQUIRED, minimum=0.0, maximum=1.0, exclusive_minimum=True),
    Key("friction", "quantity", "Coulomb sliding friction coefficient", unit="dimensionless",
        default=REQUIRED, minimum=0.0),
    Key("rolling_friction", "quantity", "rolling friction coefficient (0: none)",
        unit="dimensionless", default=Interaction.rolling_friction, minimum=0.0),
    Key("model", "choice", "the rolling friction model", default=Interaction.rolling_model,
        choices=ROLLING_MODELS),
    Key("rolling_damping", "quantity", "EPSD's viscous part, a fraction of critical damping",
        unit="dimensionless", default=Interaction.rolling_damping, minimum=0.0, maximum=1.0,
        why="a fraction of critical damping"),
), owner=__name__))


class MaterialSections(CalibrationSection):
    """Read by the loader's parser (scene/loader.py), which mixes this in with the reading
    helpers of common.Reader."""

    def parse_materials(self, value: Any) -> dict[str, Material]:
        t = self.table(value, "materials", "a table of [materials.NAME] tables")
        out: dict[str, Material] = {}
        for name, m in t.items():
            key = f"materials.{name}"
            m = self.table(m, key, f"a table ([materials.{name}])")
            kw = material_section(MATERIAL).read(m, self.source, key)
            # the keys effects add (Section.material_keys), with their defaults
            kw["effect_values"] = {k.name: kw.pop(k.name, k.default) for k in material_keys()}
            if kw.get("real_youngs_modulus", math.inf) < kw["youngs_modulus"]:
                raise self.err(f"{key}.real_youngs_modulus",
                               f"the real (unsoftened) modulus {kw['real_youngs_modulus']:g} Pa "
                               f"must be >= youngs_modulus = {kw['youngs_modulus']:g} Pa")
            spot = [k for k in ("surface_slope", "microhardness") if k in m]
            if spot and (len(spot) < 2 or not kw.get("surface_roughness")):
                missing = [k for k in ("surface_roughness", "surface_slope", "microhardness")
                           if not kw.get(k)]
                raise self.err(f"{key}.{spot[0]}",
                               f"a rough contact spot needs surface_roughness, surface_slope and "
                               f"microhardness together; missing: {', '.join(missing)}")
            if "coarse_grained" in m:
                kw["coarse_grained"] = self.parse_coarse_grained(m["coarse_grained"],
                                                                 f"{key}.coarse_grained")
            if "calibration" in m:
                kw["calibration"] = self.parse_calibration(m["calibration"],
                                                           f"{key}.calibration", name)
            out[name] = Material(name=name, **kw)
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
        return CoarseGraining(**COARSE_GRAINED.read(t, self.source, key))

    def parse_interactions(self, items: list[dict]):
        out: dict[frozenset, Interaction] = {}
        where: dict[frozenset, str] = {}
        for i, t in enumerate(items):
            key = f"interactions[{i}]"
            INTERACTION.check(t, self.source, key)
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
            v = INTERACTION.read(t, self.source, key, defaults=True)
            out[fs] = Interaction(pair=(a, b), restitution=v["restitution"],
                                  friction=v["friction"], rolling_friction=v["rolling_friction"],
                                  rolling_model=v["model"], rolling_damping=v["rolling_damping"])
            where[fs] = key
        return out, where

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
