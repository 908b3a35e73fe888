import math
"""The state's sums at an output sample, by one reduction kernel into the engine's named
slots (state.Reduction, and the f64 state.ThermalSum for the heat balance): what the run's
checks (divergence, the thermal step limit) and the sensors read."""

import taichi as ti

from . import transfer
from .state import SPHERE_INERTIA, Reduction, ThermalSum


class Measure:
    """``Measure(engine)(n)``: the sums over the first ``n`` slots as a dict (Engine.measure)."""

    def __init__(self, engine):
        self.e = e = engine
        s = e.state
        red = e.reduction
        thermal = e.model.thermal
        moisture = e.model.moisture
        compensated = s.compensated
        sums = e.thermal_sums if thermal else None
        # the thermal step: S dt with heat capacities divided by S ([thermal] time_scale)
        dt_step = e.model.dt * (e.model.scene.thermal.time_scale if thermal else 1.0)

        @ti.kernel
        def measure(n: ti.i32, serial_loops: ti.template()):
            # kinetic energy (translational + rotational, J), largest speed, non-finite flag,
            # alive count; thermal: sum m c T (J), sum m c (J/K), largest dt sum(h)/(m c)
            for k in ti.static(range(Reduction.SIZE)):
                red[k] = 0.0
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                if s.inverse_mass[i] > 0.0 and s.alive[i] != 0:
                    m = s.mass[i]
                    inertia = SPHERE_INERTIA * m * s.radius[i] ** 2
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
                ti.loop_config(serialize=serial_loops)
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


        self._kernel = e.serial_switch(measure)

    def __call__(self, n: int) -> dict:
        e = self.e
        self._kernel(n)
        r, h = transfer.read([e.reduction, e.thermal_sums]) if e.model.thermal else (
            e.reduction.to_numpy(), None)
        out = {"kinetic_energy": float(r[Reduction.KINETIC_ENERGY]),
               "max_speed": float(r[Reduction.MAX_SPEED]),
               "non_finite": bool(r[Reduction.NON_FINITE] > 0)}
        if e.model.thermal:
            energy, thermal_mass = h[ThermalSum.THERMAL_ENERGY], h[ThermalSum.THERMAL_MASS]
            out.update(thermal_energy=float(energy),
                       mean_temperature=float(energy / thermal_mass) if thermal_mass else math.nan,
                       thermal_step_ratio=float(r[Reduction.THERMAL_STEP_RATIO]))
        if e.model.moisture:
            water, dry = h[ThermalSum.WATER_MASS], h[ThermalSum.DRY_MASS]
            out.update(mean_moisture=float(water / dry) if dry else math.nan,
                       evaporated_mass=float(e.evaporated[0]))
        return out
