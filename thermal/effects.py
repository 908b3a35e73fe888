"""The thermal effects, registered with the engine through the same declarations as every
other effect (taichi_dem/effects/base.py): the engine never imports ``thermal``; the scene's
effect list (taichi_dem/effects/__init__.py) brings these in only for a scene with [thermal].

contact stage (heat effects add a conductance, W/K, to the contact law's response):
  Conduction       particle-particle, through the Hertz contact spot (conduction.py)
  CollisionConduction  particle-particle, Sun & Chen's transient heat of short contacts
                   (``contact_conduction_model = "collision"``; conduction.py)
  WallConduction   particle-wall and particle-triangle, through the contact spot
  WallCollisionConduction  the same walls: Sun & Chen's heat while a wall contact is still
                   the impact it began as (``contact_conduction_model = "collision"``)
  GasGapWall       particle-wall and particle-body, through the gas gap (gas_gap.py)
  CoarseGrainedWall particles that stand for a finer bed: its contact resistance and
                   penetration to walls and bodies instead of the two above (coarse_grained.py)
particle stage (add heat W and conductance W/K to the particle's load):
  WallContactAge   how long each coarse-grained particle has rested against a wall
  Convection       a fixed (uniform) gas (convection.py)
  PlugFlowGas      the axial plug-flow gas; its cells march after the pair stage (plug_flow.py)
  Radiation        grey body to the gas, a surface or an enclosure (radiation.py)
integrate stage:
  Temperature      m c dT/dt = sum Q, explicit; with Drying (moisture.py) where wet
"""
from __future__ import annotations

import math
import sys

import numpy as np
import taichi as ti

from taichi_dem.effects.base import Effect
from taichi_dem.errors import DivergenceError
from taichi_dem.engine.regions import region_test
from taichi_dem.engine.precision import make_compensated_add

from . import coarse_grained as coarse
from . import convection as gas_convection
from .gas_gap_effects import (MODEL_WORDS, PAIR_SHARE, WALL_AGE_FIELDS, GasGapPair, GasGapWall, _gap_words,
                              _skips_coarse, first_layer_ratios, gas_gap_free_path)
from . import moisture as drying
from .radiation import Radiation
from .conduction import (SLOWEST_IMPACT, collision_conductance, collision_factor,
                         contact_conductance, hertz_contact_time, micro_coefficient,
                         rough_contact_conductance)


class Conduction(Effect):
    """Q = h_c (T_j - T_i), h_c = 4 k_i k_j/(k_i + k_j) a, a the Hertz contact radius
    sqrt(R* d_n), corrected for a softened modulus (conduction.py conduction_tables)."""

    name = "conduction"
    stage = "contact"
    kinds = ("pair",)
    tables = ("conductance_factor", "radius_correction")
    # the partner's share, stored at the owner's entry: heat W, conductance W/K
    pair_fields = PAIR_SHARE

    def __init__(self, description, rough=False):
        super().__init__(description)
        # rough spots (conduction.py): the asperities' resistance in series, compiled only
        # for a scene whose materials give surface_roughness, surface_slope and microhardness
        self.rough = bool(rough)
        if self.rough:
            self.tables = type(self).tables + ("spot_youngs", "spot_micro")

    def table_values(self, scene, tables):
        from taichi_dem.setup.pair_tables import effective_youngs_modulus
        from .conduction import conduction_tables
        factor, correction = conduction_tables(scene, tables.names)
        out = {"conductance_factor": factor, "radius_correction": correction}
        if self.rough:
            names = tables.names
            mats = [scene.materials[n] for n in names]
            out["spot_youngs"] = np.array([[effective_youngs_modulus(a, b) for b in mats]
                                           for a in mats])
            out["spot_micro"] = np.array([[micro_coefficient(
                a.thermal_conductivity, b.thermal_conductivity, a.surface_roughness,
                b.surface_roughness, a.surface_slope, b.surface_slope, a.microhardness,
                b.microhardness) for b in mats] for a in mats])
        return out

    def contact_func(self, ctx):
        factor, correction = ctx.table["conductance_factor"], ctx.table["radius_correction"]
        skip_coarse = _skips_coarse(self, ctx)
        rough = self.rough
        youngs = ctx.table["spot_youngs"] if rough else None
        micro = ctx.table["spot_micro"] if rough else None

        @ti.func
        def conduction(c, out):
            if c.normal_overlap > 0.0 and skip_coarse(c) == 0:
                if ti.static(rough):
                    out.conductance += rough_contact_conductance(
                        factor[c.material_i, c.material_j],
                        correction[c.material_i, c.material_j], c.r_eff, c.normal_overlap,
                        youngs[c.material_i, c.material_j], micro[c.material_i, c.material_j])
                else:
                    out.conductance += contact_conductance(
                        factor[c.material_i, c.material_j],
                        correction[c.material_i, c.material_j], c.r_eff, c.normal_overlap)
            return out

        return conduction


