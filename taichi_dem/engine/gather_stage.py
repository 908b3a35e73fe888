"""The gather stage of a step (stepper.py): each particle adds its partners' shares (through
the mirror index, or its sums of the serial mode and of each worker's copy in order), runs the
contact law on its plane walls (contacts/planes.py) and mesh triangles
(bodies/mesh_contacts.py), then the particle effects, the integrate stage (temperature,
drying) and the second half kick; within a run of steps it goes on with the next step's drift.
Built once per pair list by ``GatherStage``."""
import taichi as ti

from ..effects.base import particle_load


def make_take_scattered(s, pool, pair_heat: bool):
    """A ti.func (i, scatter) -> (force N, torque N m, heat W, conductance W/K): what the
    owners added to particle i's sums (serial mode: ``scatter`` = 1; the workers: ``scatter``
    copies, added in order), which it clears; zeros when ``scatter`` is 0 (the mirror pass)."""
    copy_force, copy_torque = pool.copy_force, pool.copy_torque
    copy_heat, copy_conductance = pool.copy_heat, pool.copy_conductance
    vec0 = ti.Vector([0.0, 0.0, 0.0])

    @ti.func
    def take_scattered(i, scatter: ti.template()):
        scattered_force = vec0
        scattered_torque = vec0
        scattered_heat = 0.0
        scattered_conductance = 0.0
        if ti.static(scatter > 0):
            scattered_force = s.scattered_force[i]
            scattered_torque = s.scattered_torque[i]
            s.scattered_force[i] = vec0
            s.scattered_torque[i] = vec0
            for c in ti.static(range(scatter - 1)):
                scattered_force = scattered_force + copy_force[c, i]
                scattered_torque = scattered_torque + copy_torque[c, i]
                copy_force[c, i] = vec0
                copy_torque[c, i] = vec0
            if ti.static(pair_heat):
                scattered_heat = s.scattered_heat[i]
                scattered_conductance = s.scattered_conductance[i]
                s.scattered_heat[i] = 0.0
                s.scattered_conductance[i] = 0.0
                for c in ti.static(range(scatter - 1)):
                    scattered_heat = scattered_heat + copy_heat[c, i]
                    scattered_conductance = scattered_conductance + copy_conductance[c, i]
                    copy_heat[c, i] = 0.0
                    copy_conductance[c, i] = 0.0
        return scattered_force, scattered_torque, scattered_heat, scattered_conductance

    return take_scattered


