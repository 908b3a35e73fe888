"""The first half of a velocity Verlet step, per particle (engine/stepper.py): the half kick,
the drift, the wrap across periodic faces, the removal of particles that left the domain or
entered an outlet, and the flag that asks for a rebuild once a particle has moved half the
skin. Held particles (engine/holding.py) stay, or are carried rigidly by a body's frame."""
import taichi as ti

from .precision import make_split_add
from .state import PARKED, Flag


def make_drift(e):
    """(minimum_image, drift_particle, drift) of engine ``e``: the grid's ti.func d -> the
    shortest periodic image of a separation (m), the ti.func ``drift_particle(i, dt, t_new)``
    and the kernel ``drift(n, dt, t_new)`` over the first n particles (its loop mode the
    engine's)."""
    s = e.state
    g = e.model.grid
    lo_of, hi_of, span_of = g.layout_funcs()[:3]
    half_skin_sq_of = e.values.scalar("half_skin_squared", (0.5 * e.model.skin) ** 2)
    real = e.model.real
    flags = e.flags

    minimum_image = g.make_minimum_image()

    has_process = e.process is not None
    after_drift = e.process.make_funcs(e) if has_process else None
    holding = e.holding
    holds, particle_moves = holding.any, holding.moves
    body_frame = holding.carried
    rigid_drift, rigid_velocity = holding.rigid_drift, holding.rigid_velocity
    # positions with residuals (engine/precision.py: f32 far from the origin)
    split = e.model.split_positions
    split_add = make_split_add(real) if split else None
    vec0 = ti.Vector([0.0, 0.0, 0.0])

    @ti.func
    def drift_particle(i, dt, t_new):
        """First half of a velocity Verlet step for particle i: half kick, then drift.
        A particle that leaves the domain (or enters an outlet) is removed: marked dead
        and parked far away until the next rebuild drops it. ``t_new``: time after the
        step, s. A held particle (engine/holding.py) stays, or is carried rigidly by a
        body's frame."""
        moves = s.inverse_mass[i] > 0.0 and s.alive[i] != 0
        frozen = False
        if ti.static(holds):
            frozen = not particle_moves(i)
            if ti.static(not body_frame):
                if frozen:
                    moves = False
        if moves:
            x_old = s.position[i]
            x_new = x_old
            if ti.static(body_frame):
                if frozen:
                    x_new = rigid_drift(x_old, dt, t_new)
                    s.velocity[i] = rigid_velocity(x_new, t_new)
            residual = vec0
            if ti.static(split):
                residual = s.position_residual[i]
            if not frozen:
                v = s.velocity[i] + 0.5 * dt * s.acceleration[i]
                s.velocity[i] = v
                s.angular_velocity[i] = s.angular_velocity[i] + 0.5 * dt * s.angular_acceleration[i]
                if ti.static(split):
                    # far from the origin: the step added to (position, residual) in f64
                    x_new, residual = split_add(x_old, residual, dt * v)
                else:
                    x_new = x_old + dt * v
            x = x_new
            inside = True
            wrap = vec0
            lo, hi, span = lo_of(), hi_of(), span_of()
            for k in ti.static(range(3)):
                if ti.static(g.periodic[k]):
                    # wrap into [lo, hi): the particle re-enters through the opposite face
                    if x[k] >= hi[k]:
                        wrap[k] = -span[k]
                    elif x[k] < lo[k]:
                        wrap[k] = span[k]
                elif x[k] < lo[k] or x[k] > hi[k]:
                    inside = False
            if ti.static(split):
                x, residual = split_add(x, residual, wrap)
                s.position_residual[i] = residual
            else:
                x += wrap
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
                if moved.dot(moved) > half_skin_sq_of():
                    flags[Flag.REBUILD] = 1      # benign race: every writer writes 1

    @ti.kernel
    def drift(n: ti.i32, dt: real, t_new: ti.f64, serial_loops: ti.template()):
        ti.loop_config(serialize=serial_loops)
        for i in range(n):
            drift_particle(i, dt, t_new)

    return minimum_image, drift_particle, e.serial_switch(drift)
