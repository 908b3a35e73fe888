"""Drag from a gas on the particles (one-way coupled: the gas is given, the particles do not
push it back). PHYSICS.md "Drag"; issue 15 item 3.

With u the gas's interstitial velocity (its superficial velocity U over the local voidage
eps), v the particle's, w = u - v the slip, d the diameter:

    F = 1/2 C_D rho_g pi d^2/4 |w| w f(eps)

    schiller_naumann (a dilute particle, f = 1):
        C_D = 24/Re (1 + 0.15 Re^0.687) for Re < 1000, 0.44 above;   Re = rho_g |w| d / mu
    di_felice (Di Felice 1994, a particle in a suspension or bed):
        C_D = (0.63 + 4.8 / sqrt(Re))^2,  Re = rho_g eps |w| d / mu,
        f = eps^(2 - chi),  chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2)

That F is the drag proper. The gas's pressure gradient, which in a steady flow through the
particles balances the drag on them, -grad p = n F / eps (n particles per volume), pushes
each particle too, with V_p (-grad p) = F (1 - eps)/eps: the particle feels F / eps in all
("model B" of Zhou, Kuang, Chu & Yu 2010, J. Fluid Mech. 661:482; the hydrostatic part of
the gas's weight, rho_g/rho_p ~ 5e-4 of gravity, is left out). Summed over a packed bed per
unit volume this is the bed's pressure gradient, compared with Ergun in
tests/verification/test_drag.py. The local voidage is the grid's: the solid volume
of the particles whose centres lie in the 3 x 3 x 3 block of contact cells around the
particle's cell (cells are >= one diameter, so the block spans >= 3 diameters and holds tens of
particles in a bed), over the block's volume, clamped to [0.1, 1]. It is recomputed every step
(the cell stage) from the cells assigned at the last rebuild (particles have moved less than
half the skin since).

Where the gas goes (``through_bed``). A gas forced up through a bed on a distributor (Ergun,
fluidisation) flows through every packing, and the law above acts on every particle. In a
drum it does not: the gas takes the open section, whose resistance is a few pascals over the
drum, and goes round the bed and the flights' loads, whose pores would need orders of
magnitude more (Ergun at the superficial velocity). Dragged as if the gas went through it, a
loose bed in a dryer's 3.7 m/s gas is pushed along the axis at 1.8 - 3.1x the slope's pull
(docs/machine/dryer_slice/dryer.md). So by default (``through_bed = false``) a particle feels
the gas only while no contact touches it (the load's ``touching``: no contact force on it, and
not held at rest by mobility), i.e. while it falls in a curtain. What this leaves out, the
drag of the gas sweeping over the bed's surface, is bounded by the same slice with every
particle dragged as if alone in the gas (Schiller-Naumann at the full slip, an upper bound
for a half-sunk sphere): the part of the flow that the bed and flights carry moved by nothing
measurable (dryer.md). ``velocity`` is then the gas's velocity in the open section. At a fixed
hold-up the slices then follow Friedman and Marshall's gas term up to 3.7 m/s (dryer.md).
"""
import math

import taichi as ti

from ..base import Effect


