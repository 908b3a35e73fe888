"""Residence times (``[[sensors]] kind = "residence_time"``): how long the particles a factory
inserted took to reach an outlet. Records (id, t_in s, t_out s) come from the removal log
(process/outlets.py), which the outlet accounting drains and hands on here; /series
sensors/<name>/count, mean, median, p10, p90 describe those completed in the output interval,
and /residence/<name> in the results file holds every record."""
from __future__ import annotations

import math

import numpy as np


class ResidenceTimes:
    """Residence records of every residence-time sensor of one simulation."""

    def __init__(self, scene, accounts):
        self.sensors = [x for x in scene.sensors if x.kind == "residence_time"]
        self.factory_names = [f.name for f in scene.factories]
        self.outlet_names = [o.name for o in scene.outlets]
        # records not yet written to the results file, those of this interval, and all
        self.new = {x.name: [] for x in self.sensors}
        self.interval = {x.name: [] for x in self.sensors}
        self.all = {x.name: [] for x in self.sensors}
        accounts.listeners.append(self.take)

    def take(self, batch: dict) -> None:
        """The records of one drained batch of the removal log."""
        for x in self.sensors:
            src = self.factory_names.index(x.source)
            dst = self.outlet_names.index(x.target)
            sel = (batch["origin"] == src) & (batch["exit"] == dst)
            if np.any(sel):
                rec = np.stack([batch["id"][sel].astype(np.float64), batch["t_in"][sel],
                                batch["t_out"][sel]], axis=1)
                self.new[x.name].append(rec)
                self.interval[x.name].append(rec)
                self.all[x.name].append(rec)

    def sample(self, values: dict, now) -> None:
        # the removal log was drained by the outlet accounting, which samples first
        for x in self.sensors:
            new = self.interval[x.name]
            recs = np.concatenate(new) if new else np.empty((0, 3))
            self.interval[x.name] = []
            count = float(len(recs))     # a "total" series: sensors/pooling.py pools it
            if now.pooled_interval > 0.0:
                # a short sample: its statistics over the records of this interval and the one
                # before it (sensors/pooling.py), as its count is
                every = self.records(x.name)
                start = now.time - now.interval - now.pooled_interval
                recs = every[every[:, 2] > start + 1e-12 * max(1.0, abs(start))]
            t = recs[:, 2] - recs[:, 1]
            p = f"sensors/{x.name}/"
            values[p + "count"] = count
            if len(t):
                values[p + "mean"] = float(np.mean(t))
                values[p + "median"], values[p + "p10"], values[p + "p90"] = (
                    float(v) for v in np.percentile(t, [50, 10, 90]))
            else:
                for k in ("mean", "median", "p10", "p90"):
                    values[p + k] = math.nan

    def pop_new(self) -> dict[str, np.ndarray]:
        """Records (id, t_in, t_out) completed since the last call, per sensor (for the
        results file)."""
        out = {}
        for name, parts in self.new.items():
            if parts:
                out[name] = np.concatenate(parts)
            self.new[name] = []
        return out

    def records(self, name: str) -> np.ndarray:
        """(id, t_in, t_out) of every particle that completed the sensor's path so far."""
        parts = self.all[name]
        return np.concatenate(parts) if parts else np.empty((0, 3))

    def state_dict(self) -> dict:
        return {f"residence:{name}": self.records(name) for name in self.all}

    def load_state_dict(self, d: dict):
        for name in self.all:
            rec = np.asarray(d.get(f"residence:{name}", np.empty((0, 3))), float).reshape(-1, 3)
            self.all[name] = [rec] if len(rec) else []
            self.new[name] = []
            self.interval[name] = []
