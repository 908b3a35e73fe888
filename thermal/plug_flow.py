"""Axial plug-flow gas (PHYSICS.md "Gas models"): the cheap stand-in for the dryer's CFD.

A 1-D gas stream runs along the axis (``axis_point`` + s ``axis_direction``, 0 <= s < length)
through ``cells`` equal cells, entering at s = 0 (``flow = "along_axis"``) or at s = length
(``"against_axis"``) with mass flow m_dot at T_in. Its velocity, for Re and the relative
velocity of the Nusselt correlation, is u = m_dot / (rho_g flow_area) along the flow. Gas
properties are constant (those of [thermal.gas]); the gas holds no heat (quasi-steady: it
crosses the drum in a fraction of a second, the bed changes over minutes).

Each step, from the particle temperatures at the start of the step:
  1. every particle in the span finds its cell c and its conductance G_i = h_i A_i (Ranz-
     Marshall or Gunn, as the fixed gas); each cell sums G_c = sum G_i and S_c = sum G_i T_i;
  2. the gas marches from the inlet, cell by cell. Within a cell it passes particles of mean
     temperature T_pc = S_c / G_c spread along the cell, so (exactly, for the quasi-steady gas
     m_dot c_g dT_g/dx = -(G_c/dx)(T_g - T_pc))
         T_out = T_pc + (T_in,c - T_pc) exp(-NTU),   NTU = G_c / (m_dot c_g),
         Q_c   = m_dot c_g (T_in,c - T_out)   (W, into the cell's particles);
  3. each particle of the cell receives Q_i = G_i (T_gc - T_i) with the cell's effective gas
     temperature T_gc = T_pc + Q_c / G_c, so that sum Q_i = Q_c: the gas's loss and the
     particles' gain are equal to round-off, and the gas never overshoots the particles
     however large NTU is (an explicit march would for NTU > 2).
The march runs every step (N serial cells: microseconds): the sums of step 1 need a pass over
the particles anyway, and marching less often would break the exact balance of step 3.

Particles outside the axial span (s < 0 or s >= length) exchange nothing with the gas. The
radius of the stream is not checked: every particle in the span is in the gas (a drum).
"""
import taichi as ti

from . import convection as gas_convection


BLOCKS = 64        # CPU: particle blocks summed without atomics (a few per thread)


def _phi(x):
    """(1 - exp(-x)) / x, accurate for small x (f32: 1 - exp(-1e-6) has no digits left)."""
    return ti.select(x < 1e-3, 1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0)),
                     (1.0 - ti.exp(-x)) / ti.max(x, 1e-30))


