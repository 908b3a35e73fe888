"""Sensors: read-only observers that turn the state at an output sample into /series values
under the names of CONTRACT.md. They never change the state of the particles; some take and
reset sums of their own (body loads, plane crossings) or of the removal log.

``build_sensors(sim)`` gives the sensors of one simulation, by name, in the order their series
are written; at every output sample ``Simulation._sample`` calls each one's
``sample(values, now)``, which adds its entries to ``values``. The process parts that also
write series (``process/accounting.py``: outlets and lost mass; ``process/factories.py``:
inserted mass) take the same call.

    particles.py   particles/count, kinetic_energy, lost, mass; thermal means; the gas stream
    mass_flow.py   mass-flow planes: crossings counted on the device in the drift
    residence.py   residence times from a factory to an outlet (from the removal log)
    contacts.py    particles touching each body
    loads.py       body force, torque and power; plane wall force (the heat flows they take
                   are written by thermal/wall_heat_flows.py)

The enabled effects add their own observers after these (``Effect.run_observers``): the heat
transfer's wall and body heat series (thermal/wall_heat_flows.py) and its energy balance
(thermal/energy_balance.py).
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Now:
    """What a sensor is told at a sample."""
    time: float          # s
    interval: float      # s since the previous sample (0 at the first)
    measured: dict       # Engine.measure() at this sample: energies, largest speed, means
    # s: a short sample (sensors/pooling.py) is pooled with the interval before it, this long;
    # a sensor whose series are "records" statistics pools its records over it too
    pooled_interval: float = 0.0


def build_sensors(sim) -> dict:
    """The sensors of ``sim`` (name -> object with ``sample(values, now)``), in the order their
    series are written. ``sim.accounts`` and ``sim.factories`` must exist already."""
    from .contacts import ContactCounts
    from .loads import BodyLoads, WallLoads
    from .mass_flow import MassFlowSensor
    from .particles import ParticleMass, ParticleSeries
    from .residence import ResidenceTimes

    scene = sim.scene
    kinds = {x.kind for x in scene.sensors}
    out = {"particles": ParticleSeries(sim.engine)}
    if sim.accounts is not None:
        out["outlets"] = sim.accounts
        if "mass_flow" in kinds:
            out["mass_flow"] = MassFlowSensor(sim.engine)
        if "residence_time" in kinds:
            out["residence"] = ResidenceTimes(scene, sim.accounts)
        if "contact_count" in kinds:
            out["contacts"] = ContactCounts(scene, sim.engine)
    if "contact_statistics" in kinds:
        from .contact_statistics import ContactStatistics
        out["contact_statistics"] = ContactStatistics(scene, sim.engine)
    if sim.factories is not None:
        out["factories"] = sim.factories
        out["mass"] = ParticleMass(sim.engine)
    if sim.engine.mesh is not None:
        out["bodies"] = BodyLoads(scene, sim.engine)
    if scene.walls:
        out["walls"] = WallLoads(scene, sim.engine)
    # the enabled effects' own observers (the heat's energy balance), after the loads and
    # the outlet accounts they read
    for effect in sim.engine.model.effect_list:
        out.update(effect.run_observers(sim))
    return out