class CollisionConduction(Conduction):
    """Sun & Chen's collision conduction (conduction.py, Zhou, Yu & Zulli 2010's per-step
    flux), for particle pairs while a contact is still the collision it began as (its age below
    the Hertz duration of its impact): the heat the real collision passes, the larger of Sun &
    Chen's flux and the spot law with the real radius and duration, instead of the spot law
    Conduction adds (which keeps running: this effect adds the difference); the spot law alone
    once the contact has outlasted its collision (an enduring contact: a resting bed keeps it).

    Short contacts conduct more than the steady law, not less: heat that only has to penetrate
    a layer sqrt(kappa t) << a deep meets less resistance than the developed constriction field
    of the spot (the steady law is the long-time limit of the transient one). Over an elastic
    collision the ratio of the two heats is about 0.9 / sqrt(Fo), Fo = kappa t_c / a_max^2.

    It keeps a history per contact (the impact speed, the contact's age), so it runs with the
    contact law's mechanical effects (``mechanical``: on touching contacts that have a mass,
    with the contact's history) and adds its heat itself; it moves nothing."""

    name = "collision_conduction"
    mechanical = True
    # (impact speed m/s: the normal approach speed at the contact's first step; age s: the
    # simulated time the contact has lasted; t_c,sim s: the Hertz duration at that speed)
    contact_fields = {"collision_history": (True, "real")}
    pair_fields = {}

    def __init__(self, description, rough=False):
        super().__init__(description, rough)
        self.tables = self.tables + ("collision_factor", "collision_youngs_sim",
                                     "collision_spot_scale")

    def table_values(self, scene, tables):
        from taichi_dem.scene.model import Material
        from taichi_dem.setup.pair_tables import effective_youngs_modulus
        out = super().table_values(scene, tables)
        mats = [scene.materials[n] for n in tables.names]
        real = [Material(m.name, m.density, m.real_youngs_modulus or m.youngs_modulus,
                         m.poisson_ratio) for m in mats]
        out["collision_factor"] = np.array([[collision_factor(
            a.density, a.heat_capacity, a.thermal_conductivity, b.density, b.heat_capacity,
            b.thermal_conductivity) for b in mats] for a in mats])
        youngs_sim = np.array([[effective_youngs_modulus(a, b) for b in mats] for a in mats])
        youngs_real = np.array([[effective_youngs_modulus(a, b) for b in real] for a in real])
        out["collision_youngs_sim"] = youngs_sim
        # (E*_sim / E*_real)^1/5: the real spot radius over the simulated one at the same phase
        # of a collision at the same speed (and its square: the real duration over the simulated)
        out["collision_spot_scale"] = (youngs_sim / youngs_real) ** 0.2
        return out

    def contact_func(self, ctx):
        steady = super().contact_func(ctx)          # the spot law Conduction adds
        factor = ctx.table["collision_factor"]
        spot_factor = ctx.table["conductance_factor"]       # 2 k_s = 4 k_i k_j / (k_i + k_j)
        youngs_sim = ctx.table["collision_youngs_sim"]
        spot_scale = ctx.table["collision_spot_scale"]
        skip_coarse = _skips_coarse(self, ctx)         # (the wall variant's coarse-grained)
        Response = contact_response_type(ctx.real)
        vec0 = ti.Vector([0.0, 0.0, 0.0])

        @ti.func
        def collision_conduction(c, out, history, dt):
            state = history.collision        # (impact speed m/s, age s, t_c,sim s)
            mi, mj = c.material_i, c.material_j
            if state[1] == 0.0:
                # the contact's first step: the Hertz force has not acted yet, so the normal
                # approach speed is the impact speed (gravity's share of one step aside); the
                # simulated contact's Hertz duration follows from it once
                state[0] = ti.max(-c.v_rel.dot(c.normal), SLOWEST_IMPACT)
                state[2] = hertz_contact_time(c.m_eff, c.r_eff, youngs_sim[mi, mj], state[0])
            if c.conducts != 0 and factor[mi, mj] > 0.0 and state[1] < state[2] \
                    and skip_coarse(c) == 0:
                # still the collision: it passes the real collision's heat instead of the spot
                # law Conduction has already added (less where a softened modulus makes that
                # one pass too much)
                g_collision = collision_conductance(
                    factor[mi, mj], spot_factor[mi, mj], spot_scale[mi, mj], c.r_eff,
                    c.normal_overlap, state[2])
                spot = Response(force=vec0, torque_i=vec0, torque_j=vec0, heat=0.0,
                                conductance=0.0, normal_force=0.0, normal_stiffness=0.0)
                spot = steady(c, spot)
                extra = g_collision - spot.conductance
                out.conductance += extra
                out.heat += extra * c.temperature_difference
            state[1] += dt
            history.collision = state
            return out, history

        return collision_conduction


