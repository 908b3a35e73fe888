"""[viscous_damping]: its keys and settings (the effect is effect.py). Plain Python."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...errors import SceneError
from ...scene.keys import REQUIRED, Key, Section, register, type_name


@dataclass(frozen=True)
class DampingSettings:
    """a = -v / ``time_constant`` (s) on every moving particle."""
    time_constant: float


def read(table: Any, parser) -> DampingSettings:
    """The section, checked against its declaration (``parser``: the loader's, for the file
    name in errors)."""
    if not isinstance(table, dict):
        raise SceneError(parser.source, "viscous_damping", f"expected a table, got {type_name(table)}")
    return DampingSettings(**SECTION.read(table, parser.source, "viscous_damping"))


SECTION = register(Section("viscous_damping", "Background viscous damping for settling: "
                           "every moving particle's velocity relaxes to rest, a = -v / "
                           "time_constant (off without this section)", (
    Key("time_constant", "quantity", "the velocity falls by e in this time", unit="time",
        default=REQUIRED, minimum=0.0, exclusive_minimum=True),
), owner=__name__, reader=read, builds="taichi_dem.effects.viscous_damping.effect:build"))
