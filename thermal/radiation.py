"""Radiation between a particle and what surrounds it (PHYSICS.md), for a dryer's burner zone:

    Q = eps_p sigma A_p (T_s^4 - T_p^4),   A_p = 4 pi r^2

Model: each particle (inside the optional ``radiation_region``) is a small grey sphere inside
a large isothermal grey enclosure at T_s - the local gas temperature (``radiation_to =
"gas"``: a flame / optically thick hot gas), an isothermal wall or body, or a given
temperature. For a small body in a large enclosure the grey-body exchange factor
1 / (1/eps_p + (A_p/A_s)(1/eps_s - 1)) tends to eps_p, so only the particle's emissivity
enters. Limits, said plainly: no view factors and no shadowing - a particle buried in the bed
radiates as freely as one on its surface, so restrict the exchange to where the bed surface
faces the source with ``radiation_region`` (and expect an overestimate inside it); no
particle-particle radiation; the gas neither absorbs nor is cooled by it (the plug-flow energy
balance carries convection only), and with a plug-flow gas a particle outside the gas's axial
span does not radiate (it has no gas temperature).

Stability of the explicit update: the exchange is linearised as the conductance
4 eps sigma A T^3 with T = max(T_p, T_s) (dQ/dT_p is 4 eps sigma A T_p^3; the larger T bounds
the secant too), added to the particle's sum of conductances.
"""
import numpy as np
import taichi as ti

from taichi_dem.effects.base import Effect
from taichi_dem.engine.regions import region_test

STEFAN_BOLTZMANN = 5.670374419e-8      # W/(m^2 K^4)


@ti.func
def exchange(emissivity, radius, surroundings_temperature, particle_temperature):
    """(Q W into the particle, linearised conductance W/K) for a sphere of ``radius`` m."""
    area = 4.0 * 3.141592653589793 * radius * radius
    k = emissivity * STEFAN_BOLTZMANN * area
    ts = surroundings_temperature
    tp = particle_temperature
    hot = ti.max(ts, tp)
    return k * (ts * ts * ts * ts - tp * tp * tp * tp), 4.0 * k * hot * hot * hot


class Radiation(Effect):
    """Grey-body exchange with the gas, a surface or an enclosure (no shadowing)."""

    name = "radiation"
    stage = "particle"

    # J into the particles since the start (thermal/energy_balance.py books every declared term)
    energy_terms = {"thermal/radiated_heat": 1.0}

    def __init__(self, description, thermal, emissivities):
        super().__init__(description)
        self.thermal = thermal
        self.emissivities = dict(emissivities)     # material name -> grey-body emissivity
        self.emissivity = None                     # per material index, once allocated
        # this step's radiant heat into each particle (W), booked by integrate_func at the
        # step's dt: the particle stage does not know the step (a start pass has dt = 0)
        self.particle_fields = {"radiated_power": (False, "real")}

    def allocate(self, ctx, tree):
        self.emissivity = tree.add("emissivity", ctx.real, len(ctx.material_names))
        self.radiated = tree.add("radiated_heat", ti.f64, 1)     # J since the start

    def integrate_func(self, ctx):
        """Books the radiant heat of the step, q dt (J, thermal time S dt), into the run's
        total, an f64 sum."""
        s, radiated = ctx.state, self.radiated
        # thermal.time_scale, read at run time (engine/values.py; the same slot as the
        # temperature update's)
        time_scale = ctx.values.scalar("thermal_time_scale", float(self.thermal.time_scale))

        @ti.func
        def book_radiation(i, load, dt):
            radiated[0] += (ti.cast(s.radiated_power[i], ti.f64) * ti.cast(dt, ti.f64)
                            * ti.cast(time_scale(), ti.f64))
        return book_radiation

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """thermal/radiated_heat: J into the particles by radiation since the start."""
        values["thermal/radiated_heat"] = float(self.radiated.to_numpy()[0])

    def upload(self, ctx):
        npf = np.float64 if ctx.real == ti.f64 else np.float32
        return [(self.emissivity, np.array(
            [self.emissivities.get(k) or 0.0 for k in ctx.material_names], npf))]

    def particle_func(self, ctx):
        s = ctx.state
        th = self.thermal
        plug_flow_effect = ctx.effect("plug_flow_convection")
        stream = plug_flow_effect.stream if plug_flow_effect is not None else None
        plug_flow = stream is not None
        gas = th.gas
        radiate_to_gas = th.radiation_to == "gas"
        # the surroundings' temperature (K), read at run time (engine/values.py): a changed
        # one compiles nothing new
        surroundings_of = ctx.values.scalar(
            "radiation_temperature", float(gas.temperature if (radiate_to_gas and not plug_flow)
                                           else (th.radiation_temperature or 0.0)))
        in_radiation_region = region_test(th.radiation_region, ctx.values, "radiation_region")
        emissivity = self.emissivity

        @ti.func
        def radiation(i, load):
            s.radiated_power[i] = 0.0
            if in_radiation_region(s.position[i]):
                t_surroundings = surroundings_of() + 0.0 * load.heat
                sees = 1
                if ti.static(radiate_to_gas and plug_flow):
                    t_surroundings, sees = stream.local_temperature(i)
                if sees != 0:
                    q_rad, g_rad = exchange(emissivity[s.material[i]], s.radius[i],
                                                      t_surroundings, s.temperature[i])
                    load.heat += q_rad
                    load.conductance += g_rad
                    s.radiated_power[i] = q_rad
            return load

        return radiation