def contact_response_type(real):
    """The contact law's Response struct (contacts/geometry.py) in ``real`` precision."""
    from taichi_dem.contacts.geometry import contact_types
    return contact_types(real)[1]


class _OnWalls:
    """What a contact-spot law needs to run on particle-wall and particle-triangle contacts
    (mixed in before the pair law's class): no partner's share, and coarse-grained particles
    left alone where the scene has them (CoarseGrainedWall stands in for their wall heat)."""

    kinds = ("plane", "triangle")
    heats_walls = True
    pair_fields = {}

    def __init__(self, description, coarse_materials=False, rough=False):
        super().__init__(description, rough)
        self.skip_coarse = bool(coarse_materials)
        if self.skip_coarse:
            self.tables = self.tables + ("coarse_alpha_ws",)

    def table_values(self, scene, tables):
        out = super().table_values(scene, tables)
        if self.skip_coarse:
            out["coarse_alpha_ws"] = CoarseGrainedWall.tables_for(scene, tables)["coarse_alpha_ws"]
        return out


class WallConduction(_OnWalls, Conduction):
    """The contact-spot conduction to an isothermal wall or body (R* = r); not for coarse-
    grained particles (CoarseGrainedWall stands in)."""

    name = "wall_conduction"


class WallCollisionConduction(_OnWalls, CollisionConduction):
    """Sun & Chen's collision conduction on particle-wall and particle-triangle contacts
    (CollisionConduction's law with the wall as the second body: R* = r, m* = m, E* of the
    particle's and the wall's materials, the wall's rho c k in the collision factor; an
    isothermal wall is a semi-infinite body at its temperature, which is Sun & Chen's case).
    A particle that bounces off a shell or a flight passes the real impact's heat, then the
    spot law once it rests (WallConduction's). Not for coarse-grained particles, whose wall
    heat CoarseGrainedWall stands in for."""

    name = "wall_collision_conduction"


class CoarseGrainedWall(Effect):
    """Particles that stand for a finer bed (``[materials.X] coarse_grained``) take heat from
    walls and bodies as that bed would: G = w A_p h(t), h(t) = alpha_WS erfcx(alpha_WS
    sqrt(t/e)) (coarse_grained.py), t the thermal time since the particle came to rest
    against a wall (WallContactAge). On planes and on each body's nearest surface point, once
    per body; instead of the contact-spot and gas-gap laws for these particles."""

    name = "coarse_grained_wall"
    stage = "contact"
    kinds = ("plane", "surface")
    tables = ("coarse_alpha_ws", "coarse_effusivity_sq", "coarse_area_over_r2")
    particle_fields = WALL_AGE_FIELDS

    def __init__(self, description, reach, time_scale):
        super().__init__(description)
        self.reach = float(reach)        # of the radius: the gap at which the weight reaches 0
        self.margin = self.reach
        self.time_scale = float(time_scale)

    reference_temperature = staticmethod(coarse.reference_temperature)
    represented = staticmethod(coarse.represented)
    tables_for = staticmethod(coarse.tables_for)

    def table_values(self, scene, tables):
        return self.tables_for(scene, tables)

    def contact_func(self, ctx):
        s = ctx.state
        alpha_ws, effusivity_sq = ctx.table["coarse_alpha_ws"], ctx.table["coarse_effusivity_sq"]
        area_over_r2 = ctx.table["coarse_area_over_r2"]
        reach = self.reach
        # a step of thermal time, S dt (s), read at run time (engine/values.py)
        thermal_dt = ctx.values.scalar("thermal_dt", ctx.dt * self.time_scale)

        @ti.func
        def coarse_grained_wall(c, out):
            a = alpha_ws[c.material_i, c.material_j]
            if a > 0.0:
                # 1 touching, to 0 at a gap of `reach` radii: no jump as the particle lifts off
                weight = ti.min(1.0, 1.0 + c.normal_overlap / (ti.static(reach) * c.radius_i))
                if weight > 0.0:
                    i = c.particle
                    s.wall_touch[i] = 1
                    # the heat of this step: h at the middle of the step's thermal time
                    age = (s.wall_contact_steps[i] + 0.5) * thermal_dt()
                    h = coarse.bed_coefficient(a, effusivity_sq[c.material_i, c.material_j], age)
                    area = area_over_r2[c.material_i, c.material_j] * c.radius_i * c.radius_i
                    out.conductance += weight * h * area
            return out

        return coarse_grained_wall


