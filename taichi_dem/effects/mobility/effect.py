"""Mobility ([mobility]): skip the mutual contacts and the integration of particles that do not
move (the "adaptive sparse contacts" idea of seed 000 and of Lethe; written here from the
description, not from their code).

At every neighbour rebuild (while the last judgement held nothing, every IDLE_JUDGE_STEPS
steps), and at least every JUDGE_WITHIN_STEPS steps (a bed at rest asks for no rebuild; the
lists are rebuilt for the judgement), the particles, already sorted by contact
cell (broadphase.py), are judged per *mobility cell*: a block of contact cells about
``cell_size`` across (3 largest diameters by default; a contact cell of ~1.1 d holds about
one particle, too few for a fluctuation or a solid fraction). For each mobility cell, over
the particles whose centres lie in it:

  mean velocity       u = sum v / n                                  m/s
  granular temperature T_g = sum |v - u|^2 / (3 n)                    (m/s)^2
  solid fraction      phi = sum (4/3 pi r^3) / (the cell's volume inside the domain)

with v taken relative to the rigid motion of ``body`` in mode "body_frame" (a drum's shell), to
rest in mode "at_rest". A cell is **mobile** when T_g or |u|^2 / 3 exceeds the threshold (so a
bed carried along at low T_g is never frozen in mode "at_rest"), when phi is below the solid
fraction threshold (free surfaces, thin flows), when the mean squared acceleration of its
particles (relative to the frame's centripetal one) exceeds the square of the acceleration
threshold (a bed that still rings after it landed is quiet in velocity but not in equilibrium:
frozen then, it would keep the forces of that instant), when it touches an empty cell
(openings, free surfaces), or when one of its particles has a candidate triangle on a moving
body (other than the frame's body: a paddle about to sweep through a resting bed). Cells within one cell of a
mobile cell are **active**; the rest **inactive** (periodic axes wrap, cells beyond a
non-periodic face do not count).

What an inactive particle skips (engine/stepper.py):
  * contacts with another inactive particle: computed once at the rebuild step (where the
    pair lists, the partner shares and the conductances are new) and then frozen: force,
    torque and tangential history are kept, heat flows through the frozen conductance with the
    current temperatures (so conduction stays exact for a frozen geometry);
  * its integration: in "at_rest" its velocity, spin and accelerations are set to zero at the
    rebuild and its position is held; in "body_frame" it moves rigidly with the body
    (position rotated about the body's axis, velocity = the body's velocity there);
  * its partners' shares in the gather.
Still computed: its contacts with active particles (both sides: the active partner feels the
force), with plane walls and mesh bodies (the wall and body loads and torques stay complete),
and all heat effects and the temperature update.

In "body_frame" the inactive core is part of the frame's body kinematically, so the body must
hold it: each inactive particle's contacts from outside the core (active partners, walls,
bodies), its weight and its centripetal mass-acceleration give the reaction F + m g - m a_rigid
(and the contact torque T) that is booked on the frame body every step like a contact's load
(``Mobility.make_carried_load``, run in engine/stepper.py's gather; the core's inner contacts cancel in that sum and are
left out on both sides). Without it a drum whose core froze read its torque 10 % low: the weight
of the core, and the shear of the cascading layer on it, never reached the shell
(tests/unit/test_mobility.py checks the booked torque against sum m (x - c) x g exactly). The
frozen pairs' tangential springs are re-projected onto the turned contact plane at each rebuild
step, as every pair's is at every step (hertz_mindlin.rotate_into_tangent_plane): exact for the
tilt of the normal, and, as for active pairs, without the twist about the normal.

Where a cell is *empty* for the "touches an empty cell" rule, "body_frame" leaves out cells
beyond the frame body's reach (less than a quarter of their volume within the body's farthest
vertex from its axis, less a largest radius: outside a drum's shell), and measures a cell's
solid fraction against its volume within that reach: otherwise the shell would count as a free
surface and a cell cut by it as dilute, and every cell along the shell would stay mobile with
the layer inside it active (measured: a 19 d deep bed then froze at most 10 % of its particles
at any threshold; with the reach, 24 - 39 %). That assumes the body encloses the bed (a drum
shell): a particle centre in a cell wholly beyond the reach (a frame body that is a paddle
shaft, say) drops the reach for the rest of the run, with a warning.

Defaults (settings.py): the threshold is 1e-5 g d_max (fluctuations of 0.3 % of sqrt(g d));
a frozen cell keeps the contact forces of the instant it froze, so the threshold decides how
far from equilibrium a bed may be when it freezes, and this one let the slot hopper's settled
floor carry its bed's weight where 100x higher did not (BENCHMARKS.md "Mobility: skipping the
contacts of particles that do not move"). Solid fraction 0.4: below random loose packing
(0.55) by a margin the noise of a 3 d cell does not reach. Without gravity "auto" has no
scale and the loader asks for a value. ``acceleration_threshold`` is opt-in (same section).
"""
# (no postponed annotations: Taichi reads the kernels' argument types)

