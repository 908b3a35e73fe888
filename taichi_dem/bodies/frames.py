"""Each rigid body's triangles, frame and loads on the device, for the mesh contacts
(mesh_contacts.py).

``BodyTriangles``: every body's triangles in its reference frame (the vertices at t = 0),
their body and unit normal, and on the host their areas and owners. ``BodyFrames``: the reference axis and speed schedule of each body (kinematics.py) and its
frame now - x_world = R (x_ref - axis_point) + axis_point + offset, with its angular velocity
- computed on the device from the schedule, so that the triangles are never rewritten; its
material and its wall temperature. ``BodyLoads``: what the contacts load each body with,
summed per particle without atomics and flushed into per-body totals.
"""
import numpy as np
import taichi as ti

from ..engine import transfer
from ..engine.state import fit_rows
from ..setup.memory import triangle_slots
from .kinematics import MAX_SCHEDULE, triangle_arrays


class BodyTriangles:
    """``tri_a``, ``tri_b``, ``tri_c`` (m, reference frame), ``tri_body`` and ``tri_normal``
    (unit) per triangle on the device; ``area`` (m^2) and ``owner`` (body index) on the host
    (rigid bodies: they do not change); ``count`` triangles."""

    def __init__(self, tree, bodies, real):
        """Fields in ``tree`` (a FieldTree, finalised by the caller; then ``upload``)."""
        self._tris, owner = triangle_arrays(bodies)
        tris = self._tris
        self.count = len(tris)
        self.area = (0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0],
                                                   tris[:, 2] - tris[:, 0]), axis=1)
                     if len(tris) else np.zeros(0))
        self.owner = np.asarray(owner, np.int64)
        self.real = real
        # slots in buckets with a floor (setup/memory.py triangle_slots): scenes whose meshes
        # differ in their triangle count share their kernels; the loops run to ``count``
        self.slots = triangle_slots(self.count)
        t, nt = tree, self.slots
        self.tri_a = t.add("tri_a", real, nt, vector=True)
        self.tri_b = t.add("tri_b", real, nt, vector=True)
        self.tri_c = t.add("tri_c", real, nt, vector=True)
        self.tri_body = t.add("tri_body", ti.i32, nt)
        self.tri_normal = t.add("tri_normal", real, nt, vector=True)     # unit, reference frame

    def writes(self) -> list:
        """(field, host array) pairs of the vertices, owners and normals (engine/transfer.write:
        one copy kernel with the frames', where from_numpy compiles one per field)."""
        if not self.count:
            return []
        tris, npf = self._tris, np.float64 if self.real == ti.f64 else np.float32
        normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        # (the slots past ``count`` zero: no loop reaches them)
        return [(f, fit_rows(a, self.slots)) for f, a in (
            (self.tri_a, tris[:, 0].astype(npf)), (self.tri_b, tris[:, 1].astype(npf)),
            (self.tri_c, tris[:, 2].astype(npf)), (self.tri_body, self.owner.astype(np.int32)),
            (self.tri_normal, normal.astype(npf)))]


class BodyFrames:
    """The bodies' frames: per body ``axis_point`` and ``axis_direction`` (reference), its
    ``body_velocity`` m/s, ``body_material`` (table index), ``body_temperature`` K (negative:
    adiabatic, or no wall conduction), the speed schedule ``sched_*``, and now ``rotation``,
    ``offset`` m and ``angular_velocity`` rad/s; ``update_frames(time)`` (a kernel) and
    ``set_frames`` (a ti.func for a loop that is already serial) set them."""

    def __init__(self, tree, kinematics, real, material_index, wall_conduction: bool):
        """Fields in ``tree`` (a FieldTree, finalised by the caller; then ``upload``)."""
        self.kin = kinematics
        self.n_bodies = nb = len(kinematics.bodies)
        self.real = real
        t, nb = tree, max(nb, 1)
        self.sched_time = t.add("sched_time", real, (nb, MAX_SCHEDULE))
        self.sched_speed = t.add("sched_speed", real, (nb, MAX_SCHEDULE))
        self.sched_angle = t.add("sched_angle", real, (nb, MAX_SCHEDULE))
        self.sched_count = t.add("sched_count", ti.i32, nb)
        self.axis_point = t.add("axis_point", real, nb, vector=True)
        self.axis_direction = t.add("axis_direction", real, nb, vector=True)
        self.body_velocity = t.add("body_velocity", real, nb, vector=True)
        self.body_material = t.add("body_material", ti.i32, nb)
        # K of an isothermal body (water-cooled shell); negative = adiabatic or no conduction
        self.body_temperature = t.add("body_temperature", real, nb)
        self.rotation = ti.Matrix.field(3, 3, real)
        t._builder.dense(ti.i, nb).place(self.rotation)
        self.offset = t.add("offset", real, nb, vector=True)
        self.angular_velocity = t.add("angular_velocity", real, nb, vector=True)
        self._material_index = material_index
        self._wall_conduction = wall_conduction

    def _np_real(self):
        return np.float64 if self.real == ti.f64 else np.float32

    def writes(self) -> list:
        """(field, host array) pairs of the reference axes, velocities, materials,
        temperatures and schedules (engine/transfer.write)."""
        bodies, nb = self.kin.bodies, max(self.n_bodies, 1)
        ap, ad, bv = np.zeros((nb, 3)), np.zeros((nb, 3)), np.zeros((nb, 3))
        mat, temps = np.zeros(nb, np.int32), np.full(nb, -1.0)
        for k, b in enumerate(bodies):
            ap[k], ad[k], bv[k] = b.motion.axis_point, b.motion.axis_direction, b.motion.velocity
            mat[k] = self._material_index(b.material)
            if self._wall_conduction and b.temperature is not None:
                temps[k] = b.temperature
        npf = self._np_real()
        return [(self.axis_point, ap.astype(npf)), (self.axis_direction, ad.astype(npf)),
                (self.body_velocity, bv.astype(npf)), (self.body_material, mat),
                (self.body_temperature, temps.astype(npf))] + self.schedule_writes()

    def schedule_writes(self) -> list:
        """(field, host array) pairs of the speed schedules."""
        times, speeds, angles, counts = self.kin.schedule_arrays()
        npf = self._np_real()
        return [(self.sched_time, times.astype(npf)), (self.sched_speed, speeds.astype(npf)),
                (self.sched_angle, angles.astype(npf)),
                (self.sched_count, np.asarray(counts, np.int32))]

    def upload_schedules(self):
        """The speed schedules again (a changed shaft speed: Simulation.set_speed, resume)."""
        transfer.write(self.schedule_writes())

    def compile(self):
        """``update_frames(time)`` (a kernel; a few bodies: always serial) and ``set_frames``
        (its ti.func, for drivers.run_steps)."""
        f = self
        nb = self.n_bodies

        @ti.func
        def frame_of(b, time):
            """Rotation matrix, offset and angular velocity of body b at ``time``."""
            count = f.sched_count[b]
            row = 0
            for k in range(count):
                if time >= f.sched_time[b, k]:
                    row = k
            speed = f.sched_speed[b, row]
            angle = f.sched_angle[b, row] + speed * (time - f.sched_time[b, row])
            axis = f.axis_direction[b]
            c, s_ = ti.cos(angle), ti.sin(angle)
            k_ = ti.Matrix([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                            [-axis[1], axis[0], 0.0]])
            rot = ti.Matrix.identity(float, 3) + s_ * k_ + (1.0 - c) * (k_ @ k_)
            return rot, f.body_velocity[b] * time, speed * axis

        @ti.kernel
        def update_frames(time: self.real):
            ti.loop_config(serialize=True)
            for b in range(nb):
                rot, off, omega = frame_of(b, time)
                f.rotation[b] = rot
                f.offset[b] = off
                f.angular_velocity[b] = omega

        @ti.func
        def set_frames(time):
            """update_frames inside a loop that is already serial (drivers.run_steps)."""
            for b in range(nb):
                rot, off, omega = frame_of(b, time)
                f.rotation[b] = rot
                f.offset[b] = off
                f.angular_velocity[b] = omega

        self.update_frames = update_frames
        self.set_frames = set_frames