class WallContactAge(Effect):
    """How many steps each coarse-grained particle has rested against a heat-exchanging wall
    or body without a break (what CoarseGrainedWall's h(t) reads): counted on while it
    touches, back to 0 the first step it does not."""

    name = "wall_contact_age"
    stage = "particle"

    def particle_func(self, ctx):
        s = ctx.state

        @ti.func
        def wall_contact_age(i, load):
            if s.wall_touch[i] != 0:
                s.wall_contact_steps[i] = s.wall_contact_steps[i] + 1   # (no atomic: see Engine)
                s.wall_touch[i] = 0
            else:
                s.wall_contact_steps[i] = 0
            return load

        return wall_contact_age


class Convection(Effect):
    """Convection to a fixed gas, Q = h A (T_g - T_p), h = k_g Nu / d (PHYSICS.md)."""

    name = "convection"
    stage = "particle"

    def __init__(self, description, gas):
        super().__init__(description)
        self.gas = gas

    def particle_func(self, ctx):
        s = ctx.state
        gas = self.gas
        # the gas's values read at run time (engine/values.py): a changed gas compiles
        # nothing new; the correlation is compiled in
        values = ctx.values
        gas_velocity = values.vector("convection_gas_velocity", tuple(gas.velocity))
        prandtl_cube_root = values.scalar(
            "convection_prandtl_cube_root",
            (gas.heat_capacity * gas.viscosity / gas.conductivity) ** (1.0 / 3.0))
        density_over_viscosity = values.scalar("convection_density_over_viscosity",
                                               gas.density / gas.viscosity)
        gunn = gas.correlation == "gunn"
        porosity = values.scalar("convection_porosity", gas.porosity)
        k_gas = values.scalar("convection_gas_conductivity", gas.conductivity)
        t_gas = values.scalar("convection_gas_temperature", gas.temperature)

        @ti.func
        def convection(i, load):
            diameter = 2.0 * s.radius[i]
            reynolds = (density_over_viscosity() * diameter
                        * (gas_velocity() - s.velocity[i]).norm())
            nusselt = 0.0
            if ti.static(gunn):
                nusselt = gas_convection.nusselt_gunn(reynolds, prandtl_cube_root(), porosity())
            else:
                nusselt = gas_convection.nusselt_ranz_marshall(reynolds, prandtl_cube_root())
            h_gas = gas_convection.convective_conductance(k_gas(), nusselt, diameter)
            load.heat += h_gas * (t_gas() - s.temperature[i])
            load.conductance += h_gas
            return load

        return convection


class PlugFlowGas(Effect):
    """Convection to the axial plug-flow gas of the particle's cell; the gas itself marches
    cell by cell between the pair and the particle stages (``after_pairs``)."""

    name = "plug_flow_convection"
    stage = "particle"

    def __init__(self, description, gas, time_scale=1.0):
        super().__init__(description)
        self.gas = gas
        self.time_scale = float(time_scale)      # thermal.time_scale: the gas's step is S dt
        self.stream = None                       # the AxialPlugFlowGas, once allocated

    def allocate(self, ctx, tree):
        from .plug_flow import AxialPlugFlowGas
        self.stream = AxialPlugFlowGas(self.gas, ctx.state, tree, ctx.real)

    def prepare(self, ctx):
        self.stream.compile(ctx.values)

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """The gas stream's series (gas/...: thermal/plug_flow.py)."""
        values.update(self.stream.series())

    def after_pairs(self, ctx, n, dt):
        """The per-cell stage: the gas sees this step's particles (W, K); its energy
        integral advances by the thermal step (S dt)."""
        self.stream.exchange(n, dt * self.time_scale, ctx.serial)

    def cell_func(self, ctx):
        """``after_pairs`` as a ti.func (n, dt) for a loop that is already serial
        (engine/drivers.py run_steps, several steps in one launch)."""
        exchange = self.stream.exchange_serial
        # thermal.time_scale, read at run time (engine/values.py)
        time_scale = ctx.values.scalar("thermal_time_scale", self.time_scale)

        @ti.func
        def gas_march(n, dt):
            exchange(n, dt * time_scale())
        return gas_march

    def particle_func(self, ctx):
        s = ctx.state
        stream = self.stream

        @ti.func
        def plug_flow_convection(i, load):
            q_gas, g_gas = stream.particle_heat(i, s.temperature[i])
            load.heat += q_gas
            load.conductance += g_gas
            return load

        return plug_flow_convection


class PlugFlowStream(Effect):
    """The axial plug-flow gas itself (listed so ``taichi-dem check`` shows it; its work is
    done by PlugFlowGas)."""
    name = "plug_flow_gas"
    stage = "cell"


