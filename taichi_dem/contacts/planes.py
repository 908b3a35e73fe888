"""Plane walls: the contact law on each particle-plane contact, in the particle stage.

A plane wall is a point, an outward normal and a material (scene [[walls]]); an isothermal
wall (``temperature`` with wall conduction on) also exchanges heat. Its tangential and rolling
history lives per (particle, wall) slot; the loads on the walls are booked when a step records
them (the last step of an ``advance``: the walls' force N and heat W, for the sensors)."""

import taichi as ti


def make_plane_contacts(state, walls, wall_temperature, sphere_surface, plane_law,
                        wall_history, wall_force, wall_heat, thermal: bool, temperature_of):
    """A ti.func ``plane_contacts(i, dt, record, force, torque, heat, conductance)`` -> the
    four sums (N, N m, W, W/K) with particle i's plane-wall contacts added, in wall order.
    ``walls``: ((point m, normal, material index), ...); ``wall_temperature``: K per wall,
    -1 where the wall conducts no heat; ``record`` != 0: book the walls' loads."""
    s = state
    n_walls = len(walls)
    vec0 = ti.Vector([0.0, 0.0, 0.0])

    @ti.func
    def plane_contacts(i, dt, record, force, torque, heat, conductance):
        xi, vi, wi, ri, mi = s.position[i], s.velocity[i], s.angular_velocity[i], s.radius[i], s.material[i]
        inv_m = s.inverse_mass[i]
        temperature_i = temperature_of(i)
        for w in ti.static(range(n_walls)):
            wall_point = ti.Vector(walls[w][0])
            wall_normal = ti.Vector(walls[w][1])
            isothermal = ti.static(wall_temperature[w] >= 0.0)
            c = sphere_surface(
                wall_normal, ri - (xi - wall_point).dot(wall_normal), ri, vi, wi,
                s.acceleration[i], s.mass[i], inv_m, s.inverse_inertia[i], mi,
                ti.static(walls[w][2]), vec0, vec0,
                ti.static(wall_temperature[w]) - temperature_i,
                ti.static(1 if isothermal else 0))
            c.particle = i
            history = wall_history.load(ti.Vector([i, w]))
            out, history = plane_law(c, history, dt)
            if ti.static(thermal and isothermal):
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