# particles per thread's partial sum in BodyLoads' flush (one atomic add per run of them)
FLUSH_CHUNK = 256


class BodyLoads:
    """What the contacts load the bodies with: per particle and body ``particle_load_force``
    N, ``particle_load_torque`` N m (about the axis point) and, with wall conduction,
    ``particle_load_heat`` W, summed over steps without atomics (two threads adding into one
    body's total fight over a cache line: that cost 60 % of the mesh contact time) and flushed
    into ``force_sum``, ``torque_sum``, ``heat_sum`` before particles are reordered and at
    each sample."""

    def __init__(self, tree, real, n_bodies: int, capacity: int, wall_conduction: bool):
        t, nb = tree, max(n_bodies, 1)
        self.n_bodies = n_bodies
        self.heat_sum = t.add("heat_sum", real, nb)
        self.force_sum = t.add("force_sum", real, nb, vector=True)
        self.torque_sum = t.add("torque_sum", real, nb, vector=True)
        self.particle_load_force = t.add("particle_load_force", real, (capacity, nb), vector=True)
        self.particle_load_torque = t.add("particle_load_torque", real, (capacity, nb),
                                          vector=True)
        self.particle_load_heat = (t.add("particle_load_heat", real, (capacity, nb))
                                   if wall_conduction else None)

    def make_flush(self):
        """A ti.func (n, serial_loops) adding the first ``n`` particles' loads into the
        bodies' sums and clearing them. Each thread sums a run of FLUSH_CHUNK particles and
        adds that once: one atomic add per particle into two bodies' sums made the threads
        fight over the sums' cache line (9 ns a particle-step on the seed's cooler slice,
        ~200 ns a particle at each rebuild; BENCHMARKS.md "The cooler slice against a plain
        bed")."""
        ld = self
        nb = self.n_bodies
        heat_loads = self.particle_load_heat is not None
        chunk = FLUSH_CHUNK

        @ti.func
        def flush_loads_body(n, serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for c in range((n + chunk - 1) // chunk):
                for b in ti.static(range(nb)):
                    force = ti.Vector([0.0, 0.0, 0.0])
                    torque = ti.Vector([0.0, 0.0, 0.0])
                    heat = 0.0
                    for i in range(c * chunk, ti.min(n, (c + 1) * chunk)):
                        force += ld.particle_load_force[i, b]
                        torque += ld.particle_load_torque[i, b]
                        ld.particle_load_force[i, b] = ti.Vector([0.0, 0.0, 0.0])
                        ld.particle_load_torque[i, b] = ti.Vector([0.0, 0.0, 0.0])
                        if ti.static(heat_loads):
                            heat += ld.particle_load_heat[i, b]
                            ld.particle_load_heat[i, b] = 0.0
                    ld.force_sum[b] += force
                    ld.torque_sum[b] += torque
                    if ti.static(heat_loads):
                        ld.heat_sum[b] += heat
        return flush_loads_body

    def take(self, steps: int):
        """Mean force (N), torque (N m) and heat flow (W) per body over ``steps`` steps
        (flushed already); resets the sums."""
        steps = max(steps, 1)
        sums = (self.force_sum, self.torque_sum, self.heat_sum)
        return tuple(x.astype(np.float64)[: self.n_bodies] / steps for x in transfer.take(sums))