def _split_writer(field, residual, real):
    """ti.func (i, value): ``field[i] = value`` from an f64 value; with a ``residual`` field the
    value is kept in f64 as the sum of the two (engine/precision.py: f32 far from zero)."""
    _, split_f64 = make_compensated_add(real)
    split = residual is not None

    @ti.func
    def write(i, value):
        if ti.static(split):
            part, rest = split_f64(value)
            field[i] = part
            residual[i] = rest
        else:
            field[i] = ti.cast(value, real)

    return write


class Drying(Effect):
    """Moisture: evaporation at T_e (moisture.py); run by the Temperature update."""

    name = "drying"
    stage = "integrate"

    def __init__(self, description, thermal, compensated):
        super().__init__(description)
        self.constants = (thermal.evaporation_temperature, thermal.latent_heat,
                          thermal.water_heat_capacity)
        self.critical_moisture = float(thermal.critical_moisture)     # kg/kg (0: none)
        self.particle_fields = {"moisture": (False, "real")}
        if compensated:
            self.particle_fields["moisture_residual"] = (False, "f64")

    # J into the particles since the start (energy_balance.py): the vapour leaves with
    # L + c_w T_e per kg (moisture.py)
    energy_terms = {"thermal/vapour_heat": -1.0}

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """particles/mean_moisture (kg/kg), particles/evaporated_mass (kg so far) and
        thermal/vapour_heat: J the evaporated water carried off since the start."""
        t_e, latent, c_w = self.constants
        values["particles/mean_moisture"] = measured["mean_moisture"]
        values["particles/evaporated_mass"] = measured["evaporated_mass"]
        values["thermal/vapour_heat"] = measured["evaporated_mass"] * (latent + c_w * t_e)

    def allocate(self, ctx, tree):
        self.evaporated = tree.add("evaporated", ti.f64, 1)      # kg since the start
        self.sums = tree.add("moisture_sums", ti.f64, 2)          # kg water, kg dry solid

    def inserted_values(self, ctx):
        """An inserted particle's moisture (kg water per kg dry solid)."""
        s = ctx.state
        residual = s.moisture_residual if "moisture_residual" in self.particle_fields else None
        return [("moisture", _split_writer(s.moisture, residual, ctx.real))]

    def measure_funcs(self, ctx):
        """At a sample: mean_moisture (kg water per kg dry solid, NaN without particles) and
        evaporated_mass (kg since the start)."""
        s, sums = ctx.state, self.sums
        compensated = "moisture_residual" in self.particle_fields

        @ti.func
        def reset():
            sums[0] = 0.0
            sums[1] = 0.0

        @ti.func
        def particle(i):
            water = ti.cast(s.moisture[i], ti.f64)
            if ti.static(compensated):
                water += s.moisture_residual[i]
            sums[0] += ti.cast(s.mass[i], ti.f64) * water
            sums[1] += ti.cast(s.mass[i], ti.f64)

        def read(arrays):
            (water, dry), evaporated = arrays
            return {"mean_moisture": float(water / dry) if dry else math.nan,
                    "evaporated_mass": float(evaporated[0])}

        return reset, particle, [self.sums, self.evaporated], read


