"""Gravity's declaration: the key it adds to [simulation] (``gravity``, m/s^2), its settings
(derived from that key: there is no [gravity] table), and what it can do to a particle, for
the time step and the divergence guard (setup/timestep.py). Plain Python (no Taichi)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ...scene.keys import Key, Section, register

STANDARD = (0.0, 0.0, -9.81)        # m/s^2, the default


@dataclass(frozen=True)
class GravitySettings:
    """g, m/s^2 (a 3-vector, nonzero)."""
    acceleration: tuple

    @property
    def magnitude(self) -> float:
        """|g|, m/s^2."""
        return float(np.linalg.norm(self.acceleration))


def derive(parser) -> Optional[GravitySettings]:
    """On where [simulation] gravity (read with the section) is nonzero."""
    g = tuple(float(a) for a in parser.simulation.gravity)
    return GravitySettings(g) if any(a != 0.0 for a in g) else None


def work_bound(scene, settings: GravitySettings, span) -> float:
    """The work per unit mass gravity can do on a particle crossing the domain (J/kg): g along
    its own direction over the domain's extent that way (``span``, m, per axis)."""
    g = settings.magnitude
    direction = np.abs(np.asarray(settings.acceleration, float)) / g
    return g * float(np.dot(direction, np.asarray(span, float)))


SECTION = register(Section("gravity", "Uniform gravity: [simulation] gravity, on where it is "
                           "nonzero", (), owner=__name__,
                           derive=derive, builds="taichi_dem.effects.gravity.effect:build",
                           adds={"simulation": (
                               Key("gravity", "vector", "gravity", unit="acceleration",
                                   default=STANDARD, when_off="kept"),
                           )},
                           work_bound=work_bound,
                           resting_acceleration=lambda scene, settings: settings.magnitude))
