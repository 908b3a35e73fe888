"""The one way particles are created: the initial fill (run/simulation.py) and the factories
(process/factories.py) both hand ``Insertion.insert`` their particles as host arrays, and one
kernel writes them into the slots after the last one in use, clearing what a removed
particle left there (rows, contact history, body loads, what effects keep per particle)."""

import numpy as np
import taichi as ti

from ..effects.base import particle_load
from .state import SPHERE_INERTIA, Flag


class InsertColumn:
    """Columns of the f64 array Insertion.insert hands its kernel."""
    POSITION, VELOCITY, ANGULAR_VELOCITY = 0, 3, 6
    RADIUS, MASS, INVERSE_MASS, INVERSE_INERTIA, BIRTH_TIME = 9, 10, 11, 12, 13
    # then one column per value the effects give an inserted particle (inserted_values)
    SIZE = 14


class Insertion:
    """The insertion kernel of one engine (compiled on first use) and ``occupied``, what the
    slots in use hold for placing new particles among them."""

    def __init__(self, engine):
        self.e = engine
        self._insert = None
        self._occupied = None
        self._values = self._value_names = None    # (value_names: the effects' inserted values)

    def insert(self, count: int, arrays: dict) -> int:
        """Write the particles of ``arrays`` into slots ``count`` .. ``count + k - 1`` and flag
        a rebuild; returns the new count of slots in use. ``arrays``: position, velocity (n,3)
        m, m/s; radius m, mass kg, material (index), key (slot keys not in use) (n,);
        optional: angular_velocity (n,3) rad/s, fixed (n,) bool (held in place: no inverse
        mass), serial, origin (-1: the initial fill), birth_time s; and the values the
        enabled effects give an inserted particle (Effect.inserted_values: temperature K and
        inverse_thermal_mass 1/(J/K) with heat, moisture kg/kg when drying). The state must
        be at a whole step (between ``advance`` calls), or mid-step before a rebuild (drifted,
        forces pending: the ``before_rebuild`` hook) with velocities at t - dt/2 like the
        other particles'."""
        k = len(arrays["radius"])
        if k == 0:
            return count
        if count + k > self.e.model.particle_limit:
            raise RuntimeError("particle capacity exceeded")
        C = InsertColumn
        # two arrays (each ndarray argument costs a launch ~25 us: an insertion every few
        # dozen steps paid ~0.3 ms for thirteen); f64 columns, rounded to the device's
        # precision in the kernel (the temperature and moisture keep f64 where an f64
        # residual holds what f32 cannot, engine/precision.py)
        names = self.value_names()
        reals = np.zeros((k, C.SIZE + len(names)), np.float64)
        radius = np.asarray(arrays["radius"], np.float64)
        mass = np.asarray(arrays["mass"], np.float64)
        movable = ~np.asarray(arrays.get("fixed", np.zeros(k, bool)), bool)
        reals[:, C.POSITION:C.POSITION + 3] = arrays["position"]
        reals[:, C.VELOCITY:C.VELOCITY + 3] = np.asarray(arrays["velocity"]) * movable[:, None]
        if "angular_velocity" in arrays:
            reals[:, C.ANGULAR_VELOCITY:C.ANGULAR_VELOCITY + 3] = (
                np.asarray(arrays["angular_velocity"]) * movable[:, None])
        reals[:, C.RADIUS] = radius
        reals[:, C.MASS] = mass
        # (on the host in f64, then rounded: the same values whichever the precision)
        reals[:, C.INVERSE_MASS] = np.where(movable, 1.0 / mass, 0.0)
        reals[:, C.INVERSE_INERTIA] = np.where(
            movable, 1.0 / (SPHERE_INERTIA * mass * radius ** 2), 0.0)
        if "birth_time" in arrays:
            reals[:, C.BIRTH_TIME] = arrays["birth_time"]
        for column, name in enumerate(names, C.SIZE):
            if name in arrays:
                reals[:, column] = arrays[name]
        key = np.asarray(arrays["key"], np.int64)
        serial = np.asarray(arrays.get("serial", key), np.int64)
        origin = np.asarray(arrays.get("origin", np.full(k, -1)), np.int64)
        ints = np.stack([np.asarray(arrays["material"], np.int64), key, serial, origin],
                        axis=1).astype(np.int32)
        if self._insert is None:
            self._insert = self.e.serial_switch(self._compile_insert())
        self._insert(count, k, reals, ints)
        return count + k

    def value_names(self) -> list[str]:
        """The names of the values the enabled effects give an inserted particle, in the
        order of their columns after InsertColumn.SIZE."""
        if self._value_names is None:
            self._values = [v for effect in self.e.model.effect_list
                            for v in effect.inserted_values(self.e.context)]
            self._value_names = [name for name, _ in self._values]
        return self._value_names

    def occupied(self, count: int) -> dict:
        """What the slots in use hold, for placing new particles among them: ``alive`` (n,)
        bool, ``position`` (n, 3) m, ``radius`` (n,) m, ``particle_id`` (n,) int, in slot
        order. One serial launch (four to_numpy calls would be four parallel launches, each
        copying the whole capacity)."""
        table = np.zeros((count, 6), np.float64)
        if count:
            if self._occupied is None:
                self._occupied = self.e.serial_switch(self._compile_occupied())
            self._occupied(count, table)
        return {"alive": table[:, 4] != 0.0, "position": table[:, :3], "radius": table[:, 3],
                "particle_id": table[:, 5].astype(np.int64)}

    def _compile_occupied(self):
        s = self.e.state

        @ti.kernel
        def occupied(n: ti.i32, out: ti.types.ndarray(), serial_loops: ti.template()):
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                for k in ti.static(range(3)):
                    out[i, k] = ti.cast(s.position[i][k], ti.f64)
                out[i, 3] = ti.cast(s.radius[i], ti.f64)
                out[i, 4] = ti.cast(s.alive[i], ti.f64)
                out[i, 5] = ti.cast(s.particle_id[i], ti.f64)

        return occupied

    def _compile_insert(self):
        e = self.e
        s = e.state
        # what the effects give a particle in free flight (Effect.inserted_func: gravity, a
        # body force): its first half step's acceleration
        Load = particle_load(e.model.real)
        starts = tuple(f for f in (effect.inserted_func(e.context) for effect in e.model.effect_list)
                       if f is not None)
        process = s.process
        n_walls = s.n_walls
        wall_fields = [getattr(s, n) for n in s.wall_fields]
        mesh = e.mesh
        has_mesh = mesh is not None
        n_bodies = mesh.n_bodies if has_mesh else 0
        heat_loads = has_mesh and mesh.loads.particle_load_heat is not None
        flags = e.flags
        real = e.model.real
        self.value_names()
        # each effect's values for the particle (its temperature, its moisture), f64 columns
        writers = tuple(write for _, write in self._values)
        release = e.holding.release          # (engine/holding.py; nothing without it)
        C = InsertColumn
        # what effects keep per particle beyond what is inserted (a coarse-grained particle's
        # wall-contact clock): zero, not what a removed particle left in the slot; an effect
        # that gives inserted values sets all its particle fields
        fresh = {}
        for effect in e.model.effect_list:
            if not effect.inserted_values(e.context):
                fresh.update({n: v for n, (v, _) in effect.particle_fields.items()})
        fresh_scalars = [getattr(s, n) for n, vec in fresh.items() if not vec]
        fresh_vectors = [getattr(s, n) for n, vec in fresh.items() if vec]
        split = e.model.split_positions

        @ti.kernel
        def insert(start: ti.i32, k: ti.i32, reals: ti.types.ndarray(dtype=ti.f64, ndim=2),
                   ints: ti.types.ndarray(dtype=ti.i32, ndim=2), serial_loops: ti.template()):
            """Particles ``start`` .. ``start + k - 1`` from the rows of ``reals`` (columns:
            InsertColumn) and ``ints`` (material, key, serial, origin)."""
            ti.loop_config(serialize=serial_loops)
            for q in range(k):
                i = start + q
                x = ti.Vector([ti.cast(reals[q, C.POSITION + a], real) for a in ti.static(range(3))])
                s.position[i] = x
                s.reference_position[i] = x
                if ti.static(split):
                    # (what f32 cannot hold of an inserted position: below its spacing, dropped)
                    s.position_residual[i] = ti.Vector([0.0, 0.0, 0.0])
                s.velocity[i] = ti.Vector([ti.cast(reals[q, C.VELOCITY + a], real)
                                    for a in ti.static(range(3))])
                s.angular_velocity[i] = ti.Vector([ti.cast(reals[q, C.ANGULAR_VELOCITY + a], real)
                                    for a in ti.static(range(3))])
                s.radius[i] = ti.cast(reals[q, C.RADIUS], real)
                s.mass[i] = ti.cast(reals[q, C.MASS], real)
                s.inverse_mass[i] = ti.cast(reals[q, C.INVERSE_MASS], real)
                s.inverse_inertia[i] = ti.cast(reals[q, C.INVERSE_INERTIA], real)
                s.material[i] = ints[q, 0]
                s.particle_id[i] = ints[q, 1]
                s.alive[i] = 1
                # inserted clear of every contact: free flight is the first step's acceleration
                # (the initial fill's are computed by Engine.start); after the particle's own
                # values, which an effect may read (its material, its mass)
                load = Load(acceleration=ti.Vector([0.0, 0.0, 0.0]), heat=0.0, conductance=0.0,
                            touching=0)
                for start_of in ti.static(starts):
                    load = start_of(i, load)
                s.acceleration[i] = load.acceleration
                s.angular_acceleration[i] = ti.Vector([0.0, 0.0, 0.0])
                release(i)            # moves until the rebuild this insertion flags judges it
                if ti.static(process):
                    s.serial[i] = ints[q, 2]
                    s.origin[i] = ints[q, 3]
                    s.birth_time[i] = ti.cast(reals[q, C.BIRTH_TIME], real)
                for v in ti.static(range(len(writers))):
                    writers[v](i, reals[q, C.SIZE + v])
                # the slot may hold what a removed particle left: no rows, no history, no loads
                s.row_owned[i] = 0
                s.row_count[i] = 0
                for f in ti.static(fresh_scalars):
                    f[i] = 0
                for f in ti.static(fresh_vectors):
                    f[i] = ti.Vector([0.0, 0.0, 0.0])
                # (loops, not unrolled: one copy of the body whatever the number of walls)
                for f in ti.static(wall_fields):
                    for w in range(n_walls):
                        f[i, w] = ti.Vector([0.0, 0.0, 0.0])
                if ti.static(has_mesh):
                    mesh.mesh_count[i] = 0
                    for b in range(n_bodies):
                        mesh.loads.particle_load_force[i, b] = ti.Vector([0.0, 0.0, 0.0])
                        mesh.loads.particle_load_torque[i, b] = ti.Vector([0.0, 0.0, 0.0])
                        if ti.static(heat_loads):
                            mesh.loads.particle_load_heat[i, b] = 0.0
            flags[Flag.REBUILD] = 1

        return insert
