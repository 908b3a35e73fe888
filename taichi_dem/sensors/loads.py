"""Loads on what the particles touch: mesh bodies (force, torque about the axis point, axial
torque, angular speed, drive power, heat flow to an isothermal body; means over the output
interval, summed from the contacts by bodies/mesh_contacts.py) and plane walls (force and heat
flow in the last step of the interval, stepper.py)."""
from __future__ import annotations

import math

import numpy as np

from ..engine import transfer


class BodyLoads:
    """/series bodies/<name>/force, torque, axial_torque, angular_speed, power; for an
    isothermal body heat_flow (W, into the body), covered_area (m^2, the area of its triangles
    a particle touches at the sample) and heat_transfer_coefficient (W/(m^2 K)) = heat_flow /
    (covered_area (mean bed temperature - body temperature)), the bed being every particle in
    the scene; NaN while nothing touches or the bed is at the body's temperature."""

    def __init__(self, scene, engine):
        self.scene = scene
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        e = self.engine
        forces, torques, heats = e.mesh.take_loads(e.count)
        hot = [b.temperature is not None for b in self.scene.bodies]
        areas = e.mesh.survey.covered_areas(e.count) if (e.model.wall_conduction and any(hot)) else None
        for k, body in enumerate(self.scene.bodies):
            axis = np.asarray(body.motion.axis_direction, float)
            speed = e.kinematics.speed(k, now.time)
            axial = float(torques[k] @ axis)
            prefix = f"bodies/{body.name}/"
            values[prefix + "force"] = forces[k]
            values[prefix + "torque"] = torques[k]
            values[prefix + "axial_torque"] = axial
            values[prefix + "angular_speed"] = speed
            # the particles' torque resists the turning; the drive supplies -T w
            values[prefix + "power"] = -axial * speed
            if e.model.wall_conduction and body.temperature is not None:
                values[prefix + "heat_flow"] = heats[k]
                values[prefix + "covered_area"] = float(areas[k])
                difference = now.measured.get("mean_temperature", body.temperature) - body.temperature
                coefficient = math.nan
                if areas[k] > 0.0 and difference != 0.0:
                    coefficient = float(heats[k]) / (float(areas[k]) * difference)
                values[prefix + "heat_transfer_coefficient"] = coefficient


class WallLoads:
    """/series walls/<name>/force (N, on the wall) and heat_flow (W, isothermal walls)."""

    def __init__(self, scene, engine):
        self.walls = scene.walls
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        e = self.engine
        if e.model.thermal:
            wf, wq = transfer.read((e.wall_force, e.wall_heat))
        else:
            (wf,), wq = transfer.read((e.wall_force,)), None
        for k, w in enumerate(self.walls):
            values[f"walls/{w.name}/force"] = wf[k].astype(np.float64)
            if wq is not None and e.model.wall_conduction and w.temperature is not None:
                values[f"walls/{w.name}/heat_flow"] = float(wq[k])
