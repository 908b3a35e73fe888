"""Plane walls: the contact law on each particle-plane contact, in the particle stage.

A plane wall is a point, an outward normal and a material (scene [[walls]]); an isothermal
wall (``temperature`` with wall conduction on) also exchanges heat. Its tangential and rolling
history lives per (particle, wall) slot; the loads on the walls are booked when a step records
them (the last step of an ``advance``: the walls' force N and heat W, for the sensors).

The walls are fields read in a loop, not constants unrolled per wall: the contact law is
compiled once whatever the number of walls (a box of six walls compiled six copies of it), and
scenes that differ only in where their walls are share their compiled kernels."""

import numpy as np
import taichi as ti



class PlaneWalls:
    """The plane walls of one engine as device fields: ``point`` m, ``normal`` (unit),
    ``material`` (index), ``temperature`` K (-1: the wall conducts no heat)."""

    def __init__(self, walls, material_index, wall_conduction: bool, real, tree):
        self.count = len(walls)
        n = max(self.count, 1)
        self.point = tree.add("wall_point", real, n, vector=True)
        self.normal = tree.add("wall_normal", real, n, vector=True)
        self.material = tree.add("wall_material", ti.i32, n)
        self.temperature = tree.add("wall_temperature", real, n)
        self.conducts = wall_conduction and any(w.temperature is not None for w in walls)
        self._host = (np.array([w.point for w in walls] or [[0.0] * 3], np.float64),
                      np.array([w.normal for w in walls] or [[0.0, 0.0, 1.0]], np.float64),
                      np.array([material_index(w.material) for w in walls] or [0], np.int32),
                      np.array([w.temperature if (w.temperature is not None and wall_conduction)
                                else -1.0 for w in walls] or [-1.0], np.float64))

    def writes(self) -> list:
        """(field, host array) pairs that fill the walls' fields (engine/transfer.write)."""
        npf = np.float64 if self.point.dtype == ti.f64 else np.float32
        point, normal, material, temperature = self._host
        return [(self.point, point.astype(npf)), (self.normal, normal.astype(npf)),
                (self.material, material), (self.temperature, temperature.astype(npf))]


def make_plane_contacts(state, walls: PlaneWalls, sphere_surface, plane_law, wall_history,
                        wall_force, wall_heat, thermal: bool, temperature_of,
                        margin: float = 0.0):
    """A ti.func ``plane_contacts(i, dt, record, force, torque, heat, conductance)`` -> the
    four sums (N, N m, W, W/K) with particle i's plane-wall contacts added, in wall order.
    ``record`` != 0: book the walls' loads. ``margin``: the contact margin (a fraction of the
    radius) within which a wall not touched is still handed to the law (heat through the gas
    near it; contacts/law.margin_fraction of kind "plane")."""
    s = state
    n_walls = walls.count
    conducts = thermal and walls.conducts
    vec0 = ti.Vector([0.0, 0.0, 0.0])
    # positions with residuals (engine/precision.py)
    split = "position_residual" in state.spec

    @ti.func
    def plane_contacts(i, dt, record, force, torque, heat, conductance):
        xi, vi, wi, ri, mi = s.position[i], s.velocity[i], s.angular_velocity[i], s.radius[i], s.material[i]
        inv_m = s.inverse_mass[i]
        temperature_i = temperature_of(i)
        residual = ti.Vector([0.0, 0.0, 0.0])
        if ti.static(split):
            residual = s.position_residual[i]
        for w in range(n_walls):
            wall_normal = walls.normal[w]
            overlap = ri - (xi - walls.point[w]).dot(wall_normal)
            if ti.static(split):
                # f32 far from the origin (engine/precision.py)
                overlap -= residual.dot(wall_normal)
            # most particles are far from most walls: only the history is cleared there, and
            # the contact record and the law are built for the walls within reach only (with
            # the walls read in a loop, not unrolled as constants, that is what keeps the
            # step as fast: BENCHMARKS.md "Stop 24")
            history = wall_history.empty()
            if overlap > -ti.static(margin) * ri:
                wall_temperature = walls.temperature[w]
                isothermal = 0
                if ti.static(conducts):
                    if wall_temperature >= 0.0:
                        isothermal = 1
                c = sphere_surface(
                    wall_normal, overlap, ri, vi, wi,
                    s.acceleration[i], s.mass[i], inv_m, s.inverse_inertia[i], mi,
                    walls.material[w], vec0, vec0, wall_temperature - temperature_i, isothermal)
                c.particle = i
                history = wall_history.load(ti.Vector([i, w]))
                out, history = plane_law(c, history, dt)
                if ti.static(conducts):
                    if isothermal != 0:
                        heat += out.heat
                        conductance += out.conductance
                        if record != 0:
                            wall_heat[w] -= out.heat
                if c.normal_overlap > 0.0 and inv_m > 0.0:
                    force += out.force
                    torque += out.torque_i
                    if record != 0:
                        wall_force[w] -= out.force
                else:
                    history = wall_history.empty()     # no spring to carry
            wall_history.store(ti.Vector([i, w]), history)
        return force, torque, heat, conductance

    return plane_contacts
