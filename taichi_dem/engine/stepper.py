"""What *advances* the simulation: the step, composed only of the effects the scene enables.

One step (velocity Verlet):
  drift:  v += a dt/2, w += alpha dt/2, x += v dt; wrap periodic faces; mark particles that
          left the domain; flag a rebuild if any moved more than half the skin
  rebuild neighbours when flagged (broadphase.py)
  pair:   one kernel over owned neighbour entries computes the contact geometry once and runs
          every enabled pair effect on it (Hertz-Mindlin, rolling friction); the owner sums its
          own share, the partner's share is stored at the entry (only while touching) - no
          atomics
  gas:    (plug-flow gas only, thermal/plug_flow.py) per-cell sums of the particles' h A and
          h A T, then the gas marches from its inlet cell by cell
  gather: each particle adds its partners' shares through the mirror index, adds plane walls and gravity, and completes the kick: v += a dt/2; within a
          run of steps it goes on with the next step's drift (one pass over the particles less);
          thermal: adds convection, radiation, then updates T (and dries, thermal/moisture.py)
Effects not enabled are excluded with ``ti.static`` and so never compiled.
"""

import numpy as np
import taichi as ti

from .broadphase import Broadphase, GridSpec
from ..effects import effect_names
from ..effects.hertz_mindlin import contact_force
from ..effects import rolling
from thermal import convection as gas_convection
from thermal.conduction import contact_conductance
from thermal import moisture as drying
from thermal import radiation as radiative
from thermal.precision import make_compensated_add
from thermal import gas_gap
from ..setup.pair_tables import ROLLING_CONSTANT_TORQUE, ROLLING_EPSD, PairTables
from .state import FieldTree, Flag, PairState, ParticleState, Reduction, ThermalSum, fit_rows


