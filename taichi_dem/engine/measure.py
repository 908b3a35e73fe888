"""The state's sums at an output sample, by one reduction kernel: the engine's own (kinetic
energy, largest speed, a non-finite flag, moving count: the named slots of state.Reduction)
and those the enabled effects declare (``Effect.measure_funcs``: the heat balance's f64 sums,
the moisture), into each one's own fields. What the run's checks (divergence, the thermal
step limit) and the sensors read."""
import taichi as ti

from . import transfer
from .state import SPHERE_INERTIA, Reduction


class Measure:
    """``Measure(engine)(n)``: the sums over the first ``n`` slots as a dict (Engine.measure)."""

    def __init__(self, engine):
        self.e = e = engine
        s = e.state
        red = e.reduction
        declared = [f for f in (x.measure_funcs(e.context) for x in e.model.effect_list)
                    if f is not None]
        resets = tuple(d[0] for d in declared)
        particles = tuple(d[1] for d in declared)
        self.reads = [(len(d[2]), d[3]) for d in declared]
        self.fields = [red] + [f for d in declared for f in d[2]]

        @ti.kernel
        def measure(n: ti.i32, serial_loops: ti.template()):
            # kinetic energy (translational + rotational, J), largest speed, non-finite flag,
            # moving count; then the effects' sums over the live particles
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
            if ti.static(len(particles) > 0):
                for reset in ti.static(resets):
                    reset()
                ti.loop_config(serialize=serial_loops)
                for i in range(n):
                    if s.alive[i] != 0:
                        for particle in ti.static(particles):
                            particle(i)

        self._kernel = e.serial_switch(measure)

    def __call__(self, n: int) -> dict:
        self._kernel(n)
        arrays = transfer.read(self.fields)
        r = arrays[0]
        out = {"kinetic_energy": float(r[Reduction.KINETIC_ENERGY]),
               "max_speed": float(r[Reduction.MAX_SPEED]),
               "non_finite": bool(r[Reduction.NON_FINITE] > 0)}
        k = 1
        for count, read in self.reads:
            measured = read(arrays[k:k + count])
            k += count
            out["non_finite"] = out["non_finite"] or measured.pop("non_finite", False)
            out.update(measured)
        return out