class Drag(Effect):
    name = "drag"
    # its acceleration added after gravity's, as it always was (gravity was built first):
    # the order of the sums, and so the last bits of every result, stay what they were
    after = ("gravity",)
    stage = "particle"

    def __init__(self, description, drag):
        super().__init__(description)
        self.drag = drag

    def allocate(self, ctx, tree):
        g = ctx.grid
        # (a bucket of cells, as the neighbour search's: the count is read at run time)
        self.cell_solid = tree.add("drag_cell_solid", ctx.real, g.cell_capacity)      # m^3
        # the force on each particle in the last step, N (for the sensors; not state)
        self.force = tree.add("drag_force", ctx.real, ctx.state.capacity, vector=True)
        self._compile_cells(ctx)

    def _compile_cells(self, ctx):
        s = ctx.state
        cell_solid = self.cell_solid
        n_cells_of = ctx.grid.layout_funcs()[5]

        @ti.kernel
        def solid_per_cell(n: ti.i32, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for c in range(n_cells_of()):
                cell_solid[c] = 0.0
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                if s.alive[i] != 0:
                    r = s.radius[i]
                    ti.atomic_add(cell_solid[s.cell[i]], 4.0 / 3.0 * math.pi * r * r * r)

        self._solid_per_cell = ctx.serial_switch(solid_per_cell)

        @ti.func
        def solid_per_cell_serial(n, dt):
            """The same inside a loop that is already serial (drivers.run_steps)."""
            for c in range(n_cells_of()):
                cell_solid[c] = 0.0
            for i in range(n):
                if s.alive[i] != 0:
                    r = s.radius[i]
                    c = s.cell[i]     # (one thread - serial mode, or worker 0: no atomics)
                    cell_solid[c] = cell_solid[c] + 4.0 / 3.0 * math.pi * r * r * r

        self._solid_per_cell_serial = solid_per_cell_serial

    def after_pairs(self, ctx, n, dt):
        """The cell stage: solid volume per contact cell (m^3)."""
        self._solid_per_cell(n)

    def cell_func(self, ctx):
        """``after_pairs`` as a ti.func (n, dt) for drivers.run_steps."""
        return self._solid_per_cell_serial

    def particle_func(self, ctx):
        s = ctx.state
        g = ctx.grid
        d = self.drag
        # the gas and the cells read at run time (engine/values.py): another gas velocity
        # or density compiles nothing
        values = ctx.values
        cell_volume_of = values.scalar("drag_cell_volume",
                                       float(g.cell_size[0] * g.cell_size[1] * g.cell_size[2]))
        cell_solid = self.cell_solid
        force_field = self.force
        superficial_of = values.vector("drag_superficial_velocity", tuple(d.velocity))
        rho_of = values.scalar("drag_gas_density", d.density)
        rho_over_mu_of = values.scalar("drag_density_over_viscosity", d.density / d.viscosity)
        di_felice = d.model == "di_felice"
        through_bed = bool(d.through_bed)

        _, coordinates, neighbour = g.make_cell_arithmetic()

        @ti.func
        def voidage(i):
            v = coordinates(s.cell[i])
            solid = 0.0 * s.radius[i]
            cells = 0
            for offset in range(27):
                nb, inside = neighbour(v, offset)
                if inside:
                    solid += cell_solid[nb]
                    cells += 1
            return ti.min(ti.max(1.0 - solid / (cells * cell_volume_of()), 0.1), 1.0)

        @ti.func
        def drag(i, load):
            diameter = 2.0 * s.radius[i]
            feels_gas = True
            if ti.static(not through_bed):
                # the gas goes round packings: a particle any contact touches feels none of it
                feels_gas = load.touching == 0
            eps = 1.0 + 0.0 * diameter
            if ti.static(di_felice):
                if feels_gas:
                    eps = voidage(i)
            slip = superficial_of() / eps - s.velocity[i]
            rho, rho_over_mu = rho_of(), rho_over_mu_of()
            speed = slip.norm()
            force = slip * 0.0
            if speed > 0.0 and feels_gas:
                area = 0.25 * math.pi * diameter * diameter
                if ti.static(di_felice):
                    reynolds = rho_over_mu * eps * speed * diameter
                    c_d = (0.63 + 4.8 / ti.sqrt(reynolds)) ** 2
                    lg = ti.log(reynolds) / ti.log(10.0)
                    chi = 3.7 - 0.65 * ti.exp(-0.5 * (1.5 - lg) ** 2)
                    # drag, and the pressure gradient that balances it: F / eps (docstring)
                    force = 0.5 * c_d * rho * area * speed * slip * eps ** (1.0 - chi)
                else:
                    reynolds = rho_over_mu * speed * diameter
                    c_d = 0.44 + 0.0 * reynolds
                    if reynolds < 1000.0:
                        c_d = 24.0 / reynolds * (1.0 + 0.15 * reynolds ** 0.687)
                    force = 0.5 * c_d * rho * area * speed * slip
            force_field[i] = force
            load.acceleration += force * s.inverse_mass[i]
            return load

        return drag

    def total_force(self, n: int):
        """The drag on all particles in the last step (N, a 3-vector)."""
        import numpy as np
        return self.force.to_numpy()[:n].astype(np.float64).sum(axis=0)

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """Its series at an output sample (declared in settings.py SERIES): the gas's pull on
        the ``n`` slots' particles in the last step."""
        values["gas/drag_force"] = self.total_force(n)


def build(scene, settings) -> list:
    """The effect for a scene's drag ``settings`` (DragSettings: from [gas] or [thermal.gas])."""
    speed = sum(c * c for c in settings.velocity) ** 0.5
    where = ("forced through the packings" if settings.through_bed
             else "round the packings: only particles touching nothing feel it")
    return [Drag(f"gas drag ({settings.model.replace('_', '-')}"
                 + (", local voidage from the cell grid" if settings.model == "di_felice" else "")
                 + f"), gas velocity {speed:.3g} m/s, {where}, one-way", settings)]
