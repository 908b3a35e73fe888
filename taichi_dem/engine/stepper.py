"""What *advances* the simulation: the step, composed only of the effects the scene enables.

One step (velocity Verlet):
  drift:  v += a dt/2, w += alpha dt/2, x += v dt; wrap periodic faces; mark particles that
          left the domain; flag a rebuild if any moved more than half the skin
  rebuild neighbours when flagged (broadphase.py)
  pair:   one kernel over owned neighbour entries: the contact geometry once
          (contacts/geometry.py), then the contact law (contacts/law.py), the enabled contact
          effects unrolled on it; the owner sums its own share, the partner's share is stored
          at the entry - no atomics (serial mode: added to the partner's sums directly; the
          worker threads: added to the partner's sums in the worker's own copy)
  cell:   effects with a per-cell stage (the plug-flow gas marching cell by cell)
  gather: each particle adds its partners' shares through the mirror index (in the serial
          mode the owners have added them to its scattered_* sums already; on the workers
          it adds its sums of each copy in order), runs the same
          contact law on its plane walls and mesh triangles, then the particle effects
          (gravity, convection, gas, radiation), the integrate stage (temperature, drying) and
          the second half kick v += a dt/2; within a run of steps it goes on with the next
          step's drift (one pass over the particles less)
The effects (effects/, thermal/effects.py) declare their stage, fields and tables; those not
enabled are neither allocated nor compiled (``ti.static``). The engine never imports thermal/.

The step exists once, as the ti.funcs ``drift_particle``, ``pair_particle``,
``gather_particle`` and ``begin_step``; its drivers (drivers.py) run them one launch per stage,
as runs of steps on one thread (the serial mode, below ``parallel_from`` particles), or as runs
on the persistent worker threads (workers.py). The modes add a particle's partners' shares in
different orders - the same physics to round-off; each is deterministic (the workers' for a
given number of threads). The model the engine is built from is model.py; the particles are
created by insertion.py; the neighbour lists are broadphase.py's; the sums at a sample are
measure.py's.
"""

import numpy as np
import taichi as ti

from . import backend, transfer
from .broadphase import Broadphase
from .model import Model
from .precision import make_split_add
from .insertion import Insertion
from .measure import Measure
from ..contacts.geometry import contact_types, make_geometry
from ..contacts.history import history_members, make_history_io
from ..contacts.law import make_contact_law, margin_fraction
from ..contacts.planes import PlaneWalls, make_plane_contacts
from ..effects.base import EffectContext, particle_load
from .state import FieldTree, Flag, PairState, ParticleState, Reduction, ThermalSum, fit_rows
from . import drivers, tuning
from .tuning import PARALLEL_FROM
from .drift import make_drift
from .values import RuntimeValues
from .workers import WorkerPool, persistent_workers


