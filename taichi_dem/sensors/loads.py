"""Loads on what the particles touch: mesh bodies (force, torque about the axis point, axial
torque, angular speed, drive power; means over the output interval, summed from the contacts
by bodies/mesh_contacts.py) and plane walls (force in the last step of the interval,
stepper.py). Where the contacts carry heat (Model.heat) each keeps the heat flows it took
(``heat_flows``, W into each body or wall) for the heat transfer's own series
(thermal/wall_heat_flows.py): the sensors name no effect."""
from __future__ import annotations

import numpy as np

from ..engine import transfer


class BodyLoads:
    """/series bodies/<name>/force, torque, axial_torque, angular_speed, power. ``heat_flows``:
    the mean heat flow into each body over the interval (W), None where none is carried."""

    def __init__(self, scene, engine):
        self.scene = scene
        self.engine = engine
        self.heat_flows = None

    def sample(self, values: dict, now) -> None:
        e = self.engine
        forces, torques, heats = e.mesh.take_loads(e.count)
        self.heat_flows = heats
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


class WallLoads:
    """/series walls/<name>/force (N, on the wall). ``heat_flows``: the heat flow into each
    wall in the last step of the interval (W), None where none is carried."""

    def __init__(self, scene, engine):
        self.walls = scene.walls
        self.engine = engine
        self.heat_flows = None

    def sample(self, values: dict, now) -> None:
        e = self.engine
        if e.model.heat:
            wf, self.heat_flows = transfer.read((e.wall_force, e.wall_heat))
        else:
            (wf,) = transfer.read((e.wall_force,))
        for k, w in enumerate(self.walls):
            values[f"walls/{w.name}/force"] = wf[k].astype(np.float64)
