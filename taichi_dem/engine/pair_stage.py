"""The pair stage of a step (stepper.py): each particle's owned neighbour entries, their
contact geometry (contacts/geometry.py) and the contact law (contacts/law.py) composed from
the enabled effects; the owner sums its own share, the partner's share is stored at the entry
(no atomics), or in the serial mode and on the workers added to the partner's sums of one copy
(``share_adder``). Built once per pair list by ``make_pair_stage``."""
import taichi as ti

from ..contacts.law import make_contact_law


def make_conducted_of(s, conducted_field: "str | None"):
    """A ti.func (i) -> particle i's value of the field whose differences drive the contacts'
    heat (Model.conducted_field: the temperature, K; 0 where the contacts carry no heat)."""
    has_field = conducted_field is not None
    conducted = getattr(s, conducted_field) if has_field else None

    @ti.func
    def conducted_of(i):
        t = 0.0 * s.radius[i]
        if ti.static(has_field):
            t = conducted[i]
        return t
    return conducted_of


def make_share_adder(extra_copies: int):
    """``share_adder(first, second, copies_of_first, copies_of_second)`` (below), for a
    worker pool with ``extra_copies`` copies of the sums beyond the first."""
    def share_adder(first, second, copies_of_first, copies_of_second):
        """A ti.func (copy, j, a, b) adding a pair's partner share - a to ``first``, b to
        ``second`` at partner j - in copy ``copy`` of the sums: 0 the serial mode's
        ``scattered_*``, w > 0 worker w's (only that worker writes it). (``x = x + a``: an
        augmented assignment would be an atomic add.)"""
        @ti.func
        def add(copy, j, a, b):
            if ti.static(extra_copies > 0):
                if copy == 0:
                    first[j] = first[j] + a
                    second[j] = second[j] + b
                else:
                    copies_of_first[copy - 1, j] = copies_of_first[copy - 1, j] + a
                    copies_of_second[copy - 1, j] = copies_of_second[copy - 1, j] + b
            else:
                first[j] = first[j] + a
                second[j] = second[j] + b
        return add
    return share_adder


def make_pair_contact(s, geometry, pair_margin: float, conducted_of):
    """A ti.func building the Contact (contacts/geometry.py) of particle i with j."""
    _, _, sphere_sphere_gap, with_motion = geometry

    @ti.func
    def pair_contact(touching, d, distance_sq, ri, vi, wi, ai, inv_mi, inv_ii, mi, j,
                     conducted_i):
        """The Contact of particle i (its state passed in) with particle j (``d`` = x_i -
        x_j, m): the geometry, and the motion when ``touching``. A pair within a heat
        effect's margin but apart needs no more, and with the gas gap on such pairs are as
        common as touching ones: its partner's motion is not loaded."""
        c = sphere_sphere_gap(d, distance_sq, ri, s.radius[j], mi, s.material[j],
                              conducted_i, conducted_of(j))
        if ti.static(pair_margin > 0.0):
            if touching:
                c = with_motion(c, vi, s.velocity[j], wi, s.angular_velocity[j], ai,
                                s.acceleration[j], inv_mi, s.inverse_mass[j], inv_ii,
                                s.inverse_inertia[j])
        else:
            c = with_motion(c, vi, s.velocity[j], wi, s.angular_velocity[j], ai,
                            s.acceleration[j], inv_mi, s.inverse_mass[j], inv_ii,
                            s.inverse_inertia[j])
        return c
    return pair_contact


