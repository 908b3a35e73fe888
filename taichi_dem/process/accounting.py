"""Outlets, lost particles, sensors and residence times: the host-side accounting that turns
the device's removal log and sensor sums into /series values (and /residence records).

Mass balance: every particle's mass as the device stores it is summed in float64 here, so
    initial + fed by factories = inside + removed at outlets + lost
closes to float64 round-off (``mass_balance``). Sensors only read; they never change the state.
"""
from __future__ import annotations

import math

import numpy as np

from .outlets import EXIT_LOST


class ProcessAccounts:
    """Per-outlet, per-sensor totals of one simulation."""

    def __init__(self, sim):
        self.sim = sim
        scene = sim.scene
        self.outlets = scene.outlets
        self.factory_names = [f.name for f in scene.factories]
        self.outlet_names = [o.name for o in scene.outlets]
        no = len(self.outlets)
        self.outlet_mass = np.zeros(no)          # kg removed so far
        self.outlet_count = np.zeros(no, np.int64)
        self.lost_mass = 0.0
        self.lost_count = 0
        self._reset_interval()
        self.planes = [x for x in scene.sensors if x.kind == "mass_flow"]
        self.residence = [x for x in scene.sensors if x.kind == "residence_time"]
        self.contacts = [x for x in scene.sensors if x.kind == "contact_count"]
        self.body_names = [b.name for b in scene.bodies]
        # residence records not yet written to the results file, and all of them
        self.residence_new = {x.name: [] for x in self.residence}
        self.residence_interval = {x.name: [] for x in self.residence}
        self.residence_all = {x.name: [] for x in self.residence}
        self.thermal = sim.engine.thermal
        self.drying = sim.engine.moisture

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
        for x in self.residence:
            src = self.factory_names.index(x.source)
            dst = self.outlet_names.index(x.target)
            sel = (batch["origin"] == src) & (exit_ == dst)
            if np.any(sel):
                rec = np.stack([batch["id"][sel].astype(np.float64), batch["t_in"][sel],
                                batch["t_out"][sel]], axis=1)
                self.residence_new[x.name].append(rec)
                self.residence_interval[x.name].append(rec)
                self.residence_all[x.name].append(rec)

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
    def sample(self, values: dict, interval: float):
        """Add this sample's process series to ``values`` (interval: s since the last)."""
        engine = self.sim.engine
        self.collect()
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
        if self.planes:
            mass, count = engine.process.take_plane_flows()
            for k, x in enumerate(self.planes):
                values[f"sensors/{x.name}/mass_flow"] = mass[k] / interval if interval > 0 else 0.0
                values[f"sensors/{x.name}/crossings"] = float(count[k])
        for x in self.residence:
            new = self.residence_interval[x.name]
            recs = np.concatenate(new) if new else np.empty((0, 3))
            self.residence_interval[x.name] = []
            t = recs[:, 2] - recs[:, 1]
            p = f"sensors/{x.name}/"
            values[p + "count"] = float(len(t))
            if len(t):
                values[p + "mean"] = float(np.mean(t))
                values[p + "median"], values[p + "p10"], values[p + "p90"] = (
                    float(v) for v in np.percentile(t, [50, 10, 90]))
            else:
                for k in ("mean", "median", "p10", "p90"):
                    values[p + k] = math.nan
        if self.contacts:
            counts = engine.mesh.contact_counts(engine.count)
            for x in self.contacts:
                values[f"sensors/{x.name}/contact_count"] = float(counts[self.body_names.index(x.body)])

    def pop_residence(self) -> dict[str, np.ndarray]:
        """Residence records (id, t_in, t_out) completed since the last call, per sensor."""
        out = {}
        for name, parts in self.residence_new.items():
            if parts:
                out[name] = np.concatenate(parts)
            self.residence_new[name] = []
        return out

    def residence_times(self, name: str) -> np.ndarray:
        """(id, t_in, t_out) of every particle that completed the sensor's path so far."""
        parts = self.residence_all[name]
        return np.concatenate(parts) if parts else np.empty((0, 3))

    def state_dict(self) -> dict:
        d = {"outlet_mass": self.outlet_mass.copy(), "outlet_count": self.outlet_count.copy(),
             "lost_mass": self.lost_mass, "lost_count": self.lost_count}
        for name in self.residence_all:
            d[f"residence:{name}"] = self.residence_times(name)
        return d

    def load_state_dict(self, d: dict):
        self.outlet_mass = np.asarray(d["outlet_mass"], float).copy()
        self.outlet_count = np.asarray(d["outlet_count"], np.int64).copy()
        self.lost_mass = float(d["lost_mass"])
        self.lost_count = int(d["lost_count"])
        for name in self.residence_all:
            rec = np.asarray(d.get(f"residence:{name}", np.empty((0, 3))), float).reshape(-1, 3)
            self.residence_all[name] = [rec] if len(rec) else []
            self.residence_new[name] = []
            self.residence_interval[name] = []