class GatherStage:
    """The gather's ti.func ``gather_particle(i, dt, record, then_drift, t_next, scatter)``
    and its kernel ``gather(n, dt, record, then_drift, t_next, serial_loops)``."""

    def __init__(self, e, p, conducted_of, plane_contacts, mesh_contacts):
        """``e`` the Engine, ``p`` its PairState; ``plane_contacts`` and ``mesh_contacts``
        the contact kinds' ti.funcs (None where the scene has none)."""
        s, model = e.state, e.model
        real = model.real
        ctx = e.context
        pair_heat = model.pair_heat
        heat_carried = model.heat
        n_walls = len(model.scene.walls)
        has_mesh = mesh_contacts is not None
        holding = e.holding                  # held particles (engine/holding.py)
        holds, particle_moves = holding.any, holding.moves
        core_internal = holding.carried
        # carried by a body's frame: what that body supplies to carry a held particle
        book_carried_load = holding.carried_load
        Load = particle_load(real)
        particle_effects = tuple(x.particle_func(ctx) for x in model.particle_effects)
        # the updates of a particle's own state from its load at the step's dt (its
        # temperature and moisture from the heat; a particle effect's booking of what it
        # gave), in step order
        integrators = tuple(f for f in (x.integrate_func(ctx) for x in model.effect_list)
                            if f is not None)
        drift_particle = e.drift_particle
        pool = e.worker_pool
        take_scattered = make_take_scattered(s, pool, pair_heat)
        vec0 = ti.Vector([0.0, 0.0, 0.0])

        @ti.func
        def gather_particle(i, dt, record, then_drift, t_next, scatter: ti.template()):
            """The rest of particle i's step: its partners' shares through the mirror index
            (``scatter`` > 0: from its sums of copies 0 .. scatter - 1, added in that order,
            which it clears - add_partner_share), its plane walls and
            mesh triangles, the particle effects, the integrate stage and the second half kick;
            ``then_drift``: the next step's drift to ``t_next`` too. A particle removed since
            the last rebuild is parked and inert."""
            scattered_force, scattered_torque, scattered_heat, scattered_conductance = \
                take_scattered(i, scatter)
            if s.alive[i] != 0:
                force = s.owned_force[i]
                torque = s.owned_torque[i]
                integrates = True
                if ti.static(holds):
                    integrates = particle_moves(i)         # held or carried: not integrated
                heat = 0.0           # W into the particle
                conductance = 0.0    # W/K, for the stability check
                if ti.static(heat_carried):
                    heat = s.owned_heat[i]
                    conductance = s.conductance[i]
                if ti.static(scatter > 0):
                    # (a held particle's sums too: a carried one's from its active partners
                    # only, booked on the frame's body below; its heat from every partner)
                    force += scattered_force
                    torque += scattered_torque
                    if ti.static(pair_heat):
                        heat += scattered_heat
                        conductance += scattered_conductance
                elif integrates:
                    # one pass over the partners' entries for their shares of force and heat
                    for k in range(s.row_start[i] + s.row_owned[i], s.row_start[i] + s.row_count[i]):
                        m = p.mirror[k]
                        if m >= 0:
                            contact = p.contact[m]
                            if contact == 1:          # touching (2: near, heat only)
                                force += p.partner_force[m]
                                torque += p.partner_torque[m]
                            if ti.static(pair_heat):
                                if contact != 0:
                                    heat += p.partner_heat[m]
                                    conductance += p.pair_conductance[m]
                else:
                    if ti.static(core_internal):
                        # carried by the frame's body: only the shares of active partners (the
                        # core's inner contacts cancel in the load booked below)
                        for k in range(s.row_start[i] + s.row_owned[i], s.row_start[i] + s.row_count[i]):
                            m = p.mirror[k]
                            if m >= 0:
                                if p.contact[m] == 1 and particle_moves(p.neighbour[k]):
                                    force += p.partner_force[m]
                                    torque += p.partner_torque[m]
                    if ti.static(pair_heat):
                        # held or carried, it still conducts
                        for k in range(s.row_start[i] + s.row_owned[i], s.row_start[i] + s.row_count[i]):
                            m = p.mirror[k]
                            if m >= 0:
                                if p.contact[m] != 0:
                                    heat += p.partner_heat[m]
                                    conductance += p.pair_conductance[m]
                inv_m = s.inverse_mass[i]
                if ti.static(n_walls > 0):
                    # plane walls: the contact law on each particle-plane contact
                    force, torque, heat, conductance = plane_contacts(
                        i, dt, record, force, torque, heat, conductance)
                if ti.static(has_mesh):
                    if inv_m > 0.0:
                        mesh_force, mesh_torque, mesh_heat, mesh_conductance = mesh_contacts(
                            i, s.position[i], s.velocity[i], s.angular_velocity[i], s.radius[i],
                            s.mass[i], inv_m, s.inverse_inertia[i], s.acceleration[i],
                            s.material[i], conducted_of(i), dt)
                        force += mesh_force
                        torque += mesh_torque
                        heat += mesh_heat
                        conductance += mesh_conductance
                # the particle effects: gravity, convection, plug-flow gas, radiation
                # touching: a contact pushes on it, or it is held at rest in a packing
                touching = 0
                if force.norm_sqr() > 0.0:
                    touching = 1
                if ti.static(holds):
                    if not integrates:
                        touching = 1
                load = Load(acceleration=vec0, heat=heat, conductance=conductance,
                            touching=touching)
                for effect in ti.static(particle_effects):
                    load = effect(i, load)
                if s.alive[i] != 0:
                    for integrate in ti.static(integrators):
                        integrate(i, load, dt)
                if ti.static(core_internal):
                    if inv_m > 0.0 and s.alive[i] != 0 and not integrates:
                        book_carried_load(i, force, torque, load.acceleration)
                if inv_m > 0.0 and s.alive[i] != 0 and integrates:
                    a = force * inv_m + load.acceleration
                    alpha = torque * s.inverse_inertia[i]
                    s.acceleration[i] = a
                    s.angular_acceleration[i] = alpha
                    # (``a = a + b``: an augmented assignment to a field is an atomic add in a
                    # parallel loop, which Taichi turns back into a plain one only where the
                    # index is the loop's own - not on the workers' inner loops)
                    s.velocity[i] = s.velocity[i] + 0.5 * dt * a
                    s.angular_velocity[i] = s.angular_velocity[i] + 0.5 * dt * alpha
                if then_drift != 0:
                    # the next step's first half, fused here to save a pass over the particles
                    drift_particle(i, dt, t_next)

        @ti.kernel
        def gather(n: ti.i32, dt: real, record: ti.i32, then_drift: ti.i32, t_next: ti.f64,
                   serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                gather_particle(i, dt, record, then_drift, t_next,
                                ti.static(1 if serial_loops else 0))
        self.gather_particle = gather_particle
        self.gather = gather