import math
import sys

import numpy as np
import taichi as ti

from ..base import Effect

INACTIVE, ACTIVE, MOBILE, EMPTY = 0, 1, 2, 3
# the most steps between two judgements. A rebuild costs about as much as 5 - 10 steps (the
# chute's, BENCHMARKS.md), so one forced every 2000 steps costs under 0.5 % where nothing else
# rebuilds, and a flowing bed rebuilds far more often on its own (the chute every ~33 steps).
# Judged every 500 steps, a settling bed froze and thawed cells while it still rang (the
# frozen forces of a bed not yet at rest, released at the next judgement), settled slower and
# froze a quarter as much (1,200 spheres on a floor, tests/unit/test_mobility.py); at 2000
# the forced judgements come after the bed has come to rest and change nothing there.
JUDGE_WITHIN_STEPS = 2000
# while the last judgement held nothing (a flow: the chute), the next comes at the first
# rebuild at least this many steps later, not at every rebuild: judging is a serial pass over
# the particles, at each of the chute's rebuilds (~every 33 steps) ~8 % of its step, for
# nothing. A bed that comes to rest is frozen at most this many steps later; once a judgement
# holds particles, every rebuild judges again (a held particle is woken at the next one, as
# before). BENCHMARKS.md "Mobility where nothing freezes: the step without the hooks".
IDLE_JUDGE_STEPS = 200