class Engine:
    """Owns the device state of one simulation and the kernels that advance it."""

    def __init__(self, model: Model, parallel_from: "int | None" = None):
        """``model``: what the simulation is (model.py, frozen); ``parallel_from``: particles
        from which a CPU runs the step's loops on all threads."""
        self.model = model
        scene = model.scene
        tables = model.tables
        real = model.real
        capacity = model.capacity
        # the loop mode of every kernel (serial_switch); updated with the particle count
        self.threads = backend.cpu_threads()
        self.parallel_from = PARALLEL_FROM if parallel_from is None else int(parallel_from)
        self.serial = False
        self.choose_loop_mode(0)

        # several steps per launch in the serial mode (drivers.run_steps), unless some
        # effect's cell stage has no ti.func form
        self.runs = self.threads is not None and all(hasattr(e, "cell_func")
                                                     for e in self.model.cell_effects)
        # the serial mode's pair stage adds partner shares to the partner directly, with no
        # gather through the mirror index (one thread: no race); [mobility] keeps the entries
        # (its frozen pairs re-use their stored shares). The mirror is still built at every
        # rebuild: a checkpoint of a serial run restores into a parallel one (or a GPU)
        self.scatter_ok = model.mobility is None
        self.trees: list[FieldTree] = []
        # scene values the kernels read at run time (values.py): made first, so their place
        # is the same in every simulation; the grid's layout and the skin are read from them
        self.values = RuntimeValues(self.new_tree(), real)
        self.model.grid.bind(self.values)
        self.skin_of = self.values.scalar("skin", self.model.skin)
        # runs of steps on every thread above parallel_from (persistent_workers; off again,
        # for good, if its barrier waits show the threads sharing the cores with other work)
        self.worker_pool = WorkerPool(persistent_workers(self.threads) if self.runs else 0,
                                      capacity, real, self.model.thermal,
                                      copies=self.scatter_ok and tuning.WORKER_COPIES)
        has_planes = any(x.kind == "mass_flow" for x in scene.sensors)
        self.state = ParticleState(capacity, real, len(scene.walls), model.particle_fields,
                                   self.model.contact_fields, thermal=self.model.thermal,
                                   process=bool(scene.factories or scene.outlets))
        self.trees.append(self.state.tree)
        t = self.new_tree()
        m = len(tables.names)
        # the material-pair tables the enabled effects read, under their physics names
        self.table = {name: t.add(name, ti.i32 if values.dtype.kind in "iu" else real, (m, m))
                      for name, values in model.table_values.items()}
        # named slots: Flag (engine/state.py)
        self.flags = t.add("flags", ti.i32, Flag.SIZE)
        self.wall_force = t.add("wall_force", real, max(len(scene.walls), 1), vector=True)
        # the plane walls as fields, read in a loop (contacts/planes.py)
        self.plane_walls = PlaneWalls(scene.walls, tables.index, model.wall_conduction,
                                      real, t)
        self.reduction = t.add("reduction", real, Reduction.SIZE)   # named slots: Reduction
        if self.model.thermal:
            self.wall_heat = t.add("wall_heat", real, max(len(scene.walls), 1))
            # f64 sums over the particles: sum m c T (J), sum m c (J/K), water (kg), dry solid
            # (kg); an f32 sum of m c T at 723 K would round the heat balance away
            self.thermal_sums = t.add("thermal_sums", ti.f64, ThermalSum.SIZE)
        # what the effects see: the model, the values, the tables and the state, read-only
        self.context = EffectContext(model, self.values, self.table, self.state, self)
        for e in self.model.effect_list:
            e.allocate(self.context, t)
        self.process = None
        if scene.factories or scene.outlets or has_planes:
            from ..process.outlets import ProcessDevice
            self.process = ProcessDevice(self, t)
        t.finalize()
        self.removed_batches: list = []    # removal-log entries drained at rebuilds
        self.before_rebuild = None         # host hook (engine) before a rebuild in advance
        # the serial mode rebuilds in one launch (Broadphase.fused_rebuild); False: the
        # separate kernels (tests compare the two)
        self.fused_rebuilds = True
        # the parallel mode on the workers rebuilds on them in one launch
        # (Broadphase.rebuild_on_workers); False: the separate kernels (tests compare the two)
        self.rebuilds_on_workers = True
        npf = np.float64 if real == ti.f64 else np.float32
        transfer.write([(self.table[name], values.astype(np.int32 if values.dtype.kind in "iu"
                                                        else npf))
                        for name, values in model.table_values.items()]
                       + self.plane_walls.writes())
        for e in self.model.effect_list:
            if hasattr(e, "upload"):
                e.upload(self.context)
        if self.gas_stream is not None:
            self.gas_stream.compile()
        self.time = 0.0
        self.pairs: "PairState | None" = None
        self.broadphase = Broadphase(self)
        self.context.attach("broadphase", self.broadphase)
        self.mesh = None
        if scene.bodies:
            from ..bodies.kinematics import BodyKinematics
            from ..bodies.mesh_contacts import MeshContacts
            self.kinematics = BodyKinematics(scene.bodies)
            self.mesh = MeshContacts(self, self.kinematics)
            self.context.attach("mesh", self.mesh)
        if self.model.mobility is not None:
            self.model.mobility.compile(self.context)
        self._compile_particle_kernels()
        self.count = 0                     # slots in use
        self._measure = None               # (measure.py, compiled on first use)
        self.insertion = Insertion(self)

    # what enabled effects hold, for the sensors and the measure kernel (None when absent)
    @property
    def gas_stream(self):
        """The axial plug-flow gas (thermal/plug_flow.py) of the plug-flow effect, or None."""
        e = self.context.effect("plug_flow_convection")
        return e.stream if e is not None else None

    @property
    def evaporated(self):
        """The drying effect's evaporated water, kg since the start (a 1-entry f64 field)."""
        return self.model.effect("drying").evaporated

    @property
    def workers(self) -> int:
        """The persistent worker threads the runs of steps use now (0: none, or they gave
        way; workers.WorkerPool)."""
        return self.worker_pool.workers

    @workers.setter
    def workers(self, count: int):
        self.worker_pool.workers = count      # (0: the parallel kernels from now on)

    def choose_loop_mode(self, n: int) -> bool:
        """Serial loops for ``n`` particles? On a GPU never; on one CPU thread always; else
        below ``parallel_from`` particles, with a band of +-20 % so that a count wandering
        around it does not switch (each mode compiles its own kernels, once)."""
        if self.threads is None:
            serial = False
        elif self.threads == 1:
            serial = True
        elif self.serial:
            serial = n < 1.2 * self.parallel_from
        else:
            serial = n < 0.8 * self.parallel_from
        self.serial = serial
        return serial

    def serial_switch(self, kernel):
        """``kernel`` called with the engine's loop mode (``serial``) as its last argument, a
        ti.template(): its loops run on one thread when it is True (``ti.loop_config``)."""
        def launch(*args):
            return kernel(*args, self.serial)
        launch.kernel = kernel
        return launch

    def new_tree(self) -> FieldTree:
        t = FieldTree()
        self.trees.append(t)
        return t

    def recompile_pair_kernels(self):
        """New kernel objects after arrays they use were reallocated (compiled on first use)."""
        self._compile_pair_kernels(self.pairs)

    def grow_pairs(self, capacity: int):
        """(Re)allocate the pair arrays with room for ``capacity`` entries, keeping the saved
        previous list (old_* arrays) so the history can still be carried."""
        old = self.pairs
        new = PairState(capacity, self.model.real, self.model.contact_fields, self.model.pair_fields)
        if old is not None:
            # the partner ids and every history value the enabled effects keep, by name
            names = ["old_partner_id"] + ["old_" + name for name in self.model.contact_fields]
            saved = transfer.read([getattr(old, name) for name in names])
            transfer.write([(getattr(new, name), fit_rows(values, capacity))
                            for name, values in zip(names, saved)])
            old.destroy()
        self.pairs = new
        self.broadphase.compile_pair_kernels(new)
        self._compile_pair_kernels(new)

    def destroy(self):
        if self.pairs is not None:
            self.pairs.destroy()
        for t in self.trees:
            t.destroy()
        self.trees.clear()
        self.worker_pool.destroy()

    # ------------------------------------------------------------------ kernels
    def _compile_particle_kernels(self):
        self.minimum_image, self.drift_particle, self._drift = make_drift(self)

    def _compile_pair_kernels(self, p: PairState):
        s = self.state
        minimum_image = self.minimum_image
        real = self.model.real
        effects = self.model.effect_list
        # the contact geometry of each kind and the contact law composed from the enabled
        # effects (contacts/): the same law runs on pairs, planes and triangles
        _, sphere_surface, sphere_sphere_gap, with_motion = make_geometry(real, self.model.thermal)
        # the history values the enabled effects keep, and one load/store/clear of them per
        # storage: the neighbour entries and the (particle, plane wall) slots
        members = history_members(effects)
        _, _, History = contact_types(real, members)
        pair_history = make_history_io(History, members,
                                       {m: getattr(p, m + "_history") for m in members})
        pair_law = make_contact_law(effects, "pair", real, self.context)
        plane_law = make_contact_law(effects, "plane", real, self.context)
        # a pair is handed to the law while its gap is below the margin an effect asks for
        pair_margin = self.model.pair_margin
        pair_heat = self.model.pair_heat
        n_walls = len(self.model.scene.walls)
        wall_history = (make_history_io(History, members,
                                        {m: getattr(s, "wall_" + m + "_history") for m in members})
                        if n_walls else None)
        wall_force = self.wall_force
        drift_particle = self.drift_particle
        thermal = self.model.thermal
        wall_heat = self.wall_heat if thermal else None
        mesh_contacts = None
        if self.mesh is not None:
            mesh_contacts = self.mesh.make_particle_contacts(
                make_contact_law(effects, "triangle", real, self.context),
                make_contact_law(effects, "surface", real, self.context), sphere_surface)
        has_mesh = mesh_contacts is not None
        # a plate between two spheres: no pair contact through it
        shields = self.mesh.make_shields() if has_mesh else None
        Load = particle_load(real)
        particle_effects = tuple(e.particle_func(self.context) for e in self.model.particle_effects)
        update_temperature = (self.model.effect("temperature").integrate_func(
                                  self.context, self.model.effect("drying"))
                              if thermal else None)
        vec0 = ti.Vector([0.0, 0.0, 0.0])

        @ti.func
        def temperature_of(i):
            t = 0.0 * s.radius[i]
            if ti.static(thermal):
                t = s.temperature[i]
            return t

        plane_contacts = (make_plane_contacts(s, self.plane_walls, sphere_surface, plane_law,
                                              wall_history, wall_force, wall_heat, thermal,
                                              temperature_of,
                                              margin_fraction(self.model.contact_effects, "plane"))
                          if n_walls else None)

        mobility = self.model.mobility is not None
        active = self.model.mobility.particle_active if mobility else None
        # [mobility] "body_frame": the frozen core is carried by the frame's body, so what holds
        # it there is a load on that body (booked in the gather); its inner contacts cancel in
        # that sum and are left out of both sides
        core_internal = mobility and self.model.mobility_frame >= 0
        # one thread (the serial mode) adds each pair's partner share to the partner directly
        # (Engine.scatter_ok); [mobility]'s frozen and carried pairs read theirs at the entries
        scatter_ok = self.scatter_ok
        split = self.model.split_positions

        @ti.func
        def pair_contact(touching, d, distance_sq, ri, vi, wi, ai, inv_mi, inv_ii, mi, j,
                         temperature_i):
            """The Contact of particle i (its state passed in) with particle j (``d`` = x_i -
            x_j, m): the geometry, and the motion when ``touching``. A pair within a heat
            effect's margin but apart needs no more, and with the gas gap on such pairs are as
            common as touching ones: its partner's motion is not loaded."""
            c = sphere_sphere_gap(d, distance_sq, ri, s.radius[j], mi, s.material[j],
                                  temperature_i, temperature_of(j))
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

        pool = self.worker_pool
        extra_copies = max(pool.copies - 1, 0)
        copy_force, copy_torque = pool.copy_force, pool.copy_torque
        copy_heat, copy_conductance = pool.copy_heat, pool.copy_conductance

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

        # force (N) and torque (N m); heat flow (W) and conductance (W/K)
        add_partner_share = share_adder(s.scattered_force, s.scattered_torque, copy_force,
                                        copy_torque)
        add_partner_heat = (share_adder(s.scattered_heat, s.scattered_conductance, copy_heat,
                                        copy_conductance) if self.model.thermal else None)

        @ti.func
        def pair_particle(i, dt, full, scatter: ti.template(), copy):
            """The owned contacts of particle i in one step: their geometry, the contact law,
            the owner's sums and the partner's shares - stored at the entry (no atomics), or
            with ``scatter`` added to the partner's sums of copy ``copy`` (add_partner_share:
            one thread, or worker ``copy`` alone writing that copy).
            ``full`` = 1 (the step of a rebuild): every pair; 0: [mobility] pairs of two
            inactive particles keep their force, torque and history (their heat flows through
            the kept conductance)."""
            xi, vi, wi, ai = s.position[i], s.velocity[i], s.angular_velocity[i], s.acceleration[i]
            ri, inv_mi, inv_ii, mi = s.radius[i], s.inverse_mass[i], s.inverse_inertia[i], s.material[i]
            temperature_i = temperature_of(i)
            residual_i = vec0
            if ti.static(split):
                residual_i = s.position_residual[i]
            owned_force = vec0
            owned_torque = vec0
            owned_heat = 0.0
            owned_conductance = 0.0
            frozen_i = False
            if ti.static(mobility):
                frozen_i = full == 0 and active[i] == 0
            inactive_i = False
            if ti.static(core_internal):
                inactive_i = active[i] == 0
            for k in range(s.row_start[i], s.row_start[i] + s.row_owned[i]):
                j = p.neighbour[k]
                if ti.static(mobility):
                    if frozen_i and active[j] == 0:
                        # both inactive: the contact is frozen as it was at the rebuild
                        if ti.static(pair_heat):
                            if p.contact[k] != 0:
                                h = p.pair_conductance[k]
                                q = h * (temperature_of(j) - temperature_i)
                                owned_heat += q
                                owned_conductance += h
                                p.partner_heat[k] = -q
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
                                     temperature_i)
                    history = pair_history.empty()
                    if touching:
                        history = pair_history.load(k)
                    out, history = pair_law(c, history, dt)
                    if ti.static(pair_heat):
                        owned_heat += out.heat
                        owned_conductance += out.conductance
                        if ti.static(scatter):
                            add_partner_heat(copy, j, -out.heat, out.conductance)
                        else:
                            p.partner_heat[k] = -out.heat
                            p.pair_conductance[k] = out.conductance
                    if c.normal_overlap > 0.0:
                        inner = False
                        if ti.static(core_internal):
                            inner = inactive_i and active[j] == 0
                        if not inner:
                            owned_force += out.force
                            owned_torque += out.torque_i
                        if ti.static(scatter):
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
            if ti.static(thermal):
                s.owned_heat[i] = owned_heat
                s.conductance[i] = owned_conductance

        @ti.kernel
        def pair_forces(n: ti.i32, dt: real, full: ti.i32, serial_loops: ti.template()):
            """pair_particle over the particles; ``serial_loops``: one thread (Engine.serial)."""
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                pair_particle(i, dt, full, ti.static(serial_loops and scatter_ok), 0)

        # [mobility] "body_frame": what the frame's body supplies to carry an inactive particle
        book_carried_load = self.model.mobility.make_carried_load(self.context) if core_internal else None

        @ti.func
        def gather_particle(i, dt, record, then_drift, t_next, scatter: ti.template()):
            """The rest of particle i's step: its partners' shares through the mirror index
            (``scatter`` > 0: from its sums of copies 0 .. scatter - 1, added in that order,
            which it clears - add_partner_share), its plane walls and
            mesh triangles, the particle effects, the integrate stage and the second half kick;
            ``then_drift``: the next step's drift to ``t_next`` too. A particle removed since
            the last rebuild is parked and inert."""
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
            if s.alive[i] != 0:
                force = s.owned_force[i]
                torque = s.owned_torque[i]
                integrates = True
                if ti.static(mobility):
                    integrates = active[i] != 0      # inactive: held or carried, not integrated
                heat = 0.0           # W into the particle
                conductance = 0.0    # W/K, for the stability check
                if ti.static(thermal):
                    heat = s.owned_heat[i]
                    conductance = s.conductance[i]
                if ti.static(scatter > 0):
                    # (no [mobility] here: every particle integrates)
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
                                if p.contact[m] == 1 and active[p.neighbour[k]] != 0:
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
                            s.material[i], temperature_of(i), dt)
                        force += mesh_force
                        torque += mesh_torque
                        heat += mesh_heat
                        conductance += mesh_conductance
                # the particle effects: gravity, convection, plug-flow gas, radiation
                load = Load(acceleration=vec0, heat=heat, conductance=conductance)
                for effect in ti.static(particle_effects):
                    load = effect(i, load)
                if ti.static(thermal):
                    if s.alive[i] != 0:
                        # explicit update; stable while dt sum(h) / (m c) < 1 (checked per sample)
                        update_temperature(i, load.heat, load.conductance, dt)
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
                                ti.static(1 if (serial_loops and scatter_ok) else 0))

        self._pair_forces = self.serial_switch(pair_forces)
        self._gather = self.serial_switch(gather)

        # runs of steps (serial mode): the cell stage of each effect as a ti.func
        cell_funcs = tuple(e.cell_func(self.context) for e in self.model.cell_effects) if self.runs else ()
        set_frames = self.mesh.set_frames if has_mesh else None
        flags = self.flags
        n_wall_slots = max(n_walls, 1)

        @ti.func
        def begin_step(j, t, last, record_last, full_first, leader):
            """What step j of a run (at ``t``, s; ``last`` of the run) needs before its pair
            stage, done by the thread ``leader`` marks: the wall loads zeroed when this step
            books them, the bodies' frames set. Returns (record, full): whether the step books
            the wall loads, whether it follows a rebuild ([mobility])."""
            record = 0
            if last and record_last != 0:
                record = 1
                if leader:
                    for w in range(n_wall_slots):
                        wall_force[w] = vec0
                        if ti.static(thermal):
                            wall_heat[w] = 0.0
            if ti.static(has_mesh):
                if leader:
                    set_frames(ti.cast(t, real))
            full = 0
            if j == 0:
                full = full_first
            return record, full

        # the step's functions, which every driver runs (drivers.py)
        step = drivers.StepFunctions(
            pair_particle=pair_particle, gather_particle=gather_particle, begin_step=begin_step,
            cell_funcs=cell_funcs, flags=flags, state=s, real=real, scatter_ok=scatter_ok)
        self._run_steps = drivers.compile_run_steps(step)
        self._run_worker_steps = (drivers.compile_run_worker_steps(step, pool) if pool.workers
                                  else None)

    # ------------------------------------------------------------------ driver
    def start(self, n: int) -> int:
        """Build the first neighbour list and the initial accelerations (no time advance)."""
        if self.mesh is not None:
            self.mesh.update_frames(self.time)
        self.choose_loop_mode(n)
        self.flags[Flag.REBUILD] = 0          # (set by the insertion of the initial fill)
        self.count = self.broadphase.rebuild(n)
        if self.model.mobility is not None:
            self.model.mobility.update(self.context, self.count, self.time)
        if self.serial and self.runs:
            # one step of no length in the kernel the runs use (nothing else to compile)
            self._run_steps(self.count, 0.0, self.time, 0.0, 1, 1, 0, 0)
            return self.count
        self._pair_forces(self.count, 0.0, 1)
        for e in self.model.cell_effects:
            e.after_pairs(self.context, self.count, 0.0)
        self._gather(self.count, 0.0, 0, 0, self.time)
        return self.count

    def rebuild(self, n: int):
        """Drop dead particles, re-sort and rebuild the neighbour lists; first the
        ``before_rebuild`` hook, which may insert particles (mid-step: drifted, forces
        pending) so that this rebuild lists them too."""
        if self.before_rebuild is not None:
            self.before_rebuild(self)
            n = self.count
        self.flags[Flag.REBUILD] = 0
        if self.process is not None and self.process.log_enabled:
            batch = self.process.drain()
            if batch is not None:
                self.removed_batches.append(batch)
        self.choose_loop_mode(n)
        self.count = self.broadphase.rebuild(n)
        self.flags[Flag.DEAD_IN_SLOTS] = 0
        if self.model.mobility is not None:
            self.model.mobility.update(self.context, self.count, self.time)

    def advance(self, steps: int, record_last: bool = False):
        """Advance ``steps`` time steps of ``self.model.dt``: in runs of steps per launch in the
        serial mode (``runs``), else two parallel launches per step."""
        if self.serial and self.runs:
            drivers.advance_in_runs(self, steps, record_last)
            return
        pool = self.worker_pool
        if pool.give_way:
            pool.workers = 0
        if pool.workers and self._run_worker_steps is not None:
            drivers.advance_in_runs(self, steps, record_last, on_workers=True)
            return
        drivers.advance_per_stage(self, steps, record_last)

    def measure(self) -> dict:
        """The state's sums at this instant (measure.py): kinetic_energy J, max_speed m/s,
        non_finite; thermal: thermal_energy J, mean_temperature K, thermal_step_ratio;
        drying: mean_moisture kg/kg, evaporated_mass kg."""
        if self._measure is None:
            self._measure = Measure(self)
        return self._measure(self.count)

    @property
    def lost(self) -> int:
        return int(self.flags[Flag.LOST])

    @property
    def alive_count(self) -> int:
        """Particles in the simulation now (slots in use minus those removed since the last
        rebuild)."""
        return self.count - int(self.flags[Flag.DEAD_IN_SLOTS])

    def insert(self, arrays: dict):
        """Put new particles into the slots after the last one in use and flag a rebuild
        (insertion.py: the one way particles are created, the initial fill's too)."""
        self.count = self.insertion.insert(self.count, arrays)

    def occupied(self) -> dict:
        """What the slots in use hold (insertion.Insertion.occupied)."""
        return self.insertion.occupied(self.count)