class Temperature(Effect):
    """The explicit temperature update m c dT/dt = sum Q (stable while dt sum(h)/(m c) < 1,
    checked per sample). In f32 scenes the temperature carries an f64 residual
    (engine/precision.py) so that per-step changes below the f32 spacing are kept."""

    name = "temperature"
    stage = "integrate"
    # the contacts' heat is driven by temperature differences (K): the engine carries it
    conducted_field = "temperature"

    def __init__(self, description, compensated, time_scale=1.0):
        super().__init__(description)
        self.compensated = compensated
        self.warned = False          # the near-limit warning is printed once
        # heat capacities divided by S: the energy Q dt of a step changes T by S Q dt/(m c)
        self.time_scale = float(time_scale)
        self.particle_fields = {"temperature": (False, "real"),
                                "inverse_thermal_mass": (False, "real")}
        if compensated:
            self.particle_fields["temperature_residual"] = (False, "f64")

    def source_values(self, scene, source, names, material, mass) -> dict:
        """A fill's or factory's particles' temperature (K: the source's, or a fill's own
        from a results file; NaN where none is given), their 1 / (m (c + X c_w)) (1/(J/K):
        a wet particle's water counts) and, drying, their moisture X (kg/kg; else dry)."""
        th, n = scene.settings.get("thermal"), len(mass)
        frame = getattr(source, "frame_values", {})     # (a fill's, from a results file)
        own_t = source.temperature is None and frame.get("temperature") is not None
        temperature = (np.asarray(frame["temperature"], float) if own_t else
                       np.full(n, np.nan if source.temperature is None else source.temperature))
        heat_capacity = np.array([scene.materials[m].heat_capacity or 0.0 for m in names])[material]
        if not th.moisture:
            return {"temperature": temperature,
                    "inverse_thermal_mass": 1.0 / (mass * heat_capacity)}
        own_x = source.moisture is None and frame.get("moisture") is not None
        x = np.asarray(frame["moisture"], float) if own_x else np.full(n, source.moisture or 0.0)
        return {"temperature": temperature, "moisture": x,
                "inverse_thermal_mass": 1.0 / (mass * (heat_capacity + x * th.water_heat_capacity))}

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """particles/mean_temperature: K, weighted by the particles' heat capacities."""
        values["particles/mean_temperature"] = measured["mean_temperature"]

    def allocate(self, ctx, tree):
        # f64 sums at a sample (an f32 sum of m c T at 723 K would round a heat balance away):
        # sum m c T (J), sum m c (J/K), the largest dt sum(h)/(m c), a non-finite flag
        self.sums = tree.add("temperature_sums", ti.f64, 4)

    def inserted_values(self, ctx):
        """An inserted particle's temperature (K) and its 1 / (m c) (1/(J/K))."""
        s, real = ctx.state, ctx.real
        residual = s.temperature_residual if self.compensated else None
        return [("temperature", _split_writer(s.temperature, residual, real)),
                ("inverse_thermal_mass", _split_writer(s.inverse_thermal_mass, None, real))]

    def measure_funcs(self, ctx):
        """At a sample: thermal_energy (sum m c T, J), mean_temperature (K, NaN without
        particles), thermal_step_ratio (the largest dt sum(h)/(m c), dt the thermal step S x
        dt: ``check`` reads it), and a NaN or overflowed temperature as non_finite."""
        s, sums = ctx.state, self.sums
        compensated = self.compensated
        # the thermal step S dt (s), read at run time: a changed dt or time scale compiles
        # nothing new (engine/values.py)
        thermal_dt = ctx.values.scalar("thermal_dt", ctx.dt * self.time_scale)

        @ti.func
        def reset():
            for k in ti.static(range(4)):
                sums[k] = 0.0

        @ti.func
        def particle(i):
            thermal_mass = 1.0 / ti.cast(s.inverse_thermal_mass[i], ti.f64)
            temperature = ti.cast(s.temperature[i], ti.f64)
            if ti.static(compensated):
                temperature += s.temperature_residual[i]
            sums[0] += thermal_mass * temperature
            sums[1] += thermal_mass
            ti.atomic_max(sums[2], ti.cast(thermal_dt() * s.conductance[i]
                                           * s.inverse_thermal_mass[i], ti.f64))
            if not (s.temperature[i] > 0.0 and s.temperature[i] < 1e30):
                sums[3] = 1.0

        def read(arrays):
            energy, thermal_mass, ratio, bad = arrays[0]
            return {"thermal_energy": float(energy),
                    "mean_temperature": float(energy / thermal_mass) if thermal_mass else math.nan,
                    "thermal_step_ratio": float(ratio), "non_finite": bool(bad > 0)}

        return reset, particle, [self.sums], read

    def run_observers(self, sim) -> dict:
        """The heat flows into isothermal walls and bodies (wall_heat_flows.py), then the
        particles' energy balance that integrates them (energy_balance.py), under the name
        checkpoints keep its state by."""
        from .energy_balance import EnergyBalance
        from .wall_heat_flows import WallHeatFlows
        return {"wall_heat_flows": WallHeatFlows(sim), "energy": EnergyBalance(sim)}

    def check(self, sim, measured: dict) -> None:
        """The explicit update T += dt sum(Q)/(m c) is stable while dt sum(h)/(m c) < 1 for
        every particle (h the conductances of its contacts, gas gap, convection, linearised
        radiation; dt the thermal step S x simulation.dt): stop beyond 1, warn once past 0.5."""
        ratio = measured["thermal_step_ratio"]
        if ratio >= 1.0:
            raise DivergenceError(
                f"the temperature update is unstable at t = {sim.time:.6g} s: dt sum(h)/(m c) = "
                f"{ratio:.3g} >= 1 for some particle (dt the thermal step, thermal.time_scale x "
                f"simulation.dt). Reduce simulation.dt or thermal.time_scale (by {ratio:.2g}x at "
                f"least), or raise heat_capacity/lower thermal_conductivity if they are scaled")
        if ratio >= 0.5 and not self.warned:
            self.warned = True
            print(f"taichi-dem: warning: at t = {sim.time:.4g} s dt sum(h)/(m c) = {ratio:.3g}: "
                  f"the temperature update is near its stability limit (1)", file=sys.stderr)

    def integrate_func(self, ctx):
        """ti.func (i, load, dt s): the particle's new temperature from the load's heat (W)
        and its conductance (W/K, kept for the stability check), and its moisture when the
        scene dries (the drying effect's constants): explicit, stable while
        dt sum(h) / (m c) < 1 (``check``, per sample)."""
        drying_effect = ctx.effect("drying")
        s = ctx.state
        real = ctx.real
        compensated = self.compensated
        moisture = drying_effect is not None
        compensated_add, split_f64 = make_compensated_add(real)
        falling_rate = False
        evaporated = None
        # the drying constants read at run time (engine/values.py): a changed evaporation
        # temperature, latent heat, water heat capacity or critical moisture compiles nothing
        # new (whether there is a falling rate, X_cr > 0, is compiled in: 0 compiles it away)
        t_evap_of = latent_of = c_water_of = critical_of = None
        if moisture:
            t_e, l_v, c_w = drying_effect.constants
            t_evap_of = ctx.values.scalar("evaporation_temperature", t_e)
            latent_of = ctx.values.scalar("latent_heat", l_v)
            c_water_of = ctx.values.scalar("water_heat_capacity", c_w)
            falling_rate = drying_effect.critical_moisture > 0.0
            critical_of = ctx.values.scalar("critical_moisture", drying_effect.critical_moisture)
            evaporated = drying_effect.evaporated

        # thermal.time_scale S, read at run time (engine/values.py): one kernel for every S
        # (S = 1 multiplies by 1, exactly)
        scale = ctx.values.scalar("thermal_time_scale", self.time_scale)

        @ti.func
        def update_temperature(i, heat, conductance, dt_mechanics):
            dt = dt_mechanics * scale()      # the thermal step
            if ti.static(moisture and compensated):
                # in f64 throughout, then split back (engine/precision.py)
                t_new, x_new, inv_c, dm = drying.heat_and_dry(
                    ti.cast(s.temperature[i], ti.f64) + s.temperature_residual[i],
                    ti.cast(s.moisture[i], ti.f64) + s.moisture_residual[i],
                    ti.cast(s.inverse_thermal_mass[i], ti.f64),
                    ti.cast(s.mass[i], ti.f64), ti.cast(dt * heat, ti.f64),
                    ti.cast(t_evap_of(), ti.f64), ti.cast(latent_of(), ti.f64),
                    ti.cast(c_water_of(), ti.f64), ti.cast(critical_of(), ti.f64),
                    ti.static(falling_rate))
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
                    s.mass[i], dt * heat, t_evap_of(), latent_of(), c_water_of(), critical_of(),
                    ti.static(falling_rate))
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
                # (``a = a + b``: ``+=`` on a field is an atomic add on the engine's workers)
                s.temperature[i] = s.temperature[i] + dt * heat * s.inverse_thermal_mass[i]
            s.conductance[i] = conductance

        @ti.func
        def integrate(i, load, dt):
            update_temperature(i, load.heat, load.conductance, dt)

        return integrate


