"""Whole-population series: particles/count, kinetic_energy, lost (and lost_mass in
process/accounting.py), mass; thermal: mean temperature, mean moisture, evaporated mass and
the plug-flow gas stream's series."""
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
    """particles/count, kinetic_energy, lost; thermal scenes: mean_temperature (mean_moisture,
    evaporated_mass when drying); and the series of every effect that writes its own
    (``sample``: the gas stream's, the drag's, the collisions')."""

    def __init__(self, engine):
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        e, m = self.engine, now.measured
        thermal = {}
        if e.model.thermal:
            thermal["particles/mean_temperature"] = m["mean_temperature"]
            if e.model.moisture:
                thermal["particles/mean_moisture"] = m["mean_moisture"]
                thermal["particles/evaporated_mass"] = m["evaporated_mass"]
        values["particles/count"] = e.alive_count
        values["particles/kinetic_energy"] = m["kinetic_energy"]
        values["particles/lost"] = e.lost
        values.update(thermal)
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
