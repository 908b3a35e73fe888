"""The heat flows into isothermal walls and bodies, as series: what the load sensors took
(sensors/loads.py ``heat_flows``) under the names of CONTRACT.md, with each body's covered area
and heat transfer coefficient.

    bodies/<name>/heat_flow                  W into the body, the mean over the interval
    bodies/<name>/covered_area               m^2 of its triangles a particle touches at the sample
    bodies/<name>/heat_transfer_coefficient  W/(m^2 K) = heat_flow / (covered_area (T_bed - T_body)),
                                             T_bed the mean temperature of every particle; NaN while
                                             nothing touches or the bed is at the body's temperature
    walls/<name>/heat_flow                   W into the wall in the last step of the interval

Written for the bodies and walls that have a temperature, where wall conduction is on
(Model.heats_walls); sampled after the load sensors and before the energy balance, which
integrates them.
"""
from __future__ import annotations

import math


class WallHeatFlows:
    """The heat series of the isothermal bodies and walls of ``sim`` (module docstring)."""

    def __init__(self, sim):
        self.sim = sim

    def sample(self, values: dict, now) -> None:
        sim = self.sim
        e, scene = sim.engine, sim.scene
        if not e.model.heats_walls:
            return
        bodies, walls = sim.sensors.get("bodies"), sim.sensors.get("walls")
        hot = [b.temperature is not None for b in scene.bodies]
        if bodies is not None and bodies.heat_flows is not None and any(hot):
            heats = bodies.heat_flows
            areas = e.mesh.survey.covered_areas(e.count)
            bed = now.measured.get("mean_temperature")
            for k, body in enumerate(scene.bodies):
                if body.temperature is None:
                    continue
                prefix = f"bodies/{body.name}/"
                values[prefix + "heat_flow"] = heats[k]
                values[prefix + "covered_area"] = float(areas[k])
                difference = (bed if bed is not None else body.temperature) - body.temperature
                coefficient = math.nan
                if areas[k] > 0.0 and difference != 0.0:
                    coefficient = float(heats[k]) / (float(areas[k]) * difference)
                values[prefix + "heat_transfer_coefficient"] = coefficient
        if walls is not None and walls.heat_flows is not None:
            for k, w in enumerate(scene.walls):
                if w.temperature is not None:
                    values[f"walls/{w.name}/heat_flow"] = float(walls.heat_flows[k])