class Mobility(Effect):
    """One [mobility] section (scene.model.MobilitySettings); status per mobility cell, an
    ``particle_active`` flag per particle (1 active, 0 inactive), refreshed by
    ``after_rebuild``."""

    name, stage = "mobility", "detect"
    holds_particles = True      # (engine/holding.py: the step reads particle_active)
    # the cells are judged at rebuilds; a bed that has come to rest asks for none, so the
    # judgement made while it still moved would stand for good (nothing frozen, the
    # bookkeeping paid: the heated bed ran 30 % slower with mobility, BENCHMARKS.md)
    rebuild_within_steps = JUDGE_WITHIN_STEPS

    def __init__(self, description: str, settings, bodies=()):
        super().__init__(description)
        self.settings = settings
        # the scene's bodies (plain data): which move, and the frame body's motion and reach
        self.bodies = tuple(bodies)
        # "body_frame": the index of the body whose rigid motion the bed follows, else -1
        self.frame = ([b.name for b in self.bodies].index(settings.body)
                      if settings.mode == "body_frame" else -1)

    @property
    def carrier_body(self) -> int:
        """The body whose frame carries the inactive particles ("body_frame"), or -1."""
        return self.frame

    # ------------------------------------------------------------------ layout
    def layout(self, grid):
        """Mobility cells per axis (``blocks``) over the contact grid; contact cell c of an
        axis lies in mobility cell c * blocks // dims."""
        target = self.settings.cell_size
        blocks = []
        for k in range(3):
            n = int(round(grid.dims[k] * grid.cell_size[k] / target)) if target > 0 else grid.dims[k]
            blocks.append(max(1, min(grid.dims[k], n)))
        return tuple(blocks)

    def allocate(self, ctx, tree):
        g = ctx.grid
        self.blocks = self.layout(g)
        self.n_blocks = int(np.prod(self.blocks))
        cap = ctx.state.capacity
        real = ctx.real
        self.particle_active = tree.add("particle_active", ti.i32, cap)
        self.block_count = tree.add("mobility_count", ti.i32, self.n_blocks)
        self.block_temperature = tree.add("mobility_temperature", real, self.n_blocks)   # (m/s)^2
        self.block_mean_speed_sq = tree.add("mobility_mean_speed_sq", real, self.n_blocks)
        self.block_solid_fraction = tree.add("mobility_solid_fraction", real, self.n_blocks)
        self.block_volume = tree.add("mobility_volume", real, self.n_blocks)             # m^3
        self.block_flag = tree.add("mobility_flag", ti.i32, self.n_blocks)   # moving-body contact
        # 1: the cell lies beyond the frame body's reach (outside a drum's shell): no particle
        # can be there, so its being empty is no free surface
        self.block_beyond = tree.add("mobility_beyond", ti.i32, self.n_blocks)
        # 1: the cell lies wholly outside the frame body's reach itself: a particle centre there
        # means the body does not enclose the bed, and the reach is dropped (``update``)
        self.block_outside = tree.add("mobility_outside", ti.i32, self.n_blocks)
        self.block_mobile = tree.add("mobility_mobile", ti.i32, self.n_blocks)
        self.block_status = tree.add("mobility_status", ti.i32, self.n_blocks)
        # [inactive particles, cells inactive, active, mobile, particles outside the reach]
        self.counts = tree.add("mobility_counts", ti.i32, 5)
        # the last judgement: [its time, s; 1 if it held any particle, else 0] (in the tree:
        # a checkpoint keeps it, so a resumed run judges at the rebuilds the uninterrupted one
        # would)
        self.last_judgement = tree.add("mobility_last_judgement", ti.f64, 2)
        # 1 while the last judgement held any particle: the step reads the flags only then
        # (engine/holding.py), so a flow where nothing is held pays no flag reads. 1 until
        # the first judgement (and from a checkpoint without it: its flags stand)
        self.particles_held = tree.add("mobility_particles_held", ti.i32, 1)

    def upload(self, ctx):
        """The volume (m^3) of each mobility cell inside the domain (a non-periodic axis's last
        contact cell reaches past the face)."""
        g = ctx.grid
        edges = []
        for k in range(3):
            d, nb = g.dims[k], self.blocks[k]
            starts = [(b * d + nb - 1) // nb for b in range(nb)] + [d]
            lo = g.lo[k] + np.asarray(starts, float) * g.cell_size[k]
            lo = np.minimum(lo, g.hi[k])
            edges.append(np.diff(lo))
        vol = edges[0][:, None, None] * edges[1][None, :, None] * edges[2][None, None, :]
        self.plain_volume = np.maximum(vol, 1e-30).reshape(-1)
        beyond = np.zeros(vol.shape, np.int32)
        outside = np.zeros(vol.shape, np.int32)
        reach = self.frame_reach(ctx)
        self.reach_in_use = reach is not None
        if reach is not None:
            # where particle centres can be: a largest radius inside the body's reach; a cell
            # of which less than a quarter is there may well hold no centre in a full drum
            point, axis, radius = reach
            inside = self.fraction_within(ctx, edges, point, axis,
                                          max(radius - ctx.max_radius, 0.0))
            vol = vol * inside
            beyond = (inside < 0.25).astype(np.int32)
            outside = (self.fraction_within(ctx, edges, point, axis, radius) == 0.0
                       ).astype(np.int32)
        return (self._volumes(ctx, np.maximum(vol, 1e-30).reshape(-1), beyond.reshape(-1))
                + [(self.block_outside, outside.reshape(-1)),
                   (self.particle_active, np.ones(self.particle_active.shape, np.int32)),
                   (self.last_judgement, np.array([-np.inf, 1.0])),
                   (self.particles_held, np.ones(1, np.int32))])

    def _volumes(self, ctx, volume, beyond):
        """The writes of the cells' volumes (m^3) and their flags of lying beyond the reach."""
        npf = np.float64 if ctx.real == ti.f64 else np.float32
        return [(self.block_volume, volume.astype(npf)),
                (self.block_beyond, beyond.astype(np.int32))]

    def frame_reach(self, ctx):
        """(axis point m, unit axis, radius m) of the cylinder that the frame body sweeps as it
        turns (its farthest vertex from the axis), or None: in mode "at_rest", or for a body
        that also translates (its reach moves)."""
        frame = self.frame
        if frame < 0:
            return None
        body = self.bodies[frame]
        motion = body.motion
        if any(v != 0 for v in motion.velocity):
            return None
        point = np.asarray(motion.axis_point, float)
        axis = np.asarray(motion.axis_direction, float)
        axis = axis / np.linalg.norm(axis)
        r = np.asarray(body.vertices, float) - point
        radial = r - np.outer(r @ axis, axis)
        return point, axis, float(np.sqrt(np.max(np.sum(radial ** 2, axis=1))))

    @staticmethod
    def fraction_within(ctx, edges, point, axis, radius, samples: int = 6):
        """Fraction of each mobility cell's volume (per axis widths ``edges``, from the grid's
        lower corner) within ``radius`` of the axis through ``point`` along ``axis``: the
        midpoints of samples^3 sub-cells, numpy at set-up (m, unit vector, m)."""
        g = ctx.grid
        lows = [g.lo[k] + np.concatenate([[0.0], np.cumsum(edges[k])[:-1]]) for k in range(3)]
        u = (np.arange(samples) + 0.5) / samples
        coords = [lows[k][:, None] + edges[k][:, None] * u[None, :] for k in range(3)]  # (n_k, s)
        n = [len(e) for e in edges]
        out = np.empty(n)
        for i in range(n[0]):               # one slab of cells at a time: bounded memory
            X, Y, Z = np.meshgrid(coords[0][i], coords[1].ravel(), coords[2].ravel(),
                                  indexing="ij")
            r = np.stack([X, Y, Z], axis=-1) - point
            radial_sq = np.sum(r ** 2, axis=-1) - (r @ axis) ** 2
            within = (radial_sq <= radius ** 2).astype(float)
            out[i] = within.reshape(samples, n[1], samples, n[2], samples).mean(axis=(0, 2, 4))
        return out

    # ------------------------------------------------------------------ kernels
    def prepare(self, ctx):
        """The status kernel; needs the broadphase's cell ranges (and the mesh's candidate
        lists when the scene has bodies). ``self.frame``: the frame body's index
        or -1."""
        s = ctx.state
        g = ctx.grid
        st = self.settings
        cell_start = ctx.broadphase.cell_start
        dims = g.dims
        blocks = self.blocks
        nbx, nby, nbz = blocks
        threshold = st.granular_temperature_threshold
        # mean squared acceleration above which a cell is not in equilibrium, (m/s^2)^2
        acceleration_sq = st.acceleration_threshold ** 2 if math.isfinite(st.acceleration_threshold) else -1.0
        check_acceleration = acceleration_sq >= 0.0
        phi_min = st.solid_fraction_threshold
        counts = self.counts
        active, held, last = self.particle_active, self.particles_held, self.last_judgement
        count, temp, speed_sq = self.block_count, self.block_temperature, self.block_mean_speed_sq
        phi, volume, flag = self.block_solid_fraction, self.block_volume, self.block_flag
        mobile, status = self.block_mobile, self.block_status
        beyond, outside = self.block_beyond, self.block_outside
        mesh = ctx.mesh
        frame = self.frame
        body_frame = frame >= 0
        moving_flags = self.moving_body_flags()
        check_bodies = mesh is not None and any(moving_flags)
        rigid_velocity = self.make_rigid_velocity(ctx)
        rigid_acceleration = self.make_rigid_acceleration(ctx)
        n_blocks = self.n_blocks
        four_thirds_pi = 4.0 / 3.0 * math.pi

        # cells and mobility cells are numbered and stepped by the grid (engine/grid.py)
        cell_number, cell_coordinates, _ = g.make_cell_arithmetic()
        _, block_coordinates, neighbour_block = g.make_cell_arithmetic(blocks)

        @ti.func
        def block_of_cell(c):
            v = cell_coordinates(c)
            return ((v[0] * nbx // dims[0]) * nby + v[1] * nby // dims[1]) * nbz + v[2] * nbz // dims[2]

        @ti.func
        def first_cell(b, n, d):
            return (b * d + n - 1) // n

        @ti.kernel
        def update(n: ti.i32, t: ti.f64, serial_loops: ti.template()):
            for k in ti.static(range(5)):
                counts[k] = 0
            ti.loop_config(serialize=serial_loops)
            for b in range(n_blocks):
                v = block_coordinates(b)
                bx, by, bz = v[0], v[1], v[2]
                number = 0
                velocity_sum = ti.Vector([0.0, 0.0, 0.0])
                solid = 0.0
                acceleration = 0.0
                touches_moving = 0
                for cx in range(first_cell(bx, nbx, dims[0]), first_cell(bx + 1, nbx, dims[0])):
                    for cy in range(first_cell(by, nby, dims[1]), first_cell(by + 1, nby, dims[1])):
                        for cz in range(first_cell(bz, nbz, dims[2]), first_cell(bz + 1, nbz, dims[2])):
                            c = cell_number(ti.Vector([cx, cy, cz]))
                            for i in range(cell_start[c], cell_start[c + 1]):
                                number += 1
                                velocity_sum += s.velocity[i] - rigid_velocity(s.position[i], t)
                                solid += four_thirds_pi * s.radius[i] ** 3
                                if ti.static(check_acceleration):
                                    a = s.acceleration[i] - rigid_acceleration(s.position[i], t)
                                    acceleration += a.dot(a)
                                if ti.static(check_bodies):
                                    for q in range(mesh.mesh_start[i], mesh.mesh_start[i] + mesh.mesh_count[i]):
                                        body = mesh.triangles.tri_body[mesh.mesh_tri[q]]
                                        for bb in ti.static(range(len(moving_flags))):
                                            if ti.static(moving_flags[bb]):
                                                if body == bb:
                                                    touches_moving = 1
                mean = velocity_sum / ti.max(number, 1)
                fluctuation = 0.0
                for cx in range(first_cell(bx, nbx, dims[0]), first_cell(bx + 1, nbx, dims[0])):
                    for cy in range(first_cell(by, nby, dims[1]), first_cell(by + 1, nby, dims[1])):
                        for cz in range(first_cell(bz, nbz, dims[2]), first_cell(bz + 1, nbz, dims[2])):
                            c = cell_number(ti.Vector([cx, cy, cz]))
                            for i in range(cell_start[c], cell_start[c + 1]):
                                u = s.velocity[i] - rigid_velocity(s.position[i], t) - mean
                                fluctuation += u.dot(u)
                count[b] = number
                if outside[b] != 0 and number > 0:
                    ti.atomic_add(counts[4], number)
                temp[b] = fluctuation / (3.0 * ti.max(number, 1))
                speed_sq[b] = mean.dot(mean) / 3.0
                phi[b] = solid / volume[b]
                flag[b] = touches_moving
                if ti.static(check_acceleration):
                    if acceleration > acceleration_sq * number:
                        flag[b] = 1
            ti.loop_config(serialize=serial_loops)
            for b in range(n_blocks):
                v = block_coordinates(b)
                state = INACTIVE
                if count[b] == 0:
                    state = EMPTY
                elif (temp[b] > threshold or speed_sq[b] > threshold or phi[b] < phi_min
                      or flag[b] != 0):
                    state = MOBILE
                else:
                    for offset in range(27):
                        nb, inside = neighbour_block(v, offset)
                        if inside and count[nb] == 0 and beyond[nb] == 0:
                            state = MOBILE
                mobile[b] = state
            ti.loop_config(serialize=serial_loops)
            for b in range(n_blocks):
                v = block_coordinates(b)
                state = mobile[b]
                if state == INACTIVE:
                    for offset in range(27):
                        nb, inside = neighbour_block(v, offset)
                        if inside and mobile[nb] == MOBILE:
                            state = ACTIVE
                status[b] = state
                if state != EMPTY:
                    ti.atomic_add(counts[1 + ti.min(state, 2)], 1)
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                a = 1
                if status[block_of_cell(s.cell[i])] == INACTIVE:
                    a = 0
                    # held (at rest) or carried rigidly by the frame's body from now on
                    s.velocity[i] = rigid_velocity(s.position[i], t)
                    s.angular_velocity[i] = rigid_spin(t)
                    s.acceleration[i] = ti.Vector([0.0, 0.0, 0.0])
                    s.angular_acceleration[i] = ti.Vector([0.0, 0.0, 0.0])
                    ti.atomic_add(counts[0], 1)
                active[i] = a
            for _ in range(1):          # (a loop of its own: after every particle is judged)
                held[0] = 1 if counts[0] > 0 else 0
                last[0] = t
                last[1] = ti.cast(held[0], ti.f64)


        rigid_spin = self.make_rigid_spin(ctx)
        self._update = ctx.serial_switch(update)
        self.body_frame = body_frame

    def moving_body_flags(self) -> tuple:
        """Per body, 1 where it moves and is not the frame's: its candidate contacts make a
        cell mobile."""
        flags = []
        for b, body in enumerate(self.bodies):
            m = body.motion
            moves = (m.speed is not None and any(v != 0 for _, v in m.speed.points)
                     or any(v != 0 for v in m.velocity))
            flags.append(1 if b != self.frame and moves else 0)
        return tuple(flags)

    def make_rigid_acceleration(self, ctx):
        """A ti.func (x, t) -> the frame's centripetal acceleration at x (m/s^2; constant
        spin between schedule steps), zero without a frame body."""
        rigid_frame = self.frame >= 0
        rigid_spin_ = self.make_rigid_spin(ctx)
        centre_of = self.make_rigid_centre(ctx) if rigid_frame else None

        @ti.func
        def rigid_acceleration(x, t):
            a = ti.Vector([0.0, 0.0, 0.0]) * x[0]
            if ti.static(rigid_frame):
                w = rigid_spin_(t)
                a = w.cross(w.cross(x - centre_of(t)))
            return a
        return rigid_acceleration

    def make_rigid_velocity(self, ctx):
        """ti.func (x, t) -> the frame body's velocity at point x (m/s); zero in "at_rest"."""
        frame = self.frame
        if frame < 0:
            @ti.func
            def at_rest(x, t):
                return ti.Vector([0.0, 0.0, 0.0]) * x[0]
            return at_rest
        motion = self.bodies[frame].motion
        point = ti.Vector(list(motion.axis_point))
        velocity = ti.Vector(list(motion.velocity))
        spin = self.make_rigid_spin(ctx)
        real = ctx.real

        @ti.func
        def body_velocity(x, t):
            centre = point + velocity * ti.cast(t, real)
            return velocity + spin(t).cross(x - centre)
        return body_velocity

    def make_rigid_centre(self, ctx):
        """ti.func t -> the frame body's axis point at t (m)."""
        motion = self.bodies[self.frame].motion
        point = ti.Vector(list(motion.axis_point))
        velocity = ti.Vector(list(motion.velocity))
        real = ctx.real

        @ti.func
        def centre(t):
            return point + velocity * ti.cast(t, real)
        return centre

    def make_rigid_spin(self, ctx):
        """ti.func t -> the frame body's angular velocity vector (rad/s); zero in "at_rest"."""
        frame = self.frame
        if frame < 0:
            @ti.func
            def no_spin(t):
                return ti.Vector([0.0, 0.0, 0.0])
            return no_spin
        motion = self.bodies[frame].motion
        axis = ti.Vector(list(motion.axis_direction))
        points = tuple(motion.speed.points) if motion.speed is not None else ((0.0, 0.0),)

        # the piecewise-constant schedule as a sum of steps: speed(t) = sum_k dv_k [t >= t_k]
        steps = [(points[0][0], points[0][1])] + [
            (points[k][0], points[k][1] - points[k - 1][1]) for k in range(1, len(points))]
        real = ctx.real

        @ti.func
        def spin(t):
            speed = ti.cast(0.0, real)
            for k in ti.static(range(len(steps))):
                speed += ti.select(t >= steps[k][0], ti.cast(steps[k][1], real), ti.cast(0.0, real))
            return speed * axis
        return spin

    def make_rigid_drift(self, ctx):
        """ti.func (x, dt, t) -> x carried rigidly by the frame body over the step ending at
        t (rotation about its axis by |omega| dt, Rodrigues, plus its translation)."""
        frame = self.frame
        motion = self.bodies[frame].motion
        point = ti.Vector(list(motion.axis_point))
        velocity = ti.Vector(list(motion.velocity))
        axis = ti.Vector(list(motion.axis_direction))
        spin = self.make_rigid_spin(ctx)
        real = ctx.real

        @ti.func
        def rigid_drift(x, dt, t):
            centre = point + velocity * ti.cast(t, real)
            r = x - centre
            angle = spin(t).dot(axis) * dt
            c, s_ = ti.cos(angle), ti.sin(angle)
            r_new = r * c + axis.cross(r) * s_ + axis * axis.dot(r) * (1.0 - c)
            return centre + r_new + velocity * dt
        return rigid_drift

    def make_carried_load(self, ctx):
        """ti.func book_carried_load(i, force, torque, acceleration) for "body_frame":
        inactive particle i is carried rigidly by the frame's body, which must supply
        C = m a_rigid - (F + m g) and the torque -T that keep it on its path (a_rigid =
        w x (w x r), the body's spin constant between schedule steps); the reaction,
        F + m g - m a_rigid at the lever r from the body's axis point and T, is a load on the
        body like a contact's. ``force``, ``torque``: the contacts from outside the inactive
        core (N, N m); ``acceleration``: the particle effects' (m/s^2). Booked in the body's
        per-particle load sums, every step as the contacts are."""
        frame = self.frame
        frames, loads = ctx.mesh.frames, ctx.mesh.loads
        s = ctx.state

        @ti.func
        def book_carried_load(i, force, torque, acceleration):
            w = frames.angular_velocity[frame]
            lever = s.position[i] - (frames.axis_point[frame] + frames.offset[frame])
            residual = force + s.mass[i] * (acceleration - w.cross(w.cross(lever)))
            loads.particle_load_force[i, frame] = loads.particle_load_force[i, frame] + residual
            loads.particle_load_torque[i, frame] = (loads.particle_load_torque[i, frame]
                                                    + lever.cross(residual) + torque)
        return book_carried_load

    # ------------------------------------------------------------------ driver
    def after_rebuild(self, ctx, n: int, time: float):
        """Judge every particle: its ``particle_active`` flag for the steps to the next
        rebuild; while the last judgement held none, only every IDLE_JUDGE_STEPS steps."""
        judged_at, held = self.last_judgement.to_numpy()
        if held == 0.0 and time - judged_at < (IDLE_JUDGE_STEPS - 0.5) * ctx.dt:
            return
        self._update(n, time)
        if self.reach_in_use and int(self.counts[4]) > 0:
            # a particle centre beyond the frame body's reach: the body does not enclose the
            # bed (a paddle shaft, not a drum shell), so its reach says nothing about where
            # particles can be; judge again with the plain cell volumes and every empty cell
            body = self.bodies[self.frame].name
            print(f"taichi-dem: warning: [mobility] {int(self.counts[4])} particles lie beyond "
                  f"the reach of body '{body}'; mode \"body_frame\" counts cells outside the "
                  f"frame body as walls only when the body encloses the bed (a drum shell); "
                  f"judging with the plain cell volumes from now on", file=sys.stderr)
            self.reach_in_use = False
            for field, values in self._volumes(ctx, self.plain_volume,
                                               np.zeros(len(self.plain_volume), np.int32)):
                field.from_numpy(values)            # (once, in this rare case)
            self.block_outside.fill(0)
            self._update(n, time)

    def statistics(self) -> dict:
        """Counts from the last update: inactive particles; cells inactive, active, mobile."""
        c = self.counts.to_numpy()
        return {"inactive_particles": int(c[0]), "inactive_cells": int(c[1]),
                "active_cells": int(c[2]), "mobile_cells": int(c[3])}


def build(scene, settings) -> list:
    """The effect for a scene's [mobility] ``settings`` (MobilitySettings; its body frame
    among ``scene.bodies``)."""
    m = settings
    frame = f"relative to body '{m.body}'" if m.mode == "body_frame" else "at rest"
    return [Mobility(
        f"mobility: contacts between inactive particles frozen, their integration skipped "
        f"(granular temperature > {m.granular_temperature_threshold:.3g} (m/s)^2"
        f"{' (auto: 1e-5 g d_max)' if m.threshold_is_auto else ''}, solid fraction < "
        f"{m.solid_fraction_threshold:g}"
        + (f", rms acceleration > {m.acceleration_threshold:.3g} m/s^2"
           if m.acceleration_threshold < float("inf") else "")
        + f", cells of {m.cell_size * 1e3:.3g} mm, {frame})", m, scene.bodies)]