class Engine:
    """Owns the device state of one simulation and the kernels that advance it."""

    def __init__(self, scene, tables: PairTables, capacity: int, real, skin: float,
                 max_radius: float, dt: float):
        self.scene = scene
        self.tables = tables
        self.real = real
        self.skin = skin
        self.dt = dt
        self.effects = effect_names(scene)
        self.rolling_cdt = "rolling_constant_torque" in self.effects
        self.rolling_epsd = "rolling_epsd" in self.effects
        self.thermal = scene.thermal is not None
        self.conduction = "conduction" in self.effects
        self.wall_conduction = "wall_conduction" in self.effects
        # particle-fluid-wall conduction (thermal/gas_gap.py): only with wall conduction on
        self.gas_gap = "gas_gap_wall" in self.effects
        th = scene.thermal
        self.gas_gap_parameters = ((th.gap_gas_conductivity, th.gas_gap_lens, th.gas_gap_min_gap)
                                   if self.gas_gap else (0.0, 0.0, 1.0))
        self.convection = "convection" in self.effects
        self.plug_flow = "plug_flow_gas" in self.effects
        self.radiation = "radiation" in self.effects
        self.moisture = "drying" in self.effects
        self.trees: list[FieldTree] = []
        self.walls = scene.walls
        has_planes = any(x.kind == "mass_flow" for x in scene.sensors)
        self.state = ParticleState(capacity, real, len(scene.walls), self.rolling_epsd,
                                   thermal=self.thermal, moisture=self.moisture,
                                   process=bool(scene.factories or scene.outlets))
        self.trees.append(self.state.tree)
        self.grid = GridSpec(scene.domain.min, scene.domain.max, scene.domain.periodic,
                             2.0 * max_radius + skin, capacity)
        t = self.new_tree()
        m = len(tables.names)
        self.youngs_eff = t.add("youngs_eff", real, (m, m))
        self.shear_eff = t.add("shear_eff", real, (m, m))
        self.damping = t.add("damping", real, (m, m))
        self.friction = t.add("friction", real, (m, m))
        self.rolling_friction = t.add("rolling_friction", real, (m, m))
        self.rolling_model = t.add("rolling_model", ti.i32, (m, m))
        self.rolling_damping = t.add("rolling_damping", real, (m, m))
        # named slots: Flag (engine/state.py)
        self.flags = t.add("flags", ti.i32, Flag.SIZE)
        self.wall_force = t.add("wall_force", real, max(len(scene.walls), 1), vector=True)
        self.reduction = t.add("reduction", real, Reduction.SIZE)   # named slots: Reduction
        self.gas_stream = None
        if self.thermal:
            self.conductance_factor = t.add("conductance_factor", real, (m, m))
            self.radius_correction = t.add("radius_correction", real, (m, m))
            self.wall_heat = t.add("wall_heat", real, max(len(scene.walls), 1))
            # f64 sums over the particles: sum m c T (J), sum m c (J/K), water (kg), dry solid
            # (kg); an f32 sum of m c T at 723 K would round the heat balance away
            self.thermal_sums = t.add("thermal_sums", ti.f64, ThermalSum.SIZE)
            if self.plug_flow:
                from thermal.plug_flow import AxialPlugFlowGas
                self.gas_stream = AxialPlugFlowGas(scene.thermal.gas, self.state, t, real)
            if self.radiation:
                self.emissivity = t.add("emissivity", real, m)         # per material
            if self.moisture:
                self.evaporated = t.add("evaporated", ti.f64, 1)      # kg since the start
        self.process = None
        if scene.factories or scene.outlets or has_planes:
            from ..process.outlets import ProcessDevice
            self.process = ProcessDevice(self, t)
        t.finalize()
        self.removed_batches: list = []    # removal-log entries drained at rebuilds
        if self.radiation:
            self.emissivity.from_numpy(np.array([scene.materials[k].emissivity or 0.0 for k in tables.names],
                                                np.float64 if real == ti.f64 else np.float32))
        if self.gas_stream is not None:
            self.gas_stream.compile()
        if self.thermal:
            from ..setup.pair_tables import conduction_tables
            factor, correction = conduction_tables(scene, tables.names)
            npf = np.float64 if real == ti.f64 else np.float32
            self.conductance_factor.from_numpy(factor.astype(npf))
            self.radius_correction.from_numpy(correction.astype(npf))
        for name in ("youngs_eff", "shear_eff", "damping", "friction", "rolling_friction",
                     "rolling_damping"):
            getattr(self, name).from_numpy(getattr(tables, name).astype(np.float64 if real == ti.f64 else np.float32))
        self.rolling_model.from_numpy(tables.rolling_model.astype(np.int32))
        self.max_radius = max_radius
        self.time = 0.0
        self.pairs: "PairState | None" = None
        self.broadphase = Broadphase(self)
        self.mesh = None
        if scene.bodies:
            from ..bodies.kinematics import BodyKinematics
            from ..bodies.mesh_contacts import MeshContacts
            self.kinematics = BodyKinematics(scene.bodies)
            self.mesh = MeshContacts(self, self.kinematics)
        self._compile_particle_kernels()
        if scene.factories:
            self._compile_insert()

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
        new = PairState(capacity, self.real, self.rolling_epsd, self.conduction)
        if old is not None:
            new.old_partner_id.from_numpy(fit_rows(old.old_partner_id.to_numpy(), capacity))
            new.old_tangential_history.from_numpy(fit_rows(old.old_tangential_history.to_numpy(), capacity))
            if old.old_rolling_history is not None:
                new.old_rolling_history.from_numpy(fit_rows(old.old_rolling_history.to_numpy(), capacity))
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

    # ------------------------------------------------------------------ kernels
    def _compile_particle_kernels(self):
        s = self.state
        g = self.grid
        lo = ti.Vector(list(g.lo))
        hi = ti.Vector(list(g.hi))
        span = ti.Vector(list(g.span))
        half_skin_sq = (0.5 * self.skin) ** 2
        real = self.real
        flags = self.flags
        red = self.reduction

        minimum_image = self.minimum_image = g.make_minimum_image()

        has_process = self.process is not None
        after_drift = self.process.make_funcs(self) if has_process else None
        from ..process.outlets import PARKED

        @ti.func
        def drift_particle(i, dt, t_new):
            """First half of a velocity Verlet step for particle i: half kick, then drift.
            A particle that leaves the domain (or enters an outlet) is removed: marked dead
            and parked far away until the next rebuild drops it. ``t_new``: time after the
            step, s."""
            if s.inverse_mass[i] > 0.0 and s.alive[i] != 0:
                v = s.velocity[i] + 0.5 * dt * s.acceleration[i]
                s.velocity[i] = v
                s.angular_velocity[i] += 0.5 * dt * s.angular_acceleration[i]
                x_old = s.position[i]
                x_new = x_old + dt * v
                x = x_new
                inside = True
                for k in ti.static(range(3)):
                    if ti.static(g.periodic[k]):
                        # wrap into [lo, hi): the particle re-enters through the opposite face
                        if x[k] >= hi[k]:
                            x[k] -= span[k]
                        elif x[k] < lo[k]:
                            x[k] += span[k]
                    elif x[k] < lo[k] or x[k] > hi[k]:
                        inside = False
                s.position[i] = x
                removed = False
                if ti.static(has_process):
                    removed = after_drift(i, x_old, x_new, x, inside, t_new)
                elif not inside:
                    removed = True
                    s.alive[i] = 0
                    s.position[i] = ti.Vector([PARKED, PARKED, PARKED])
                    s.velocity[i] = ti.Vector([0.0, 0.0, 0.0])
                    ti.atomic_add(flags[Flag.LOST], 1)
                    ti.atomic_add(flags[Flag.DEAD_IN_SLOTS], 1)
                if not removed:
                    moved = minimum_image(x - s.reference_position[i])
                    if moved.dot(moved) > half_skin_sq:
                        flags[Flag.REBUILD] = 1      # benign race: every writer writes 1
        self.drift_particle = drift_particle

        @ti.kernel
        def drift(n: ti.i32, dt: real, t_new: ti.f64):
            for i in range(n):
                drift_particle(i, dt, t_new)

        thermal = self.thermal
        moisture = self.moisture
        compensated = s.compensated
        sums = self.thermal_sums if thermal else None
        dt_step = self.dt

        @ti.kernel
        def measure(n: ti.i32):
            # kinetic energy (translational + rotational, J), largest speed, non-finite flag,
            # alive count; thermal: sum m c T (J), sum m c (J/K), largest dt sum(h)/(m c)
            for k in ti.static(range(Reduction.SIZE)):
                red[k] = 0.0
            for i in range(n):
                if s.inverse_mass[i] > 0.0 and s.alive[i] != 0:
                    m = s.mass[i]
                    inertia = 0.4 * m * s.radius[i] ** 2
                    v2 = s.velocity[i].dot(s.velocity[i])
                    red[Reduction.KINETIC_ENERGY] += (0.5 * m * v2 + 0.5 * inertia
                                                      * s.angular_velocity[i].dot(s.angular_velocity[i]))
                    ti.atomic_max(red[Reduction.MAX_SPEED], ti.sqrt(v2))
                    if not (v2 >= 0.0 and v2 < 1e300):
                        red[Reduction.NON_FINITE] = 1.0      # NaN or overflow
                    red[Reduction.MOVING_COUNT] += 1.0
            if ti.static(thermal):
                for k in ti.static(range(ThermalSum.SIZE)):
                    sums[k] = 0.0
                for i in range(n):
                    if s.alive[i] != 0:
                        thermal_mass = 1.0 / ti.cast(s.inverse_thermal_mass[i], ti.f64)
                        temperature = ti.cast(s.temperature[i], ti.f64)
                        if ti.static(compensated):
                            temperature += s.temperature_residual[i]
                        sums[ThermalSum.THERMAL_ENERGY] += thermal_mass * temperature
                        sums[ThermalSum.THERMAL_MASS] += thermal_mass
                        ti.atomic_max(red[Reduction.THERMAL_STEP_RATIO],
                                      dt_step * s.conductance[i] * s.inverse_thermal_mass[i])
                        if not (s.temperature[i] > 0.0 and s.temperature[i] < 1e30):
                            red[Reduction.NON_FINITE] = 1.0
                        if ti.static(moisture):
                            water = ti.cast(s.moisture[i], ti.f64)
                            if ti.static(compensated):
                                water += s.moisture_residual[i]
                            sums[ThermalSum.WATER_MASS] += ti.cast(s.mass[i], ti.f64) * water
                            sums[ThermalSum.DRY_MASS] += ti.cast(s.mass[i], ti.f64)

        self._drift, self._measure = drift, measure

    def _compile_pair_kernels(self, p: PairState):
        s = self.state
        minimum_image = self.minimum_image
        # the pair tables (material x material), as the kernels read them
        youngs_eff, shear_eff, damping, friction = (self.youngs_eff, self.shear_eff, self.damping,
                                                    self.friction)
        rolling_friction, rolling_model, rolling_damping = (
            self.rolling_friction, self.rolling_model, self.rolling_damping)
        cdt, epsd = self.rolling_cdt, self.rolling_epsd
        walls = [(tuple(w.point), tuple(w.normal), self.tables.index(w.material)) for w in self.walls]
        n_walls = len(walls)
        gravity = ti.Vector(list(self.scene.simulation.gravity))
        wall_force = self.wall_force
        real = self.real
        drift_particle = self.drift_particle
        has_mesh = self.mesh is not None
        conduction, wall_conduction, convection = self.conduction, self.wall_conduction, self.convection
        thermal = self.thermal
        conductance_factor = self.conductance_factor if thermal else None
        radius_correction = self.radius_correction if thermal else None
        gas_gap_on = self.gas_gap
        gap_k, gap_lens, gap_min = self.gas_gap_parameters
        wall_temperature = [w.temperature if (w.temperature is not None and wall_conduction) else -1.0
                            for w in self.walls]
        wall_heat = self.wall_heat if thermal else None
        gas = self.scene.thermal.gas if (thermal and convection) else None
        has_gas = gas is not None and not self.plug_flow       # a uniform ("fixed") gas
        stream = self.gas_stream
        plug_flow = stream is not None
        th = self.scene.thermal
        radiation, moisture = self.radiation, self.moisture
        compensated = s.compensated
        compensated_add, split_f64 = make_compensated_add(real)
        # names the kernel closes over must exist even when their effect is off
        emissivity = evaporated = radiate_to_gas = radiation_temperature = None
        in_radiation_region = t_evap = latent = c_water = None
        if radiation:
            emissivity = self.emissivity
            radiate_to_gas = th.radiation_to == "gas"
            radiation_temperature = (gas.temperature if (radiate_to_gas and not plug_flow)
                                     else (th.radiation_temperature or 0.0))
            in_radiation_region = _region_test(th.radiation_region)
        if moisture:
            evaporated = self.evaporated
            t_evap, latent, c_water = th.evaporation_temperature, th.latent_heat, th.water_heat_capacity
        gas_velocity = ti.Vector(list(gas.velocity)) if has_gas else None
        prandtl = gas.heat_capacity * gas.viscosity / gas.conductivity if gas is not None else 0.0
        prandtl_cube_root = prandtl ** (1.0 / 3.0)

        @ti.func
        def rolling_torque(pair_model, w_rel, normal, fn, sn, r_eff, mu_r, eta_r, inertia_eff,
                           rolling_inertia, history, dt):
            torque = ti.Vector([0.0, 0.0, 0.0])
            if ti.static(cdt):
                if pair_model == ROLLING_CONSTANT_TORQUE:
                    torque = rolling.constant_torque(w_rel, fn, r_eff, mu_r, inertia_eff, dt)
            if ti.static(epsd):
                if pair_model == ROLLING_EPSD:
                    torque, history = rolling.epsd(w_rel, normal, fn, sn, r_eff, mu_r, eta_r,
                                                   rolling_inertia, history, dt)
            return torque, history

        @ti.kernel
        def pair_forces(n: ti.i32, dt: real):
            for i in range(n):
                xi, vi, wi = s.position[i], s.velocity[i], s.angular_velocity[i]
                ri, inv_mi, inv_ii, mi = s.radius[i], s.inverse_mass[i], s.inverse_inertia[i], s.material[i]
                owned_force = ti.Vector([0.0, 0.0, 0.0])
                owned_torque = ti.Vector([0.0, 0.0, 0.0])
                owned_heat = 0.0
                owned_conductance = 0.0
                for k in range(s.row_start[i], s.row_start[i] + s.row_owned[i]):
                    j = p.neighbour[k]
                    d = minimum_image(xi - s.position[j])
                    rj = s.radius[j]
                    distance_sq = d.dot(d)
                    if distance_sq < (ri + rj) * (ri + rj) and distance_sq > 0.0:
                        dist = ti.sqrt(distance_sq)
                        normal_overlap = ri + rj - dist
                        normal = d / dist                                   # from j to i
                        r_eff = ri * rj / (ri + rj)
                        mj = s.material[j]
                        if ti.static(conduction):
                            # Q = h_c (T_j - T_i), h_c = 4 k_i k_j/(k_i + k_j) a, with the Hertz
                            # contact radius a = (3 F_n R*/(4 E*))^(1/3) = sqrt(R* d_n),
                            # corrected for a softened modulus (model.conduction_tables)
                            h_c = contact_conductance(conductance_factor[mi, mj],
                                                      radius_correction[mi, mj], r_eff,
                                                      normal_overlap)
                            heat = h_c * (s.temperature[j] - s.temperature[i])
                            owned_heat += heat
                            owned_conductance += h_c
                            p.partner_heat[k] = -heat
                            p.pair_conductance[k] = h_c
                            if inv_mi + s.inverse_mass[j] <= 0.0:
                                # two fixed particles (listed only for heat): no forces
                                p.partner_force[k] = ti.Vector([0.0, 0.0, 0.0])
                                p.partner_torque[k] = ti.Vector([0.0, 0.0, 0.0])
                                p.contact[k] = ti.u8(1)
                                continue
                        m_eff = 1.0 / (inv_mi + s.inverse_mass[j])
                        arm_i = ri - 0.5 * normal_overlap     # centre to contact point
                        arm_j = rj - 0.5 * normal_overlap
                        wj = s.angular_velocity[j]
                        v_rel = vi - s.velocity[j] - (arm_i * wi + arm_j * wj).cross(normal)
                        normal_acceleration = (s.acceleration[i] - s.acceleration[j]).dot(normal)
                        fn, ft, history, sn = contact_force(
                            normal, normal_overlap, r_eff, m_eff, v_rel, normal_acceleration,
                            p.tangential_history[k], youngs_eff[mi, mj], shear_eff[mi, mj],
                            damping[mi, mj], friction[mi, mj], dt)
                        force = fn * normal + ft
                        lever = normal.cross(ft)
                        torque_i = -arm_i * lever
                        torque_j = -arm_j * lever
                        if ti.static(cdt or epsd):
                            if rolling_friction[mi, mj] > 0.0:
                                prev = ti.Vector([0.0, 0.0, 0.0])
                                if ti.static(epsd):
                                    prev = p.rolling_history[k]
                                tr, rolling_history = rolling_torque(
                                    rolling_model[mi, mj], wi - wj, normal, fn, sn, r_eff,
                                    rolling_friction[mi, mj], rolling_damping[mi, mj],
                                    1.0 / (inv_ii + s.inverse_inertia[j]),
                                    1.0 / (rolling.rolling_inverse_inertia(inv_mi, inv_ii, ri)
                                           + rolling.rolling_inverse_inertia(
                                               s.inverse_mass[j], s.inverse_inertia[j], rj)),
                                    prev, dt)
                                torque_i += tr
                                torque_j -= tr
                                if ti.static(epsd):
                                    p.rolling_history[k] = rolling_history
                        owned_force += force
                        owned_torque += torque_i
                        p.partner_force[k] = -force
                        p.partner_torque[k] = torque_j
                        p.tangential_history[k] = history
                        p.contact[k] = ti.u8(1)
                    elif p.contact[k] != 0:
                        # the contact opened: its history is discarded
                        p.contact[k] = ti.u8(0)
                        p.tangential_history[k] = ti.Vector([0.0, 0.0, 0.0])
                        if ti.static(epsd):
                            p.rolling_history[k] = ti.Vector([0.0, 0.0, 0.0])
                s.owned_force[i] = owned_force
                s.owned_torque[i] = owned_torque
                if ti.static(thermal):
                    s.owned_heat[i] = owned_heat
                    s.conductance[i] = owned_conductance

        mesh_contacts = self.mesh.make_particle_contacts(rolling_torque) if has_mesh else None

        @ti.kernel
        def gather(n: ti.i32, dt: real, record: ti.i32, then_drift: ti.i32, t_next: ti.f64):
            for i in range(n):
                if s.alive[i] == 0:
                    continue          # removed since the last rebuild: parked, inert
                force = s.owned_force[i]
                torque = s.owned_torque[i]
                for k in range(s.row_start[i] + s.row_owned[i], s.row_start[i] + s.row_count[i]):
                    m = p.mirror[k]
                    if m >= 0:
                        if p.contact[m] != 0:
                            force += p.partner_force[m]
                            torque += p.partner_torque[m]
                heat = 0.0           # W into the particle
                conductance = 0.0    # W/K, for the stability check
                if ti.static(thermal):
                    heat = s.owned_heat[i]
                    conductance = s.conductance[i]
                if ti.static(conduction):
                    for k in range(s.row_start[i] + s.row_owned[i], s.row_start[i] + s.row_count[i]):
                        m = p.mirror[k]
                        if m >= 0:
                            if p.contact[m] != 0:
                                heat += p.partner_heat[m]
                                conductance += p.pair_conductance[m]
                inv_m = s.inverse_mass[i]
                if ti.static(n_walls > 0):
                    xi, vi, wi, ri, mi = s.position[i], s.velocity[i], s.angular_velocity[i], s.radius[i], s.material[i]
                    for w in ti.static(range(n_walls)):
                        wall_point = ti.Vector(walls[w][0])
                        wall_normal = ti.Vector(walls[w][1])
                        mw = ti.static(walls[w][2])
                        normal_overlap = ri - (xi - wall_point).dot(wall_normal)
                        history = ti.Vector([0.0, 0.0, 0.0])
                        rolling_history = ti.Vector([0.0, 0.0, 0.0])
                        if ti.static(wall_temperature[w] >= 0.0):
                            h_w = 0.0 * ri
                            if normal_overlap > 0.0:
                                # conduction to an isothermal (e.g. water-cooled) wall
                                h_w = contact_conductance(conductance_factor[mi, mw],
                                                          radius_correction[mi, mw], ri,
                                                          normal_overlap)
                            if ti.static(gas_gap_on):
                                # and through the gas between the particle and the wall, within
                                # the fluid lens (thermal/gas_gap.py); touching or not
                                h_w += ti.static(gap_k) * gas_gap.plane_gap_integral(
                                    ri, ri - normal_overlap, ti.static(gap_lens), ti.static(gap_min))
                            if h_w > 0.0:
                                q_w = h_w * (ti.static(wall_temperature[w]) - s.temperature[i])
                                heat += q_w
                                conductance += h_w
                                if record != 0:
                                    wall_heat[w] -= q_w
                        if normal_overlap > 0.0 and inv_m > 0.0:
                            arm = ri - 0.5 * normal_overlap
                            v_rel = vi - arm * wi.cross(wall_normal)       # the wall is at rest
                            fn, ft, history, sn = contact_force(
                                wall_normal, normal_overlap, ri, s.mass[i], v_rel,
                                s.acceleration[i].dot(wall_normal),
                                s.wall_tangential_history[i, w], youngs_eff[mi, mw],
                                shear_eff[mi, mw], damping[mi, mw], friction[mi, mw], dt)
                            wall_contact = fn * wall_normal + ft
                            contact_torque = -arm * wall_normal.cross(ft)
                            if ti.static(cdt or epsd):
                                if rolling_friction[mi, mw] > 0.0:
                                    prev = ti.Vector([0.0, 0.0, 0.0])
                                    if ti.static(epsd):
                                        prev = s.wall_rolling_history[i, w]
                                    tr, rolling_history = rolling_torque(
                                        rolling_model[mi, mw], wi, wall_normal, fn, sn, ri,
                                        rolling_friction[mi, mw], rolling_damping[mi, mw],
                                        1.0 / s.inverse_inertia[i],
                                        1.0 / rolling.rolling_inverse_inertia(
                                            inv_m, s.inverse_inertia[i], ri),
                                        prev, dt)
                                    contact_torque += tr
                            force += wall_contact
                            torque += contact_torque
                            if record != 0:
                                wall_force[w] -= wall_contact
                        s.wall_tangential_history[i, w] = history
                        if ti.static(epsd):
                            s.wall_rolling_history[i, w] = rolling_history
                if ti.static(has_mesh):
                    if inv_m > 0.0:
                        mesh_force, mesh_torque, mesh_heat, mesh_conductance = mesh_contacts(
                            i, s.position[i], s.velocity[i], s.angular_velocity[i], s.radius[i],
                            s.mass[i], s.inverse_inertia[i], s.acceleration[i], s.material[i], dt)
                        force += mesh_force
                        torque += mesh_torque
                        heat += mesh_heat
                        conductance += mesh_conductance
                if ti.static(has_gas):
                    # convection, Q = h A (T_g - T_p), h = k_g Nu / d (PHYSICS.md)
                    diameter = 2.0 * s.radius[i]
                    reynolds = ti.static(gas.density / gas.viscosity) * diameter * (gas_velocity - s.velocity[i]).norm()
                    nusselt = 0.0
                    if ti.static(gas.correlation == "gunn"):
                        nusselt = gas_convection.nusselt_gunn(reynolds, prandtl_cube_root, ti.static(gas.porosity))
                    else:
                        nusselt = gas_convection.nusselt_ranz_marshall(reynolds, prandtl_cube_root)
                    h_gas = gas_convection.convective_conductance(ti.static(gas.conductivity), nusselt, diameter)
                    heat += h_gas * (ti.static(gas.temperature) - s.temperature[i])
                    conductance += h_gas
                # --- plug-flow gas, radiation, drying (thermal/: plug_flow, radiation, moisture)
                if ti.static(plug_flow):
                    q_gas, g_gas = stream.particle_heat(i, s.temperature[i])
                    heat += q_gas
                    conductance += g_gas
                if ti.static(radiation):
                    if in_radiation_region(s.position[i]):
                        t_surroundings = ti.static(radiation_temperature) + 0.0 * heat
                        sees = 1
                        if ti.static(radiate_to_gas and plug_flow):
                            t_surroundings, sees = stream.local_temperature(i)
                        if sees != 0:
                            q_rad, g_rad = radiative.exchange(emissivity[s.material[i]], s.radius[i],
                                                              t_surroundings, s.temperature[i])
                            heat += q_rad
                            conductance += g_rad
                if ti.static(thermal):
                    if s.alive[i] != 0:
                        # explicit update; stable while dt sum(h) / (m c) < 1 (checked per sample)
                        if ti.static(moisture and compensated):
                            # in f64 throughout, then split back (thermal/precision.py)
                            t_new, x_new, inv_c, dm = drying.heat_and_dry(
                                ti.cast(s.temperature[i], ti.f64) + s.temperature_residual[i],
                                ti.cast(s.moisture[i], ti.f64) + s.moisture_residual[i],
                                ti.cast(s.inverse_thermal_mass[i], ti.f64),
                                ti.cast(s.mass[i], ti.f64), ti.cast(dt * heat, ti.f64),
                                t_evap, latent, c_water)
                            t_part, t_rest = split_f64(t_new)
                            s.temperature[i] = t_part
                            s.temperature_residual[i] = t_rest
                            if dm > 0.0:
                                x_part, x_rest = split_f64(x_new)
                                s.moisture[i] = x_part
                                s.moisture_residual[i] = x_rest
                                s.inverse_thermal_mass[i] = ti.cast(inv_c, real)
                                evaporated[0] += dm
                        elif ti.static(moisture):
                            t_new, x_new, inv_c, dm = drying.heat_and_dry(
                                s.temperature[i], s.moisture[i], s.inverse_thermal_mass[i],
                                s.mass[i], dt * heat, t_evap, latent, c_water)
                            s.temperature[i] = t_new
                            if dm > 0.0:
                                s.moisture[i] = x_new
                                s.inverse_thermal_mass[i] = inv_c
                                evaporated[0] += ti.cast(dm, ti.f64)
                        elif ti.static(compensated):
                            t_part, t_rest = compensated_add(
                                s.temperature[i], s.temperature_residual[i],
                                dt * heat * s.inverse_thermal_mass[i])
                            s.temperature[i] = t_part
                            s.temperature_residual[i] = t_rest
                        else:
                            s.temperature[i] += dt * heat * s.inverse_thermal_mass[i]
                        s.conductance[i] = conductance
                if inv_m > 0.0 and s.alive[i] != 0:
                    a = force * inv_m + gravity
                    alpha = torque * s.inverse_inertia[i]
                    s.acceleration[i] = a
                    s.angular_acceleration[i] = alpha
                    s.velocity[i] += 0.5 * dt * a
                    s.angular_velocity[i] += 0.5 * dt * alpha
                if then_drift != 0:
                    # the next step's first half, fused here to save a pass over the particles
                    drift_particle(i, dt, t_next)

        self._pair_forces, self._gather = pair_forces, gather

    # ------------------------------------------------------------------ driver
    def start(self, n: int) -> int:
        """Build the first neighbour list and the initial accelerations (no time advance)."""
        if self.mesh is not None:
            self.mesh.update_frames(self.time)
        self.count = self.broadphase.rebuild(n)
        self._pair_forces(self.count, 0.0)
        if self.gas_stream is not None:
            self.gas_stream.exchange(self.count, 0.0)
        self._gather(self.count, 0.0, 0, 0, self.time)
        return self.count

    def rebuild(self, n: int):
        """Drop dead particles, re-sort and rebuild the neighbour lists."""
        self.flags[Flag.REBUILD] = 0
        if self.process is not None and self.process.log_enabled:
            batch = self.process.drain()
            if batch is not None:
                self.removed_batches.append(batch)
        self.count = self.broadphase.rebuild(n)
        self.flags[Flag.DEAD_IN_SLOTS] = 0

    def advance(self, steps: int, record_last: bool = False):
        """Advance ``steps`` time steps of ``self.dt``."""
        dt = self.dt
        for k in range(steps):
            n = self.count
            if k == 0:
                # later steps drifted at the end of the previous gather
                self._drift(n, dt, self.time + dt)
            self.time += dt
            rebuild = self.flags[Flag.REBUILD] != 0
            if self.mesh is not None:
                self.mesh.update_frames(self.time)
                self.mesh.interval_steps += 1
                rebuild = rebuild or self.mesh.needs_rebinning(self.time)
            if rebuild:
                self.rebuild(n)
            last = k == steps - 1
            record = 1 if (record_last and last) else 0
            if record:
                self.wall_force.fill(0.0)
                if self.thermal:
                    self.wall_heat.fill(0.0)
            self._pair_forces(self.count, dt)
            if self.gas_stream is not None:
                self.gas_stream.exchange(self.count, dt)     # the gas sees this step's particles
            # the state is left at a whole step (no pending drift) when advance returns
            self._gather(self.count, dt, record, 0 if last else 1, self.time + dt)

    def measure(self) -> dict:
        self._measure(self.count)
        r = self.reduction.to_numpy()
        out = {"kinetic_energy": float(r[Reduction.KINETIC_ENERGY]),
               "max_speed": float(r[Reduction.MAX_SPEED]),
               "non_finite": bool(r[Reduction.NON_FINITE] > 0)}
        if self.thermal:
            h = self.thermal_sums.to_numpy()
            energy, thermal_mass = h[ThermalSum.THERMAL_ENERGY], h[ThermalSum.THERMAL_MASS]
            out.update(thermal_energy=float(energy),
                       mean_temperature=float(energy / thermal_mass) if thermal_mass else 0.0,
                       thermal_step_ratio=float(r[Reduction.THERMAL_STEP_RATIO]))
        if self.moisture:
            water, dry = h[ThermalSum.WATER_MASS], h[ThermalSum.DRY_MASS]
            out.update(mean_moisture=float(water / dry) if dry else 0.0,
                       evaporated_mass=float(self.evaporated[0]))
        return out

    @property
    def lost(self) -> int:
        return int(self.flags[Flag.LOST])

    @property
    def alive_count(self) -> int:
        """Particles in the simulation now (slots in use minus those removed since the last
        rebuild)."""
        return self.count - int(self.flags[Flag.DEAD_IN_SLOTS])

    def insert(self, arrays: dict):
        """Put new particles into the slots after the last one in use and flag a rebuild.
        ``arrays``: position, velocity (n,3) m, m/s; radius m, mass kg, key (slot keys not in
        use), serial, origin (n,), birth_time s; temperature K and inverse_thermal_mass 1/(J/K)
        when thermal; moisture kg/kg when drying. The state must be at a whole step (between
        ``advance`` calls)."""
        k = len(arrays["radius"])
        if k == 0:
            return
        if self.count + k > self.state.capacity:
            raise RuntimeError("particle capacity exceeded")
        # the device's precision (an f32 field assigned from f64 would warn at compile time)
        npf = np.float64 if self.real == ti.f64 else np.float32
        npt = np.float64 if self.state.compensated else npf
        zeros = np.zeros(k, npf)
        self._insert(self.count, k,
                     np.ascontiguousarray(arrays["position"], npf),
                     np.ascontiguousarray(arrays["velocity"], npf),
                     np.ascontiguousarray(arrays["radius"], npf),
                     np.ascontiguousarray(arrays["mass"], npf),
                     np.ascontiguousarray(arrays["material"], np.int32),
                     np.ascontiguousarray(arrays["key"], np.int32),
                     np.ascontiguousarray(arrays["serial"], np.int32),
                     np.ascontiguousarray(arrays["origin"], np.int32),
                     np.ascontiguousarray(arrays["birth_time"], npf),  # (residence: f32 is
                     # 4e-6 s at 100 s)
                     # f64 where an f64 residual keeps what f32 cannot (thermal/precision.py)
                     np.ascontiguousarray(arrays.get("temperature", zeros), npt),
                     np.ascontiguousarray(arrays.get("inverse_thermal_mass", zeros), npf),
                     np.ascontiguousarray(arrays.get("moisture", zeros), npt))
        self.count += k

    def _compile_insert(self):
        s = self.state
        gravity = ti.Vector(list(self.scene.simulation.gravity))
        thermal = self.thermal
        process = s.process
        n_walls = s.n_walls
        wall_fields = [getattr(s, n) for n in ("wall_tangential_history", "wall_rolling_history")
                       if hasattr(s, n)]
        mesh = self.mesh
        has_mesh = mesh is not None
        n_bodies = mesh.n_bodies if has_mesh else 0
        heat_loads = has_mesh and mesh.particle_load_heat is not None
        flags = self.flags
        drying = self.moisture
        compensated = s.compensated
        real = self.real
        compensated_add, split_f64 = make_compensated_add(real)

        @ti.kernel
        def insert(start: ti.i32, k: ti.i32, position: ti.types.ndarray(),
                   velocity: ti.types.ndarray(), radius: ti.types.ndarray(),
                   mass: ti.types.ndarray(), material: ti.types.ndarray(),
                   key: ti.types.ndarray(), serial: ti.types.ndarray(),
                   origin: ti.types.ndarray(), birth_time: ti.types.ndarray(),
                   temperature: ti.types.ndarray(), inverse_thermal_mass: ti.types.ndarray(),
                   moisture: ti.types.ndarray()):
            for q in range(k):
                i = start + q
                x = ti.Vector([position[q, 0], position[q, 1], position[q, 2]])
                s.position[i] = x
                s.reference_position[i] = x
                s.velocity[i] = ti.Vector([velocity[q, 0], velocity[q, 1], velocity[q, 2]])
                s.angular_velocity[i] = ti.Vector([0.0, 0.0, 0.0])
                # inserted clear of every contact: free flight is the first step's acceleration
                s.acceleration[i] = gravity
                s.angular_acceleration[i] = ti.Vector([0.0, 0.0, 0.0])
                r = radius[q]
                m = mass[q]
                s.radius[i] = r
                s.mass[i] = m
                s.inverse_mass[i] = 1.0 / m
                s.inverse_inertia[i] = 1.0 / (0.4 * m * r * r)
                s.material[i] = material[q]
                s.particle_id[i] = key[q]
                s.alive[i] = 1
                if ti.static(process):
                    s.serial[i] = serial[q]
                    s.origin[i] = origin[q]
                    s.birth_time[i] = birth_time[q]
                if ti.static(thermal and compensated):
                    t_part, t_rest = split_f64(ti.cast(temperature[q], ti.f64))
                    s.temperature[i] = t_part
                    s.temperature_residual[i] = t_rest
                    s.inverse_thermal_mass[i] = inverse_thermal_mass[q]
                elif ti.static(thermal):
                    s.temperature[i] = temperature[q]
                    s.inverse_thermal_mass[i] = inverse_thermal_mass[q]
                if ti.static(drying and compensated):
                    x_part, x_rest = split_f64(ti.cast(moisture[q], ti.f64))
                    s.moisture[i] = x_part
                    s.moisture_residual[i] = x_rest
                elif ti.static(drying):
                    s.moisture[i] = moisture[q]
                # the slot may hold what a removed particle left: no rows, no history, no loads
                s.row_owned[i] = 0
                s.row_count[i] = 0
                for f in ti.static(wall_fields):
                    for w in ti.static(range(n_walls)):
                        f[i, w] = ti.Vector([0.0, 0.0, 0.0])
                if ti.static(has_mesh):
                    mesh.mesh_count[i] = 0
                    for b in ti.static(range(n_bodies)):
                        mesh.particle_load_force[i, b] = ti.Vector([0.0, 0.0, 0.0])
                        mesh.particle_load_torque[i, b] = ti.Vector([0.0, 0.0, 0.0])
                        if ti.static(heat_loads):
                            mesh.particle_load_heat[i, b] = 0.0
            flags[Flag.REBUILD] = 1

        self._insert = insert


def _region_test(region):
    """A ti.func position -> bool: inside ``region`` (a scene Region), always True for None."""
    if region is None:
        @ti.func
        def inside(x):
            return True
        return inside
    if region.kind == "box":
        lo, hi = ti.Vector(list(region.box_min)), ti.Vector(list(region.box_max))

        @ti.func
        def inside(x):
            return (x >= lo).all() and (x <= hi).all()
        return inside
    p0, axis = ti.Vector(list(region.axis_point)), ti.Vector(list(region.axis_direction))
    length, r2 = region.length, region.radius ** 2

    @ti.func
    def inside(x):
        d = x - p0
        a = d.dot(axis)
        return a >= 0.0 and a <= length and (d - a * axis).norm_sqr() <= r2
    return inside
