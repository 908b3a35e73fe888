"""Outlets and lost particles: the host-side accounting that turns the device's removal log
(process/outlets.py) into /series values.

Mass balance: every particle's mass as the device stores it is summed in float64 here, so
    initial + fed by factories = inside + removed at outlets + lost
closes to float64 round-off (``Simulation.mass_balance``). Each drained batch of the log is
also handed to the ``listeners`` (the residence-time sensor, sensors/residence.py). Accounting
only reads; it never changes the state.
"""
from __future__ import annotations

import math

import numpy as np

from .outlets import EXIT_LOST


class ProcessAccounts:
    """Per-outlet totals and the lost particles of one simulation."""

    def __init__(self, sim):
        self.sim = sim
        scene = sim.scene
        self.outlets = scene.outlets
        no = len(self.outlets)
        self.outlet_mass = np.zeros(no)          # kg removed so far
        self.outlet_count = np.zeros(no, np.int64)
        self.lost_mass = 0.0
        self.lost_count = 0
        self.removed_energy = 0.0                # J, sum m c T of what left the scene
        self._reset_interval()
        # callables batch -> None, given every drained batch of the removal log
        self.listeners: list = []
        self.thermal = sim.engine.model.carries("temperature")
        self.drying = sim.engine.model.carries("moisture")

    def _reset_interval(self):
        no = len(self.outlets)
        self.i_mass = np.zeros(no)
        self.i_count = np.zeros(no, np.int64)
        self.i_heat = np.zeros(no)               # sum m T (for the mass-weighted mean)
        self.i_water = np.zeros(no)              # sum m X, kg water (dry mass m)

    # ------------------------------------------------------------------ removals
    def take(self, batch: dict):
        """Account one drained batch of the removal log."""
        exit_ = batch["exit"]
        mass = batch["mass"]
        lost = exit_ == EXIT_LOST
        if "thermal_mass" in batch:
            # m c T carried out of the scene (J), through outlets or across the domain's faces
            self.removed_energy += float(np.sum(batch["thermal_mass"] * batch["temperature"]))
        self.lost_mass += float(np.sum(mass[lost]))
        self.lost_count += int(np.sum(lost))
        for o in range(len(self.outlets)):
            sel = exit_ == o
            if not np.any(sel):
                continue
            m = float(np.sum(mass[sel]))
            self.outlet_mass[o] += m
            self.outlet_count[o] += int(np.sum(sel))
            self.i_mass[o] += m
            self.i_count[o] += int(np.sum(sel))
            if self.thermal:
                self.i_heat[o] += float(np.sum(mass[sel] * batch["temperature"][sel]))
            if "moisture" in batch:
                self.i_water[o] += float(np.sum(mass[sel] * batch["moisture"][sel]))
        for listen in self.listeners:
            listen(batch)

    def collect(self):
        """Account everything the device's removal log holds now."""
        engine = self.sim.engine
        if engine.process is not None and engine.process.log_enabled:
            batch = engine.process.drain()
            if batch is not None:
                engine.removed_batches.append(batch)
        for batch in engine.removed_batches:
            self.take(batch)
        engine.removed_batches.clear()

    # ------------------------------------------------------------------ samples
    def sample(self, values: dict, now):
        """Add this sample's outlet series to ``values`` (``now.interval``: s since the last
        sample). Drains the removal log first, so the sensors after it see this interval's
        removals."""
        self.collect()
        interval = now.interval
        for o, out in enumerate(self.outlets):
            p = f"outlets/{out.name}/"
            values[p + "mass"] = self.outlet_mass[o]
            values[p + "count"] = float(self.outlet_count[o])
            values[p + "mass_flow"] = self.i_mass[o] / interval if interval > 0 else 0.0
            if self.thermal:
                values[p + "mean_temperature"] = (self.i_heat[o] / self.i_mass[o]
                                                  if self.i_mass[o] > 0 else math.nan)
            if self.drying:
                # kg water per kg dry solid of what left in the interval
                values[p + "mean_moisture"] = (self.i_water[o] / self.i_mass[o]
                                               if self.i_mass[o] > 0 else math.nan)
        if self.outlets or self.sim.scene.factories:
            values["particles/lost_mass"] = self.lost_mass
        self._reset_interval()

    def state_dict(self) -> dict:
        return {"outlet_mass": self.outlet_mass.copy(), "outlet_count": self.outlet_count.copy(),
                "lost_mass": self.lost_mass, "lost_count": self.lost_count,
                "removed_energy": self.removed_energy}

    def load_state_dict(self, d: dict):
        self.outlet_mass = np.asarray(d["outlet_mass"], float).copy()
        self.outlet_count = np.asarray(d["outlet_count"], np.int64).copy()
        self.lost_mass = float(d["lost_mass"])
        self.lost_count = int(d["lost_count"])
        self.removed_energy = float(d.get("removed_energy", 0.0))