def thermal_effects(scene) -> list:
    """The thermal effects ``scene`` calls for, in step order (none without [thermal])."""
    th = scene.settings.get("thermal")
    if th is None:
        return []
    compensated = scene.simulation.precision != "f64"
    scaled = (f"; heat capacities / {th.time_scale:g} (thermal time = {th.time_scale:g} x "
              f"simulated time)") if th.time_scale != 1.0 else ""
    out = [Temperature("explicit temperature update, m c dT/dt = sum Q" + scaled, compensated,
                       th.time_scale)]
    free_path = gas_gap_free_path(scene) if th.gas_gap and th.gas_gap_model == "schlunder" else 0.0
    rough = any(m.microhardness is not None for m in scene.materials.values())
    spot = "; rough spots: the asperities in series (Yovanovich)" if rough else ""
    if th.conduction:
        out.append(Conduction(f"particle-particle conduction (contact radius correction: "
                              f"{th.contact_radius_correction}{spot})", rough))
        if th.contact_conduction_model == "collision":
            out.append(CollisionConduction(
                "collision conduction between particles (Sun & Chen 1988; Zhou, Yu & Zulli "
                "2010): the larger of it and the spot law while a contact lasts no longer than "
                "the Hertz duration of its impact, the spot law after", rough))
        if th.gas_gap and th.gas_gap_pairs:
            out.append(GasGapPair(
                f"conduction through the gas gap between particles (fluid lens "
                f"{th.gas_gap_lens:g} R, {_gap_words(th, free_path)}, k_g "
                f"{th.gap_gas_conductivity:g} W/(m K); {MODEL_WORDS[th.gas_gap_model]}; pairs "
                f"within the lens are listed and handed to the contact law)",
                th.gap_gas_conductivity, th.gas_gap_lens, th.gas_gap_min_gap, th.gas_gap_model,
                th.gas_gap_porosity, free_path=free_path,
                solids={name: (m.thermal_conductivity, m.surface_roughness or 0.0)
                        for name, m in scene.materials.items()
                        if m.thermal_conductivity is not None}))
    hot = [w.name for w in list(scene.walls) + list(scene.bodies) if w.temperature is not None]
    coarse_names = sorted(n for n, m in scene.materials.items() if m.coarse_grained is not None)
    if th.wall_conduction and hot:
        but = (f" (not for {', '.join(coarse_names)}: coarse-grained)") if coarse_names else ""
        out.append(WallConduction("conduction to isothermal " + ", ".join(hot) + but + spot,
                                  coarse_materials=bool(coarse_names), rough=rough))
        if th.contact_conduction_model == "collision":
            out.append(WallCollisionConduction(
                "collision conduction to " + ", ".join(hot) + but + " (Sun & Chen 1988, the "
                "wall a semi-infinite body at its temperature): while a wall contact lasts no "
                "longer than the Hertz duration of its impact, the spot law after",
                coarse_materials=bool(coarse_names), rough=rough))
        if coarse_names:
            words = "; ".join(
                f"{n} for {scene.materials[n].coarse_grained.represented_diameter * 1e6:g} um "
                f"particles, bed porosity {scene.materials[n].coarse_grained.bed_porosity:g}"
                for n in coarse_names)
            out.append(CoarseGrainedWall(
                f"coarse-grained particles to {', '.join(hot)} as the bed they stand for: "
                f"Schlünder's contact coefficient in series with penetration for the time each "
                f"has rested on the wall ({words}; reach {th.coarse_reach:g} R)",
                th.coarse_reach, th.time_scale))
            out.append(WallContactAge("the time each coarse-grained particle has rested "
                                      "against a wall or body"))
        if th.gas_gap:
            widened = th.gas_gap_model == "schlunder"
            out.append(GasGapWall(
                f"conduction through the gas gap to {', '.join(hot)} (fluid lens "
                f"{th.gas_gap_lens:g} R, {_gap_words(th, free_path)}, k_g "
                f"{th.gap_gas_conductivity:g} W/(m K); {MODEL_WORDS[th.gas_gap_model]})",
                th.gap_gas_conductivity, th.gas_gap_lens, th.gas_gap_min_gap, th.gas_gap_model,
                th.gas_gap_porosity, coarse_materials=bool(coarse_names),
                free_path=free_path, time_scale=th.time_scale,
                first_layer_ratios=first_layer_ratios(scene, free_path) if widened else None))
            if widened and not coarse_names:
                out.append(WallContactAge("the time each particle has rested against a wall "
                                          "or body (the first layer's transient resistance)"))
    gas = th.gas
    if gas is not None and not gas.plug_flow:
        out.append(Convection(f"convection to a {gas.model} gas at {gas.temperature:g} K "
                              f"({gas.correlation})", gas))
    if gas is not None and gas.plug_flow:
        speed = sum(c * c for c in gas.velocity) ** 0.5
        out.append(PlugFlowGas(f"convection to the plug-flow gas of the particle's cell "
                               f"({gas.correlation}, u = {speed:.3g} m/s)", gas, th.time_scale))
        out.append(PlugFlowStream(
            f"axial plug-flow gas: {gas.cells} cells over {gas.length:g} m "
            f"{gas.flow.replace('_', ' ')}, {gas.mass_flow:g} kg/s in at "
            f"{gas.temperature:g} K, energy balance per cell"))
    if th.radiation:
        to = {"gas": "the local gas temperature",
              "surface": f"'{th.radiation_surface}' at {th.radiation_temperature or 0:g} K",
              "enclosure": f"an enclosure at {th.radiation_temperature or 0:g} K"}[th.radiation_to]
        where = " inside radiation_region" if th.radiation_region is not None else ""
        out.append(Radiation(f"grey-body radiation to {to}{where} (no shadowing)", th,
                             {k: m.emissivity for k, m in scene.materials.items()}))
    if th.moisture:
        falling = (f", falling rate below {th.critical_moisture:g} kg/kg"
                   if th.critical_moisture > 0.0 else "")
        out.append(Drying(f"moisture: evaporation at {th.evaporation_temperature:g} K, "
                          f"latent heat {th.latent_heat:g} J/kg{falling}", th, compensated))
    return out


def build(scene, settings) -> list:
    """The heat transfer's effects for a scene whose [thermal] reads as ``settings``
    (scene.settings.get("thermal")), by its section's ``builds`` (effects/registry.py)."""
    return list(thermal_effects(scene))