def make_frozen_pair_heat(p, conducted_of, add_partner_heat):
    """A ti.func (k, j, conducted_i, scatter, copy) -> (heat W, conductance W/K) into the
    owner of entry k from partner j, for a frozen pair of two held particles (engine/
    holding.py): it still conducts, through the conductance kept at the entry at the last
    rebuild, at today's temperature difference. The partner's share is added to its sums
    (``scatter``: copy ``copy``) or stored at the entry; (0, 0) where the pair is open."""
    @ti.func
    def frozen_pair_heat(k, j, conducted_i, scatter: ti.template(), copy):
        q = 0.0 * conducted_i
        h = 0.0 * conducted_i
        if p.contact[k] != 0:
            h = p.pair_conductance[k]
            q = h * (conducted_of(j) - conducted_i)
            if ti.static(scatter):
                add_partner_heat(copy, j, -q, h)
            else:
                p.partner_heat[k] = -q
        return q, h
    return frozen_pair_heat


class PairStage:
    """The pair stage's ti.func ``pair_particle(i, dt, full, scatter, copy)`` and its kernel
    ``pair_forces(n, dt, full, serial_loops)``, with the shares' adders the gather reads."""

    def __init__(self, e, p, geometry, pair_history, conducted_of, shields,
                 before_pairs=None):
        """``e`` the Engine, ``p`` its PairState; ``geometry`` contacts/geometry.py's
        make_geometry; ``pair_history`` the history's load/store at the entries;
        ``shields`` (i, j, d) -> whether a mesh plate lies between them, or None;
        ``before_pairs`` (i): run for every particle before any pair (or None)."""
        s, model, real, minimum_image = e.state, e.model, e.model.real, e.minimum_image
        pair_law = make_contact_law(model.effect_list, "pair", real, e.context)
        # a pair is handed to the law while its gap is below the margin an effect asks for
        pair_margin = model.pair_margin
        pair_heat, heat = model.pair_heat, model.heat
        has_mesh, holding = shields is not None, e.holding
        holds, particle_moves = holding.any, holding.moves
        # held particles carried by a body's frame (engine/holding.py): what holds the frozen core
        # is a load on that body (the gather); its inner contacts cancel there: left out of both
        core_internal = holding.carried
        split, has_before_pairs = model.split_positions, before_pairs is not None
        vec0 = ti.Vector([0.0, 0.0, 0.0])
        pair_contact = make_pair_contact(s, geometry, pair_margin, conducted_of)
        pool = e.worker_pool
        share_adder = make_share_adder(max(pool.copies - 1, 0))
        # force (N) and torque (N m); heat flow (W) and conductance (W/K)
        add_partner_share = share_adder(s.scattered_force, s.scattered_torque, pool.copy_force,
                                        pool.copy_torque)
        add_partner_heat = (share_adder(s.scattered_heat, s.scattered_conductance,
                                        pool.copy_heat, pool.copy_conductance)
                            if heat else None)
        frozen_pair_heat = (make_frozen_pair_heat(p, conducted_of, add_partner_heat)
                            if pair_heat else None)

        @ti.func
        def pair_particle(i, dt, full, scatter: ti.template(), copy):
            """The owned contacts of particle i in one step: their geometry, the contact law,
            the owner's sums and the partner's shares - stored at the entry (no atomics), or
            with ``scatter`` added to the partner's sums of copy ``copy`` (add_partner_share:
            one thread, or worker ``copy`` alone writing that copy). ``full`` = 1 (the step
            of a rebuild): every pair; 0: pairs of two held particles (engine/holding.py) keep
            their force, torque and history (their heat flows through the kept conductance)."""
            xi, vi, wi, ai = s.position[i], s.velocity[i], s.angular_velocity[i], s.acceleration[i]
            ri, inv_mi, inv_ii, mi = s.radius[i], s.inverse_mass[i], s.inverse_inertia[i], s.material[i]
            conducted_i = conducted_of(i)
            residual_i = vec0
            if ti.static(split):
                residual_i = s.position_residual[i]
            owned_force = vec0
            owned_torque = vec0
            owned_heat = 0.0
            owned_conductance = 0.0
            frozen_i = False
            if ti.static(holds):
                frozen_i = full == 0 and not particle_moves(i)
            inactive_i = False
            if ti.static(core_internal):
                inactive_i = not particle_moves(i)
            for k in range(s.row_start[i], s.row_start[i] + s.row_owned[i]):
                j = p.neighbour[k]
                if ti.static(holds):
                    frozen = False
                    if frozen_i:             # (``and`` evaluates both sides: a read per pair)
                        frozen = not particle_moves(j)
                    if frozen:
                        # both held: the contact is frozen as it was at the rebuild (neither
                        # particle is integrated, so its force goes to neither side)
                        if ti.static(pair_heat):
                            q, h = frozen_pair_heat(k, j, conducted_i, scatter, copy)
                            owned_heat += q
                            owned_conductance += h
                        continue
                d = minimum_image(xi - s.position[j])
                if ti.static(split):
                    # x_i - x_j of near particles is exact in f32: the residuals make it precise
                    d += residual_i - s.position_residual[j]
                rj = s.radius[j]
                distance_sq = d.dot(d)
                reach = ri + rj
                if ti.static(pair_margin > 0.0):
                    reach += ti.static(pair_margin) * ti.max(ri, rj)
                within = distance_sq < reach * reach and distance_sq > 0.0
                if ti.static(has_mesh):
                    if within:
                        within = not shields(i, j, d)
                if within:
                    # a pair within the margin but apart (heat only): its geometry without the
                    # motion; touching: the whole contact
                    touching = True
                    if ti.static(pair_margin > 0.0):
                        touching = distance_sq < (ri + rj) * (ri + rj)
                    c = pair_contact(touching, d, distance_sq, ri, vi, wi, ai, inv_mi, inv_ii, mi, j,
                                     conducted_i)
                    history = pair_history.empty()
                    if touching:
                        history = pair_history.load(k)
                    out, history = pair_law(c, history, dt)
                    if ti.static(pair_heat):
                        owned_heat += out.heat
                        owned_conductance += out.conductance
                        if ti.static(scatter):
                            add_partner_heat(copy, j, -out.heat, out.conductance)
                            if ti.static(holds):
                                # (what a frozen pair conducts through until the next rebuild)
                                p.pair_conductance[k] = out.conductance
                        else:
                            p.partner_heat[k] = -out.heat
                            p.pair_conductance[k] = out.conductance
                    if c.normal_overlap > 0.0:
                        inner = False
                        if ti.static(core_internal):
                            if inactive_i:
                                inner = not particle_moves(j)
                        if not inner:
                            owned_force += out.force
                            owned_torque += out.torque_i
                        if ti.static(scatter):
                            # (an inner pair of a carried core goes to neither side's sum: the
                            # gather books a carried particle's load from active partners only)
                            if not inner:
                                add_partner_share(copy, j, -out.force, out.torque_j)
                        else:
                            p.partner_force[k] = -out.force
                            p.partner_torque[k] = out.torque_j
                        pair_history.store(k, history)
                        p.contact[k] = ti.u8(1)
                    else:
                        # near, not touching: no force (the gather reads the partner's share
                        # of touching pairs only) and no spring to carry
                        if p.contact[k] == 1:
                            pair_history.clear(k)
                        p.contact[k] = ti.u8(2)
                elif p.contact[k] != 0:
                    # the contact opened: its history is discarded
                    p.contact[k] = ti.u8(0)
                    pair_history.clear(k)
            s.owned_force[i] = owned_force
            s.owned_torque[i] = owned_torque
            if ti.static(heat):
                s.owned_heat[i] = owned_heat
                s.conductance[i] = owned_conductance

        @ti.kernel
        def pair_forces(n: ti.i32, dt: real, full: ti.i32, serial_loops: ti.template()):
            """pair_particle over the particles (before_pairs first); ``serial_loops``: one thread."""
            if ti.static(has_before_pairs):
                ti.loop_config(serialize=serial_loops)
                for i in range(n):
                    before_pairs(i)
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                pair_particle(i, dt, full, ti.static(serial_loops), 0)
        self.pair_particle = pair_particle
        self.pair_forces = pair_forces