class AxialPlugFlowGas:
    """The gas stream's fields and kernels. ``exchange(n, dt, serial_loops)`` runs after the pair
    kernel and before the particle update (``serial_loops``: the engine's loop mode);
    ``particle_heat(i, T)`` is the ti.func the update calls.

    Per-particle scratch (cell, conductance) is recomputed every step, so it needs no
    reordering; it is sized to the particle capacity it was built with."""

    def __init__(self, gas, state, tree, real):
        self.gas = gas
        self.cells = n_cells = gas.cells
        cap = state.capacity
        self.cell_of = tree.add("gas_cell_of", ti.i32, cap)           # -1: outside the span
        self.conductance = tree.add("gas_particle_conductance", real, cap)   # W/K
        self.cell_conductance = tree.add("gas_cell_conductance", real, n_cells)   # G_c W/K
        self.cell_weighted = tree.add("gas_cell_weighted", real, n_cells)         # S_c W
        self.cell_temperature = tree.add("gas_cell_temperature", real, n_cells)   # T_gc K
        self.exit_temperature = tree.add("gas_exit_temperature", real, n_cells)   # K
        # [heat flow to the particles in the last step W, its time integral J, outlet K]
        self.totals = tree.add("gas_totals", ti.f64, 3)
        # per-block partial cell sums (CPU): each block of particles sums into its own row with
        # plain stores; atomic adds from every particle onto a few cells cost more than the
        # pair kernel on the drum benchmark (BENCHMARKS.md). On a GPU atomics are cheap and
        # blocks would starve it, so there each particle adds atomically (``blocks`` = 0).
        arch = ti.lang.impl.current_cfg().arch
        self.blocks = BLOCKS if arch in (ti.x64, ti.arm64) else 0
        if self.blocks:
            self.partial_conductance = tree.add("gas_partial_conductance", real, (self.blocks, n_cells))
            self.partial_weighted = tree.add("gas_partial_weighted", real, (self.blocks, n_cells))
        self.state = state
        self.real = real

    def compile(self, values):
        """The stream's ti.funcs and kernel. The gas's values (its axis, span, speed, mass
        flow, inlet temperature and properties) are read at run time from ``values``
        (engine/values.py RuntimeValues): a changed value compiles nothing new; the number of
        cells, the flow's direction and the correlation are compiled in."""
        g = self.gas
        s = self.state
        n_cells = self.cells
        p0 = values.vector("plug_flow_axis_point", tuple(g.axis_point))
        axis = values.vector("plug_flow_axis_direction", tuple(g.axis_direction))
        u_gas = values.vector("plug_flow_velocity", tuple(g.velocity))
        inv_dx = values.scalar("plug_flow_inverse_cell_length", n_cells / g.length)
        length = values.scalar("plug_flow_length", g.length)
        # m_dot c_g, W/K
        capacity_rate = values.scalar("plug_flow_capacity_rate", g.mass_flow * g.heat_capacity)
        t_in = values.scalar("plug_flow_inlet_temperature", g.temperature)
        along = g.flow == "along_axis"
        re_factor = values.scalar("plug_flow_density_over_viscosity", g.density / g.viscosity)
        prandtl_cube_root = values.scalar(
            "plug_flow_prandtl_cube_root",
            (g.heat_capacity * g.viscosity / g.conductivity) ** (1.0 / 3.0))
        gunn = g.correlation == "gunn"
        porosity = values.scalar("plug_flow_porosity", g.porosity)
        k_gas = values.scalar("plug_flow_conductivity", g.conductivity)
        cell_of, G, GC, SC = self.cell_of, self.conductance, self.cell_conductance, self.cell_weighted
        TC, TX, totals = self.cell_temperature, self.exit_temperature, self.totals
        phi = ti.func(_phi)

        blocks = self.blocks
        PG = self.partial_conductance if blocks else None
        PS = self.partial_weighted if blocks else None

        @ti.func
        def particle_conductance(i):
            """(cell or -1, h A W/K) of particle i in the stream."""
            c = -1
            h_area = 0.0
            if s.alive[i] != 0:
                axial = (s.position[i] - p0()).dot(axis())
                if axial >= 0.0 and axial < length():
                    c = ti.min(ti.cast(axial * inv_dx(), ti.i32), n_cells - 1)
                    diameter = 2.0 * s.radius[i]
                    reynolds = re_factor() * diameter * (u_gas() - s.velocity[i]).norm()
                    nusselt = 0.0
                    if ti.static(gunn):
                        nusselt = gas_convection.nusselt_gunn(reynolds, prandtl_cube_root(),
                                                              porosity())
                    else:
                        nusselt = gas_convection.nusselt_ranz_marshall(reynolds,
                                                                       prandtl_cube_root())
                    h_area = gas_convection.convective_conductance(k_gas(), nusselt, diameter)
            cell_of[i] = c
            G[i] = h_area
            return c, h_area

        @ti.func
        def march(dt):
            """The gas from the inlet cell by cell: each cell's exchange with the particles in
            it (the sums GC, SC of this step), then those sums cleared; dt: the thermal step, s."""
            t_gas = ti.cast(t_in(), self.real)
            total = 0.0
            for k in range(n_cells):
                c = k
                if ti.static(not along):
                    c = n_cells - 1 - k
                if ti.static(blocks):
                    for b in range(blocks):
                        GC[c] = GC[c] + PG[b, c]      # (serial: no atomics)
                        SC[c] = SC[c] + PS[b, c]
                        PG[b, c] = 0.0
                        PS[b, c] = 0.0
                g_c = GC[c]
                t_out = t_gas
                t_seen = t_gas
                if g_c > 0.0:
                    t_particles = SC[c] / g_c
                    ntu = g_c / capacity_rate()
                    f = phi(ntu)                      # (1 - e^-NTU) / NTU
                    t_out = t_gas - (t_gas - t_particles) * ntu * f
                    t_seen = t_particles + (t_gas - t_particles) * f    # T_pc + Q_c / G_c
                    total += capacity_rate() * (t_gas - t_out)
                TC[c] = t_seen
                TX[c] = t_out
                GC[c] = 0.0
                SC[c] = 0.0
                t_gas = t_out
            totals[0] = ti.cast(total, ti.f64)
            totals[1] = totals[1] + ti.cast(total, ti.f64) * ti.cast(dt, ti.f64)
            totals[2] = ti.cast(t_gas, ti.f64)

        @ti.kernel
        def exchange(n: ti.i32, dt: self.real, serial_loops: ti.template()):
            if ti.static(blocks):
                ti.loop_config(serialize=serial_loops)
                for b in range(blocks):
                    chunk = (n + blocks - 1) // blocks
                    for i in range(b * chunk, ti.min(n, (b + 1) * chunk)):     # serial in a block
                        c, h_area = particle_conductance(i)
                        if c >= 0:
                            PG[b, c] = PG[b, c] + h_area                 # own row: no atomics
                            PS[b, c] = PS[b, c] + h_area * s.temperature[i]
            else:
                ti.loop_config(serialize=serial_loops)
                for i in range(n):
                    c, h_area = particle_conductance(i)
                    if c >= 0:
                        ti.atomic_add(GC[c], h_area)
                        ti.atomic_add(SC[c], h_area * s.temperature[i])
            ti.loop_config(serialize=True)
            for _ in range(1):           # one serial march from the inlet
                march(dt)

        @ti.func
        def exchange_serial(n, dt):
            """``exchange`` inside a loop that is already serial (Engine.run_steps): the
            particles' sums go straight onto their cells, then the march."""
            for i in range(n):
                c, h_area = particle_conductance(i)
                if c >= 0:
                    # (one thread - the serial mode, or worker 0 - so no atomics)
                    GC[c] = GC[c] + h_area
                    SC[c] = SC[c] + h_area * s.temperature[i]
            march(dt)

        @ti.func
        def particle_heat(i, temperature):
            """(Q W, G W/K) from the gas to particle i at ``temperature`` K."""
            q = 0.0 * temperature
            h_area = 0.0 * temperature
            c = cell_of[i]
            if c >= 0:
                h_area = G[i]
                q = h_area * (TC[c] - temperature)
            return q, h_area

        @ti.func
        def local_temperature(i):
            """(gas temperature seen in particle i's cell K, 1 if in the span else 0)."""
            c = cell_of[i]
            t = 0.0
            inside = 0
            if c >= 0:
                t = TC[c]
                inside = 1
            return t, inside

        self.exchange = exchange
        self.exchange_serial = exchange_serial
        self.particle_heat = particle_heat
        self.local_temperature = local_temperature

    def series(self) -> dict:
        """/series values (CONTRACT additions): the gas leaving each cell (K, cells in order
        along axis_direction), the outlet, the heat flow to the particles in the last step (W)
        and its integral since the start (J)."""
        import numpy as np
        t = self.totals.to_numpy()
        return {"gas/temperature": self.exit_temperature.to_numpy().astype(np.float64),
                "gas/outlet_temperature": float(t[2]), "gas/heat_flow": float(t[0]),
                "gas/transferred_heat": float(t[1])}
