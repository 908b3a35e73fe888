"""[body_force]: its keys, the key it adds to every material, its series and its bound on a
free particle's acceleration (the effect is effect.py). Plain Python (no Taichi)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ...errors import SceneError
from ...scene.keys import REQUIRED, Key, Section, Series, register, type_name


@dataclass(frozen=True)
class BodyForceSettings:
    """a = ``acceleration`` (m/s^2, a 3-vector) x the material's body_force_factor."""
    acceleration: tuple


def read(table: Any, parser) -> BodyForceSettings:
    """The section, checked against its declaration (``parser``: the loader's)."""
    if not isinstance(table, dict):
        raise SceneError(parser.source, "body_force", f"expected a table, got {type_name(table)}")
    return BodyForceSettings(**SECTION.read(table, parser.source, "body_force"))


def factors(scene) -> dict[str, float]:
    """Each material's body_force_factor (1 where the material does not give one)."""
    return {name: m.effect_values["body_force_factor"] for name, m in scene.materials.items()}


def largest_acceleration(scene, settings: BodyForceSettings) -> float:
    """The largest acceleration the force gives any particle, m/s^2 (the time step and the
    divergence guard expect the speed it can build up across the domain)."""
    strength = math.sqrt(sum(a * a for a in settings.acceleration))
    return strength * max((abs(f) for f in factors(scene).values()), default=1.0)


SECTION = register(Section("body_force", "A uniform body force per unit mass on the "
                           "particles, times each material's body_force_factor (off without "
                           "this section)", (
    Key("acceleration", "vector", "the acceleration it gives a particle of factor 1",
        unit="acceleration", default=REQUIRED),
), owner=__name__, reader=read, builds="taichi_dem.effects.body_force.effect:build",
   adds={"materials.*": (
    Key("body_force_factor", "quantity", "how strongly [body_force] pulls this material "
        "(0: not at all)", unit="dimensionless", default=1.0),
)}, acceleration_bound=largest_acceleration))

# the series the effect writes (sensors/series.py; the results file's units come from here)
SERIES = (Series("body_force/force", "N", "the body force on all particles inside", "(3,)"),)
