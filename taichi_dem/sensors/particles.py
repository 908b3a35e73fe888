"""Whole-population series: particles/count, kinetic_energy, lost (and lost_mass in
process/accounting.py), mass; and the effects' own (the heat effects': mean temperature, mean
moisture, evaporated mass, the plug-flow gas stream's)."""
from __future__ import annotations

import numpy as np

from ..engine import transfer


def mass_inside(engine) -> float:
    """Mass of the particles in the simulation now, kg (float64 sum of the stored masses)."""
    s = engine.state
    n = engine.count
    alive, mass = transfer.read((s.alive, s.mass))
    return float(np.sum(mass[:n][alive[:n] != 0].astype(np.float64)))


class ParticleSeries:
    """particles/count, kinetic_energy, lost; and the series of every effect that writes its
    own (``sample``: the temperature's mean, the drying's moisture, the gas stream's, the
    drag's, the collisions')."""

    def __init__(self, engine):
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        e, m = self.engine, now.measured
        values["particles/count"] = e.alive_count
        values["particles/kinetic_energy"] = m["kinetic_energy"]
        values["particles/lost"] = e.lost
        for effect in e.model.effect_list:
            # an effect's own series (declared with its keys: SERIES in its settings module)
            if hasattr(effect, "sample"):
                effect.sample(values, e.count, m)


class ParticleMass:
    """particles/mass: the mass inside now (scenes with factories)."""

    def __init__(self, engine):
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        values["particles/mass"] = mass_inside(self.engine)
