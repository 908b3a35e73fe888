"""Loads on what the particles touch: mesh bodies (force, torque about the axis point, axial
torque, angular speed, drive power, heat flow to an isothermal body; means over the output
interval, summed from the contacts by bodies/mesh_contacts.py) and plane walls (force and heat
flow in the last step of the interval, stepper.py)."""
from __future__ import annotations

import numpy as np


class BodyLoads:
    """/series bodies/<name>/force, torque, axial_torque, angular_speed, power, heat_flow."""

    def __init__(self, scene, engine):
        self.scene = scene
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        e = self.engine
        forces, torques, heats = e.mesh.take_loads(e.count)
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
            if e.wall_conduction and body.temperature is not None:
                values[prefix + "heat_flow"] = heats[k]


class WallLoads:
    """/series walls/<name>/force (N, on the wall) and heat_flow (W, isothermal walls)."""

    def __init__(self, scene, engine):
        self.walls = scene.walls
        self.engine = engine

    def sample(self, values: dict, now) -> None:
        e = self.engine
        wf = e.wall_force.to_numpy()
        wq = e.wall_heat.to_numpy() if e.thermal else None
        for k, w in enumerate(self.walls):
            values[f"walls/{w.name}/force"] = wf[k].astype(np.float64)
            if wq is not None and e.wall_conduction and w.temperature is not None:
                values[f"walls/{w.name}/heat_flow"] = float(wq[k])
