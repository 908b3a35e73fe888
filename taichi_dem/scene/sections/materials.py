"""[materials.NAME] (with its calibration) and [[interactions]]: their keys and checks. The keys
effects add to a material (its conductivity, ...) are theirs (scene/keys.py ``Section.adds``)."""
from __future__ import annotations

from typing import Any

from ..keys import REQUIRED, Key, Section, added_values, host_section, register
from ..keys import type_name as _type_name
from ..model import Interaction, Material
from .calibration import CALIBRATION, CalibrationSection

ROLLING_MODELS = ("constant_torque", "epsd")
_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0

MATERIAL = register(Section("materials.*", "A material, [materials.NAME]", (
    Key("density", "quantity", "the solid's density", unit="density", default=REQUIRED, **_P),
    Key("youngs_modulus", "quantity", "Young's modulus (may be softened for a longer step)",
        unit="pressure", default=REQUIRED, **_P),
    Key("poisson_ratio", "quantity", "Poisson's ratio", unit="dimensionless", default=REQUIRED,
        minimum=-1.0, maximum=0.5, exclusive_minimum=True, exclusive_maximum=True),
    Key("calibration", "table", "what the material was calibrated against: the record "
        "`taichi-dem calibrate` writes, or its file ([materials.NAME.calibration])",
        default=None),
), owner=__name__, nested={"calibration": CALIBRATION}))

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
            kw = host_section(MATERIAL).read(m, self.source, key)
            # the keys effects add (Section.adds), with their defaults
            kw["effect_values"] = added_values(MATERIAL.path, m, self.source, key)
            for name_added in kw["effect_values"]:
                kw.pop(name_added, None)
            if "calibration" in m:
                kw["calibration"] = self.parse_calibration(m["calibration"],
                                                           f"{key}.calibration", name)
            out[name] = Material(name=name, **kw)
        return out

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
